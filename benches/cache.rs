//! The file cache's benefit (TF5200 File Caching): a program calling a cycle 100,000 times,
//! with and without `#CACHE LOAD` first, at `fs_latency_us` 0 and 200, in virtual time. Criterion
//! measures the wall time of a whole run (throughput = calls, so it prints calls/s); each case
//! also prints once its wall time per call, file-system opens and simulated machining time.
//!
//! The four main cases call a cycle that only returns (`M17`), passing one parameter: their
//! time per call is the call overhead (call line, cache or file lookup, frame, return). The
//! `_body` case adds one parameter computation to the cycle, for comparison.
//!
//! `cargo bench --bench cache`

use std::path::Path;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use ncchannel::machine::{Machine, Op, Reply, StopWhen};
use ncchannel::report::event::EventLog;
use ncchannel::runtime::{Clock, RunEnd, Runtime, Tick};

const CALLS: u64 = 100_000;

/// Parameter lists (caching on) and programs in `dir`.
fn write_case(dir: &Path, cached: bool, fs_latency_us: u64, body: &str) {
    std::fs::create_dir_all(dir.join("params")).unwrap();
    std::fs::create_dir_all(dir.join("nc")).unwrap();
    std::fs::write(
        dir.join("params/startup.lis"),
        "kanal_anzahl 1\nsda_mds[0] channel1.lis\npfad[0].prg[0] ../nc\npfad[0].typ[0] 0x03\n\
         pfad[0].prioritaet[0] 0\n\
         configuration.channel[0].decoder.function FCT_USE_CACHED_FILES\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("params/channel1.lis"),
        "streaming_prog_file streaming.nc\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("params/runtime.toml"),
        format!("fs_latency_us = {fs_latency_us}\n"),
    )
    .unwrap();
    std::fs::write(dir.join("nc/c.cyc"), format!("{body}M17\n")).unwrap();
    let mut main = String::with_capacity(32 * CALLS as usize);
    main.push_str("P2=0\n");
    if cached {
        main.push_str("#CACHE LOAD[FILE=c.cyc]\n");
    }
    for _ in 0..CALLS {
        main.push_str("L CYCLE [NAME=c.cyc @P1=1]\n");
    }
    main.push_str("M30\n");
    std::fs::write(dir.join("nc/main.nc"), main).unwrap();
}

/// A machine with main.nc started, ready to run.
fn machine(dir: &Path) -> (Machine, Duration) {
    let config = ncchannel::params::load(&dir.join("params/startup.lis")).unwrap();
    let channels = ncchannel::channels(&config, false, &ncchannel::Loader::start()).unwrap();
    let period = Duration::from_micros(config.runtime.cycle_period_us);
    let mut m = Machine::new(channels, EventLog::disabled(), StopWhen::ProgramsFinished);
    let t0 = Tick::first(period, ncchannel::runtime::Clock::Virtual);
    assert_eq!(
        m.apply(&t0, 1, Op::Start("main.nc".into())),
        Reply::Command(Ok(()))
    );
    (m, period)
}

struct Outcome {
    opens: u64,
    hits: u64,
    sim: Duration,
    wall: Duration,
}

fn run(m: Machine, period: Duration) -> Outcome {
    let (mut rt, _tx) = Runtime::new(m, period, Clock::Virtual);
    let t = Instant::now();
    let s = rt.run(Some(100_000_000));
    let wall = t.elapsed();
    assert_eq!(s.end, RunEnd::Stopped, "the program must end");
    let sim = rt.time();
    let (m, _) = rt.into_inner();
    let c = &m.channels()[0];
    assert!(c.report().errors.is_empty(), "{:?}", c.report().errors);
    Outcome {
        opens: c.report().store.opens,
        hits: c.report().cache.hits,
        sim,
        wall,
    }
}

fn cache(c: &mut Criterion) {
    let mut g = c.benchmark_group("cycle_calls_100k");
    g.sample_size(10);
    g.throughput(Throughput::Elements(CALLS));
    let cases = [
        (false, 0u64, ""),
        (true, 0, ""),
        (false, 200, ""),
        (true, 200, ""),
        (true, 0, "P2=P2+@P1\n"),
    ];
    {
        for (cached, fs_latency_us, body) in cases {
            let name = format!(
                "{}_fs{fs_latency_us}us{}",
                if cached { "cached" } else { "uncached" },
                if body.is_empty() { "" } else { "_body" }
            );
            // CACHE_BENCH_ONLY=cached_fs0us runs one case alone (for a profiler).
            if std::env::var("CACHE_BENCH_ONLY").is_ok_and(|o| o != name) {
                continue;
            }
            let dir = tempfile::tempdir().unwrap();
            write_case(dir.path(), cached, fs_latency_us, body);
            let (m, period) = machine(dir.path());
            let o = run(m, period);
            eprintln!(
                "{name}: {} file-system opens, {} cache hits, simulated {:.3} s, wall {:.1} ms = {:.0} ns per call",
                o.opens,
                o.hits,
                o.sim.as_secs_f64(),
                o.wall.as_secs_f64() * 1e3,
                o.wall.as_nanos() as f64 / CALLS as f64
            );
            g.bench_function(&name, |b| {
                b.iter_batched(
                    || machine(dir.path()),
                    |(m, period)| run(m, period),
                    BatchSize::PerIteration,
                )
            });
        }
    }
    g.finish();
}

criterion_group!(benches, cache);
criterion_main!(benches);
