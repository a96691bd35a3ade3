//! The one support module of the test binaries (each `tests/<capability>/main.rs` includes it).
//! Here: a channel rig — parameter lists and programs in a temporary folder, a machine run in
//! virtual time, the event log captured as JSON values. In submodules: an ADS server and raw
//! client (`ads`), spawned-process helpers for the abuse tests (`abuse`), motion checks and
//! generators, and the synthetic streaming load the stream bench shares.
#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use ncchannel::channel::{Channel, Finish};
use ncchannel::machine::{Machine, Op, Reply, StopWhen};
use ncchannel::report::event::EventLog;
use ncchannel::runtime::{Clock, Runtime, Tick};
use ncchannel::Feeder;
use serde_json::Value;

pub struct Rig {
    pub dir: tempfile::TempDir,
}

#[derive(Clone, Default)]
struct Shared(Arc<Mutex<Vec<u8>>>);

impl Write for Shared {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

pub struct RunResult {
    pub log: String,
    pub events: Vec<Value>,
    pub finish: Option<Finish>,
    pub machine: Machine,
    pub ticks: u64,
    /// The runtime's own figures of the run (virtual time).
    pub stats: ncchannel::vocab::stats::CycleStats,
}

/// Events of one kind (`ev`), in order.
pub fn of<'a>(events: &'a [Value], ev: &str) -> Vec<&'a Value> {
    events.iter().filter(|e| e["ev"] == ev).collect()
}

/// Texts of the `block` events, in order.
pub fn block_texts(events: &[Value]) -> Vec<String> {
    of(events, "block")
        .iter()
        .map(|e| e["text"].as_str().unwrap().to_string())
        .collect()
}

/// The events a channel driven by hand has collected, as JSON values.
pub fn channel_events(c: &mut ncchannel::channel::Channel) -> Vec<Value> {
    c.events_mut()
        .events()
        .iter()
        .map(|e| serde_json::to_value(e).unwrap())
        .collect()
}

impl RunResult {
    pub fn of(&self, ev: &str) -> Vec<&Value> {
        of(&self.events, ev)
    }
    /// Texts of the `block` events, in order.
    pub fn block_texts(&self) -> Vec<String> {
        block_texts(&self.events)
    }
    pub fn error_codes(&self) -> Vec<u64> {
        self.of("error")
            .iter()
            .map(|e| e["code"].as_u64().unwrap())
            .collect()
    }
    /// Where channel 1's `axis` stands at the end, mm.
    pub fn position(&self, axis: char) -> f64 {
        self.machine.channels()[0]
            .status()
            .positions
            .into_iter()
            .find(|(a, _)| *a == axis)
            .map(|(_, v)| v)
            .unwrap()
    }
}

/// The M functions the shipped and the tests' programs use (tool change, coolant, laser, the
/// printer's M200/M201), defined as MOS: handed to the units and acknowledged without a wait,
/// so the tests of motion and streaming see the program's pace unchanged.
pub const RIG_M_FUNCTIONS: &str = "m_synch[6] MOS\nm_synch[7] MOS\nm_synch[8] MOS\n\
    m_synch[9] MOS\nm_synch[10] MOS\nm_synch[11] MOS\nm_synch[200] MOS\nm_synch[201] MOS\n";

impl Rig {
    /// One channel, streaming program `streaming.nc`, programs in `nc/`, caching on (2 × 200 B).
    pub fn new() -> Rig {
        Self::with_runtime("")
    }

    pub fn with_runtime(runtime_toml: &str) -> Rig {
        Self::with_cache(Some((2, 200)), runtime_toml)
    }

    /// Like `with_runtime`, with other cache limits: `Some((max_cache_number,
    /// max_cache_size))`, or `None` for file caching off.
    pub fn with_cache(cache: Option<(u32, u32)>, runtime_toml: &str) -> Rig {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("params")).unwrap();
        std::fs::create_dir_all(dir.path().join("nc")).unwrap();
        let mut startup = String::from(
            "kanal_anzahl 1\nsda_mds[0] channel1.lis\npfad[0].prg[0] ../nc\npfad[0].typ[0] 0x03\npfad[0].prioritaet[0] 0\n",
        );
        if let Some((files, bytes)) = cache {
            startup.push_str(&format!(
                "configuration.channel[0].decoder.function FCT_USE_CACHED_FILES\n\
                 configuration.channel[0].decoder.max_cache_number {files}\n\
                 configuration.channel[0].decoder.max_cache_size {bytes}\n"
            ));
        }
        std::fs::write(dir.path().join("params/startup.lis"), startup).unwrap();
        std::fs::write(
            dir.path().join("params/channel1.lis"),
            format!("streaming_prog_file streaming.nc\n{RIG_M_FUNCTIONS}"),
        )
        .unwrap();
        if !runtime_toml.is_empty() {
            std::fs::write(dir.path().join("params/runtime.toml"), runtime_toml).unwrap();
        }
        Rig { dir }
    }

    pub fn startup(&self) -> PathBuf {
        self.dir.path().join("params/startup.lis")
    }

    pub fn nc(&self) -> PathBuf {
        self.dir.path().join("nc")
    }

    /// `serve --bind 127.0.0.1:0 --start long.nc --events <events>` on this rig's lists (see
    /// [`Rig::long_program`]), standard output discarded, standard error piped.
    pub fn serve_long(&self, events: &std::path::Path) -> std::process::Command {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_ncchannel"));
        cmd.args([
            "serve",
            "--bind",
            "127.0.0.1:0",
            "--start",
            "long.nc",
            "--params",
        ])
        .arg(self.startup())
        .arg("--events")
        .arg(events)
        .stderr(std::process::Stdio::piped())
        .stdout(std::process::Stdio::null());
        cmd
    }

    /// `long.nc`: a program that runs for minutes, 20,000 short moves back and forth (one
    /// block event each), for tests that stop or kill a running channel.
    pub fn long_program(&self) -> PathBuf {
        let mut text = String::from("N1 G01 F30000\n");
        for i in 0..20_000 {
            let x = if i % 2 == 0 { 0.2 } else { 0.0 };
            text.push_str(&format!("N{} X{x:.3}\n", i + 2));
        }
        text.push_str("M30\n");
        self.program("long.nc", &text)
    }

    pub fn program(&self, name: &str, text: &str) -> PathBuf {
        let p = self.nc().join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    pub fn machine(&self) -> (Machine, Duration, Shared2) {
        let config = ncchannel::params::load(&self.startup()).unwrap();
        let channels = ncchannel::channels(&config, true, &ncchannel::Loader::start()).unwrap();
        let shared = Shared::default();
        let log = EventLog::to_writer(Box::new(shared.clone()));
        let period = Duration::from_micros(config.runtime.cycle_period_us);
        (
            Machine::new(channels, log, StopWhen::ProgramsFinished),
            period,
            Shared2(shared),
        )
    }

    /// Channel 1 of the rig on its own (its events kept in its buffer), and the cycle time.
    pub fn channel(&self) -> (Channel, Duration) {
        let config = ncchannel::params::load(&self.startup()).unwrap();
        let mut channels = ncchannel::channels(&config, true, &ncchannel::Loader::start()).unwrap();
        let period = Duration::from_micros(config.runtime.cycle_period_us);
        (channels.remove(0), period)
    }

    /// Start `program` on channel 1, feed `stream` (if any) with the built-in feeder, run in
    /// virtual time until the program finishes or `max_ticks`.
    pub fn run(&self, program: &str, stream: Option<Feeder>, max_ticks: u64) -> RunResult {
        self.run_with(program, stream, max_ticks, |_| {})
    }

    pub fn run_with(
        &self,
        program: &str,
        stream: Option<Feeder>,
        max_ticks: u64,
        prepare: impl FnOnce(&mut Machine),
    ) -> RunResult {
        let (mut machine, period, shared) = self.machine();
        if let Some(f) = stream {
            machine.attach_feeder(1, f);
        }
        prepare(&mut machine);
        let t0 = tick0(period);
        // A refused start raises its error, which the run then shows.
        let _ = machine.apply(&t0, 1, Op::Start(program.to_string()));
        let (mut rt, _tx) = Runtime::new(machine, period, Clock::Virtual);
        rt.run(Some(max_ticks));
        let ticks = rt.ticks();
        let (mut machine, stats) = rt.into_inner();
        machine.finish_log().unwrap();
        let finish = machine.finishes()[0];
        let log = String::from_utf8(shared.0 .0.lock().unwrap().clone()).unwrap();
        let events = log
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        RunResult {
            log,
            events,
            finish,
            machine,
            ticks,
            stats,
        }
    }
}

pub struct Shared2(Shared);

impl Shared2 {
    pub fn text(&self) -> String {
        String::from_utf8(self.0 .0.lock().unwrap().clone()).unwrap()
    }
}

pub fn tick0(period: Duration) -> Tick {
    Tick::first(period, ncchannel::runtime::Clock::Virtual)
}

pub fn feeder(text: &str, packet: usize, every: u64) -> Feeder {
    Feeder::new(text.as_bytes().to_vec(), packet, every, false).unwrap()
}

pub fn crlf(text: &str) -> Vec<u8> {
    text.replace('\n', "\r\n").into_bytes()
}

pub fn path_str(p: &Path) -> String {
    p.display().to_string()
}

/// The channels in real time behind a real ADS server on a loopback port, in this process.
pub struct Served {
    pub server: ncchannel::ads::ServerHandle,
    stop: ncchannel::runtime::StopHandle,
    thread: std::thread::JoinHandle<Machine>,
    log: Shared2,
}

impl Served {
    pub fn start(rig: &Rig) -> Served {
        let (machine, period, log) = rig.machine();
        let mut machine = machine;
        machine.set_stop_when(StopWhen::Never);
        let n = machine.channels().len() as u16;
        let (mut rt, tx) = Runtime::new(machine, period, Clock::RealTime);
        let stop = rt.stop_handle();
        let thread = std::thread::spawn(move || {
            rt.run(None);
            rt.into_inner().0
        });
        let backend = ncchannel::machine::remote::ChannelBackend::new(tx, n);
        let config = ncchannel::ads::ServerConfig {
            bind: "127.0.0.1:0".parse().unwrap(),
            ..Default::default()
        };
        let server = ncchannel::ads::spawn(config, Arc::new(backend)).unwrap();
        Served {
            server,
            stop,
            thread,
            log,
        }
    }

    /// Wait until the event log holds `n` block events (the channel executed that many
    /// blocks), at most `deadline`: a test waits for the work, not for a time it guessed.
    pub fn wait_blocks(&self, n: usize, deadline: std::time::Duration) {
        let t0 = std::time::Instant::now();
        loop {
            let blocks = self
                .log
                .text()
                .lines()
                .filter(|l| l.contains("\"ev\":\"block\""))
                .count();
            if blocks >= n || t0.elapsed() > deadline {
                return;
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
    }

    /// Stop the runtime and return the event log as JSON values.
    pub fn finish(self) -> (Machine, Vec<Value>) {
        self.server.shutdown();
        self.stop.stop();
        let mut m = self.thread.join().unwrap();
        m.finish_log().unwrap();
        let events = self
            .log
            .text()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        (m, events)
    }
}

/// The 5,000-line program the ADS end-to-end tests stream: mostly parameter blocks with a
/// short move every 25 lines, so the channel runs and moves, yet 5,000 lines take seconds,
/// not minutes, of real time. Ends with M30.
pub fn streamed_5000_lines() -> Vec<String> {
    let mut lines: Vec<String> = vec!["N1 G01 F30000".into()];
    lines.extend((2..5000).map(|i| {
        if i % 25 == 0 {
            format!(
                "N{i} X{:.3} Y{:.3}",
                (i % 50) as f64 * 0.02,
                (i % 31) as f64 * 0.02
            )
        } else {
            format!("N{i} P{}={i}", 1 + i % 20)
        }
    }));
    lines.push("M30".into());
    lines
}

/// Run an outside client, `program script args…`, against `served` (its address in
/// `NCCHANNEL_ADS_ADDR`); it must succeed and print one JSON line. Returns that line and the
/// run's events.
pub fn run_client(
    served: Served,
    program: &str,
    script: &str,
    args: &[&Path],
) -> (Value, Vec<Value>) {
    let out = std::process::Command::new(program)
        .arg(script)
        .args(args)
        .env("NCCHANNEL_ADS_ADDR", served.server.local_addr().to_string())
        .output()
        .unwrap_or_else(|e| panic!("{program} runs: {e}"));
    let (_, events) = served.finish();
    // The exit status too: a client killed by a signal (a crash inside its C library)
    // leaves no message on stderr.
    assert!(
        out.status.success(),
        "{} ({}; stdout: {})",
        String::from_utf8_lossy(&out.stderr),
        out.status,
        String::from_utf8_lossy(&out.stdout)
    );
    let seen = serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim()).unwrap();
    (seen, events)
}

pub mod abuse;
pub mod ads;
pub mod limit_check;
pub mod queued;
pub mod random_path;
pub mod streaming_load;

/// The reply to a stream write the channel took.
pub const WRITTEN: Reply = Reply::Stream(Ok(()));

/// Start `program` through the channel's door; a refusal fails the test.
pub fn start(c: &mut Channel, t: &Tick, program: &str) {
    let r = c.apply(t, Op::Start(program.to_string()));
    assert_eq!(r, Reply::Command(Ok(())), "start {program}");
}

/// Write stream data through the channel's door, as a client does.
pub fn write(c: &mut Channel, t: &Tick, data: &[u8]) -> Reply {
    c.apply(t, Op::WriteStream(data.into()))
}
