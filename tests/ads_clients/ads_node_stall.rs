//! A runtime stall longer than Node `ads-client`'s default request timeout (2 s) while the
//! unmodified client streams with a 0x708 retry loop (tests/node/stream_through_a_stall.js):
//! no request times out, every line is executed exactly once and in order. The stall is one
//! tick that overruns by 2.5 s (the shape of a tick doing work that grows with its input),
//! made by a [`Cycle`] around the real machine that sleeps in one `step` once the channel
//! has executed 1,000 blocks. Ignored by default (needs Node and tests/node/node_modules):
//!
//! `npm ci --prefix tests/node && cargo test --test ads_clients -- --ignored ads_node_stall`

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use ncchannel::machine::{Machine, Request, StopWhen};
use ncchannel::runtime::{Clock, Cycle, Flow, Runtime, Tick};

use crate::support as common;

/// Longer than ads-client's default request timeout (2 s).
const STALL: Duration = Duration::from_millis(2500);
/// Blocks executed before the stall, so the client is mid-stream when it comes.
const STALL_AFTER_BLOCKS: u64 = 1000;

/// The real machine, with one tick that overruns by [`STALL`].
struct StallOnce {
    machine: Machine,
    /// How long the stalled tick took, once it has run.
    stalled: Arc<Mutex<Option<Duration>>>,
}

impl Cycle for StallOnce {
    type Request = Request;

    fn serve(&mut self, req: Request, tick: &Tick) {
        self.machine.serve(req, tick);
    }

    fn step(&mut self, tick: &Tick) -> Flow {
        let mut stalled = self.stalled.lock().unwrap();
        if stalled.is_none()
            && self.machine.channels()[0].report().stats.blocks >= STALL_AFTER_BLOCKS
        {
            let began = Instant::now();
            std::thread::sleep(STALL);
            *stalled = Some(began.elapsed());
        }
        drop(stalled);
        self.machine.step(tick)
    }
}

#[test]
#[ignore = "needs Node and tests/node/node_modules: npm ci --prefix tests/node"]
fn ads_node_stall_longer_than_the_client_timeout_answers_busy_and_loses_no_line() {
    let node = std::env::var("NCCHANNEL_NODE").unwrap_or_else(|_| "node".into());
    let rig = common::Rig::new();
    let lines = common::streamed_5000_lines();
    let file = rig.dir.path().join("prog.nc");
    std::fs::write(&file, lines.join("\n") + "\n").unwrap();

    let (mut machine, period, log) = rig.machine();
    machine.set_stop_when(StopWhen::Never);
    let stalled = Arc::new(Mutex::new(None));
    let cycle = StallOnce {
        machine,
        stalled: Arc::clone(&stalled),
    };
    let (mut rt, tx) = Runtime::new(cycle, period, Clock::RealTime);
    let stop = rt.stop_handle();
    let runtime = std::thread::spawn(move || {
        rt.run(None);
        rt.into_inner().0.machine
    });
    // The server as `serve` builds it, with the default reply timeout.
    let backend = ncchannel::machine::remote::ChannelBackend::new(tx, 1);
    let config = ncchannel::ads::ServerConfig {
        bind: "127.0.0.1:0".parse().unwrap(),
        ..Default::default()
    };
    let server = ncchannel::ads::spawn(config, Arc::new(backend)).unwrap();

    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/node/stream_through_a_stall.js"
    );
    let out = std::process::Command::new(&node)
        .arg(script)
        .arg(&file)
        .env("NCCHANNEL_ADS_ADDR", server.local_addr().to_string())
        .output()
        .unwrap_or_else(|e| panic!("{node} runs: {e}"));
    server.shutdown();
    stop.stop();
    let mut machine = runtime.join().unwrap();
    machine.finish_log().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let seen: serde_json::Value =
        serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim()).unwrap();
    let stall = stalled.lock().unwrap().expect("the runtime stalled");
    println!(
        "STALL {:.2} s under ads-client (2 s timeout): {seen}",
        stall.as_secs_f64()
    );
    assert!(stall >= STALL, "{stall:?}");
    assert!(
        seen["slow_busy"].as_u64().unwrap() > 0,
        "writes during the stall were answered 0x708: {seen}"
    );
    assert!(
        seen["max_answer_ms"].as_u64().unwrap() < 2000,
        "every write answered within the client's timeout: {seen}"
    );
    let events: Vec<serde_json::Value> = log
        .text()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(common::block_texts(&events), lines);
}
