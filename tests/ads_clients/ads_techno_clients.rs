//! Real clients as the PLC of a channel's technology units (port 851): M25 is MVS_SVS in the
//! channel's table (tests/ads/techno_rig.rs); the client sets `head.plc_present_w`, starts the
//! program, sees the unit asking (a notification on `techno_unit_std_sync`), reads it by name,
//! holds the acknowledgement, then writes `please_rw` FALSE and `done_w` TRUE (TF5200 HLI
//! "Technology functions"; the PLC side as `kimblad/TwinSharp`
//! `TwinSharp/CNC/TechnologyProcesses.cs` runs it). Meanwhile this side watches the channel:
//! the motion stays at X10 while the unit waits and the program ends only after the
//! acknowledgement. Ignored by default (needs the client installed):
//!
//! `NCCHANNEL_PYTHON=/path/to/venv/bin/python cargo test --test ads_clients -- --ignored techno`
//! (pyads, tests/python/techno_with_pyads.py; Node `ads-client` after `npm install --prefix
//! tests/node`, tests/node/techno_plc_test.js).

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use ncchannel::vocab::mode::State;

use crate::techno_rig::TechnoRig;

/// What the channel showed at one moment.
struct Seen {
    at: Instant,
    x: f64,
    used: u16,
}

/// Run `program script` against a fresh rig, watching the channel until the client exits;
/// the client's JSON line and what was seen.
fn run_watching(program: &str, script: &str) -> (serde_json::Value, Vec<Seen>) {
    let rig = TechnoRig::start();
    let mut cmd = Command::new(program);
    cmd.arg(script)
        .env("NCCHANNEL_ADS_ADDR", rig.server.local_addr().to_string())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd
        .spawn()
        .unwrap_or_else(|e| panic!("{program} runs: {e}"));
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut seen = Vec::new();
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("{script} did not finish within 60 s");
        }
        let s = rig.status();
        let x = s
            .positions
            .iter()
            .find(|p| p.0 == 'X')
            .map_or(f64::NAN, |p| p.1);
        seen.push(Seen {
            at: Instant::now(),
            x,
            used: s.techno.used_std,
        });
        std::thread::sleep(Duration::from_millis(1));
    }
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{script}: {stderr}");
    let end = rig.status();
    assert_eq!(end.state, State::Ready, "the program ended");
    let x = end
        .positions
        .iter()
        .find(|p| p.0 == 'X')
        .map_or(f64::NAN, |p| p.1);
    assert!((x - 30.0).abs() < 1e-6, "at its end: X{x}");
    assert_eq!(end.techno.used_std, 0);
    let json: serde_json::Value = serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim())
        .unwrap_or_else(|e| panic!("{script} printed no JSON ({e}): {stderr}"));
    // What the client saw, for a reader of `--nocapture`.
    eprintln!("{script} saw: {json}");
    (json, seen)
}

/// The channel waited for the client: the unit asked for at least `held`, the axis stayed
/// at X10 (never beyond) while it asked and until the acknowledgement took it back.
fn assert_waited(seen: &[Seen], held: Duration) {
    let asking: Vec<&Seen> = seen.iter().filter(|s| s.used == 1).collect();
    let (first, last) = (
        asking.first().expect("the unit was seen asking"),
        asking[asking.len() - 1],
    );
    assert!(
        last.at - first.at >= held,
        "asked for {:?} only",
        last.at - first.at
    );
    for s in seen.iter().take_while(|s| s.at <= last.at) {
        assert!(
            s.x <= 10.0 + 1e-6,
            "moved past X10 before the acknowledgement: {}",
            s.x
        );
    }
    for s in &asking {
        assert!((s.x - 10.0).abs() < 1e-6, "waiting away from X10: {}", s.x);
    }
}

fn assert_m25(unit: &serde_json::Value) {
    assert_eq!(unit["please"], 1, "{unit}");
    assert_eq!(unit["type"], 1, "{unit}");
    assert_eq!(unit["nr"], 25, "{unit}");
    assert_eq!(unit["block_nr"], 20, "{unit}");
    assert_eq!(unit["prg_line"], 2, "{unit}");
    assert_eq!(unit["synch_mode"], 2, "{unit}");
}

#[test]
#[ignore = "needs Python with pyads: NCCHANNEL_PYTHON=… cargo test --test ads_clients -- --ignored techno"]
fn pyads_as_the_plc_acknowledges_m25_and_the_motion_waits() {
    let python = std::env::var("NCCHANNEL_PYTHON").unwrap_or_else(|_| "python3".into());
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/python/techno_with_pyads.py"
    );
    let (json, seen) = run_watching(&python, script);
    assert_m25(&json["unit"]);
    assert_m25(&json["notified"]);
    assert_eq!(json["used_after"], 0);
    assert_waited(&seen, Duration::from_millis(150));
}

#[test]
#[ignore = "needs Node and tests/node/node_modules: npm install --prefix tests/node"]
fn node_ads_client_as_the_plc_acknowledges_m25_and_the_motion_waits() {
    let node = std::env::var("NCCHANNEL_NODE").unwrap_or_else(|_| "node".into());
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/node/techno_plc_test.js");
    let (json, seen) = run_watching(&node, script);
    assert_m25(&json["unit"]);
    assert_m25(&json["notified"]);
    assert_eq!(json["used_after"], 0);
    assert_waited(&seen, Duration::from_millis(150));
}
