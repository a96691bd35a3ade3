//! Channel throughput in virtual time, events off: streamed non-moving blocks, streamed short
//! moves, and a file program with `$IF`/`$SWITCH` every 10 lines. Each case also prints the
//! tick work percentiles of one run (the runtime measures every tick).

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use ncchannel::channel::Finish;
use ncchannel::machine::{Machine, Op, Reply, StopWhen};
use ncchannel::report::event::EventLog;
use ncchannel::runtime::{Clock, Runtime, Tick};
use ncchannel::Feeder;

const BLOCKS: usize = 1_000_000;

struct Setup {
    dir: tempfile::TempDir,
}

impl Setup {
    fn new() -> Setup {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("p")).unwrap();
        std::fs::create_dir_all(dir.path().join("nc")).unwrap();
        std::fs::write(
            dir.path().join("p/startup.lis"),
            "kanal_anzahl 1\nsda_mds[0] ch.lis\npfad[0].prg[0] ../nc\npfad[0].typ[0] 0x03\n",
        )
        .unwrap();
        std::fs::write(
            dir.path().join("p/ch.lis"),
            "streaming_prog_file streaming.nc\nm_synch[8] NO_SYNCH\n",
        )
        .unwrap();
        Setup { dir }
    }

    /// Run `program` (fed from `stream` if given) to its end; returns the tick work p99 in µs.
    fn run(&self, program: &str, stream: Option<&[u8]>) -> (f64, f64, u64) {
        let config = ncchannel::params::load(&self.dir.path().join("p/startup.lis")).unwrap();
        let channels = ncchannel::channels(&config, false, &ncchannel::Loader::start()).unwrap();
        let period = Duration::from_micros(config.runtime.cycle_period_us);
        let mut m = Machine::new(channels, EventLog::disabled(), StopWhen::ProgramsFinished);
        if let Some(s) = stream {
            m.attach_feeder(1, Feeder::new(s.to_vec(), 992, 1, false).unwrap());
        }
        let t0 = Tick::first(period, ncchannel::runtime::Clock::Virtual);
        assert_eq!(
            m.apply(&t0, 1, Op::Start(program.to_string())),
            Reply::Command(Ok(()))
        );
        let (mut rt, _tx) = Runtime::new(m, period, Clock::Virtual);
        rt.run(None);
        let (m, stats) = rt.into_inner();
        assert_eq!(m.finishes()[0], Some(Finish::Ended));
        (
            stats.work.quantile_us(0.5),
            stats.work.quantile_us(0.99),
            m.channels()[0].report().stats.blocks,
        )
    }
}

fn non_moving() -> Vec<u8> {
    let mut s = String::from("P1=0\r\n");
    for i in 0..BLOCKS {
        if i % 4 == 3 {
            s.push_str("M8\r\n");
        } else {
            s.push_str(&format!("N{i} P{}=[P1+{}]\r\n", 2 + i % 20, i % 7));
        }
    }
    s.push_str("M30\r\n");
    s.into_bytes()
}

fn short_moves() -> Vec<u8> {
    let mut s = String::from("G01 F6000\r\n");
    for i in 0..BLOCKS {
        s.push_str(&format!(
            "N{i} X{:.3} Y{:.3}\r\n",
            (i % 100) as f64 * 0.001,
            (i % 37) as f64 * 0.001
        ));
    }
    s.push_str("M30\r\n");
    s.into_bytes()
}

fn branchy() -> String {
    let mut s = String::from("P1=0\nP2=0\n");
    let mut i = 0;
    while i < BLOCKS {
        if i % 20 == 0 {
            s.push_str("$IF P1 < 5\nP2=P2+1\n$ELSE\nP2=P2-1\n$ENDIF\n");
            i += 5;
        } else if i % 20 == 10 {
            s.push_str("$SWITCH P2 MOD 3\n$CASE 0\nP3=1\n$BREAK\n$CASE 1\nP3=2\n$BREAK\n$DEFAULT\nP3=3\n$ENDSWITCH\n");
            i += 10;
        } else {
            s.push_str(&format!("N{i} P1=[P1+1] MOD 10\n"));
            i += 1;
        }
    }
    s.push_str("M30\n");
    s
}

fn bench(c: &mut Criterion) {
    let setup = Setup::new();
    let mut g = c.benchmark_group("channel_virtual_time");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(20));
    g.throughput(Throughput::Elements(BLOCKS as u64));

    let nm = non_moving();
    let (p50, p99, blocks) = setup.run("streaming.nc", Some(&nm));
    eprintln!("streamed non-moving: {blocks} blocks; tick work p50 {p50:.2} µs p99 {p99:.2} µs");
    g.bench_function("streamed_non_moving_1M", |b| {
        b.iter(|| setup.run("streaming.nc", Some(&nm)))
    });

    let mv = short_moves();
    let (p50, p99, blocks) = setup.run("streaming.nc", Some(&mv));
    eprintln!("streamed short moves: {blocks} blocks; tick work p50 {p50:.2} µs p99 {p99:.2} µs");
    g.bench_function("streamed_short_moves_1M", |b| {
        b.iter(|| setup.run("streaming.nc", Some(&mv)))
    });

    std::fs::write(setup.dir.path().join("nc/branchy.nc"), branchy()).unwrap();
    let (p50, p99, _) = setup.run("branchy.nc", None);
    eprintln!("file with $IF/$SWITCH every 10 lines: tick work p50 {p50:.2} µs p99 {p99:.2} µs");
    g.bench_function("file_if_switch_1M_lines", |b| {
        b.iter(|| setup.run("branchy.nc", None))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
