//! `run` with a simulated PLC (runtime.toml `[plc]`, `machine::plc`): its delay shows in the
//! block times, fixed and drawn delays repeat by seed, late answers, a PLC that stops answering
//! leaves the program waiting, and a bad `[plc]` is a usage error naming the key.

use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

/// A start-up list with one channel whose M8 is MVS_SVS (20 ms process time) and M9 MOS,
/// the program `p.nc`, and `runtime` as runtime.toml.
fn setup(dir: &Path, runtime: &str, program: &str) {
    std::fs::create_dir_all(dir.join("params")).unwrap();
    std::fs::create_dir_all(dir.join("nc")).unwrap();
    std::fs::write(
        dir.join("params/startup.lis"),
        "kanal_anzahl 1\nsda_mds[0] channel1.lis\npfad[0].prg[0] ../nc\npfad[0].typ[0] 0x03\npfad[0].prioritaet[0] 0\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("params/channel1.lis"),
        "m_synch[8] MVS_SVS\nm_prozess_zeit[8] 20000\nm_synch[9] MOS\nm_prozess_zeit[9] 20000\n",
    )
    .unwrap();
    std::fs::write(dir.join("params/runtime.toml"), runtime).unwrap();
    std::fs::write(dir.join("nc/p.nc"), program).unwrap();
}

const PROGRAM: &str = "G90 G1 X10 F6000\nM8\nG1 X20\nM9\nG1 X30\nM8\nG1 X40\nM30\n";

fn run(dir: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .current_dir(dir)
        .args(["run", "p.nc", "--params", "params/startup.lis"])
        .args(["--events", "ev.jsonl", "--report", "report.json"])
        .args(extra)
        .output()
        .expect("the binary runs")
}

fn events(dir: &Path) -> Vec<Value> {
    std::fs::read_to_string(dir.join("ev.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn report(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

/// Per M8: its output time and the time of the next block that took effect after it.
fn m8_output_to_next_block(ev: &[Value]) -> Vec<(f64, f64)> {
    let mut v = Vec::new();
    for (i, e) in ev.iter().enumerate() {
        if e["ev"] == "techno_output" && e["number"] == 8 {
            let out = e["t"].as_f64().unwrap();
            let next = ev[i..]
                .iter()
                .find(|b| b["ev"] == "block")
                .map(|b| b["t"].as_f64().unwrap())
                .unwrap();
            v.push((out, next));
        }
    }
    v
}

fn text(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr)
}

#[test]
fn an_mvs_svs_function_holds_the_motion_for_the_plc_delay() {
    let dir = tempfile::tempdir().unwrap();
    setup(dir.path(), "", PROGRAM);
    let out = run(dir.path(), &[]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    let own = m8_output_to_next_block(&events(dir.path()));
    let own_time = report(dir.path())["time_s"].as_f64().unwrap();
    // Without a PLC the channel answers after the 20 ms process time.
    for (o, s) in &own {
        assert!((s - o - 0.020).abs() < 0.0015, "{o} → {s}");
    }

    setup(dir.path(), "[plc]\ndelay_ms = 300\n", PROGRAM);
    let out = run(dir.path(), &[]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert!(text(&out).contains("plc:        simulated, delay 300 ms, 3 acknowledged"));
    let plc = m8_output_to_next_block(&events(dir.path()));
    assert_eq!(plc.len(), 2);
    for (o, s) in &plc {
        assert!(
            s - o >= 0.300 && s - o < 0.303,
            "the motion starts ≥ 300 ms after output: {o} → {s}"
        );
    }
    let r = report(dir.path());
    assert_eq!(r["techno"]["output"], 3);
    assert_eq!(r["techno"]["acknowledged"], 3);
    let plc_time = r["time_s"].as_f64().unwrap();
    // The two M8 waits grow by 280 ms each; M9 (MOS) is not waited for, but the program end
    // waits for it.
    assert!(plc_time - own_time > 0.55, "{own_time} → {plc_time}");
}

#[test]
fn fixed_and_drawn_delays_repeat_by_seed() {
    let dir = tempfile::tempdir().unwrap();
    let time = |runtime: &str| {
        setup(dir.path(), runtime, PROGRAM);
        let out = run(dir.path(), &[]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out));
        let r = report(dir.path());
        (
            r["time_s"].as_f64().unwrap(),
            r["techno"]["waited_s"].as_f64().unwrap(),
        )
    };
    let fixed = time("[plc]\ndelay_ms = 100\n");
    assert_eq!(
        fixed,
        time("[plc]\ndelay_ms = 100\nseed = 9\n"),
        "a fixed delay draws nothing"
    );
    let a = time("[plc]\ndelay_ms = [50, 250]\nseed = 3\n");
    assert_eq!(a, time("[plc]\ndelay_ms = [50, 250]\nseed = 3\n"));
    let b = time("[plc]\ndelay_ms = [50, 250]\nseed = 4\n");
    assert_ne!(a, b, "another seed, other delays");
    // Three waits of 50 … 250 ms (+ the tick the PLC sees the unit in).
    for (_, waited) in [a, b] {
        assert!((0.15..=0.76).contains(&waited), "{waited}");
    }
    // A per-function delay wins over the default.
    let m9 = time("[plc]\ndelay_ms = 100\nfunctions = { M9 = 400 }\n");
    assert!((m9.1 - fixed.1 - 0.3).abs() < 0.0015, "{fixed:?} {m9:?}");
}

#[test]
fn every_kth_answer_comes_late() {
    let dir = tempfile::tempdir().unwrap();
    setup(
        dir.path(),
        "[plc]\ndelay_ms = 100\nlate_every = 2\nlate_ms = 500\n",
        PROGRAM,
    );
    let out = run(dir.path(), &[]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    assert!(text(&out).contains("1 late by 500 ms"), "{}", text(&out));
    let waited: Vec<f64> = events(dir.path())
        .iter()
        .filter(|e| e["ev"] == "techno_acknowledged")
        .map(|e| e["waited_s"].as_f64().unwrap())
        .collect();
    assert_eq!(waited.len(), 3);
    assert!((waited[0] - 0.101).abs() < 0.0015, "{waited:?}");
    assert!(
        (waited[1] - 0.601).abs() < 0.0015,
        "the 2nd answer 500 ms late: {waited:?}"
    );
    assert!((waited[2] - 0.101).abs() < 0.0015, "{waited:?}");
}

#[test]
fn a_plc_that_stops_answering_leaves_the_program_waiting() {
    let dir = tempfile::tempdir().unwrap();
    setup(
        dir.path(),
        "[plc]\ndelay_ms = 10\nstop_after = 1\n",
        PROGRAM,
    );
    let out = run(dir.path(), &["--max-ticks", "5000"]);
    assert_eq!(out.status.code(), Some(3), "max ticks: {}", text(&out));
    assert!(
        text(&out).contains("stops after 1: 1 left unanswered"),
        "{}",
        text(&out)
    );
    let r = report(dir.path());
    assert_eq!(r["techno"]["output"], 2, "{r}");
    assert_eq!(r["techno"]["acknowledged"], 1, "M9 (MOS) waits in its unit");
    let ev = events(dir.path());
    let last_block = ev.iter().rfind(|e| e["ev"] == "block").unwrap();
    // The MOS M9 went out and its block's motion ran; the program waits at the next M8,
    // whose output waits for the unit M9 still holds.
    assert_eq!(last_block["text"], "M8", "{last_block}");
    assert_eq!(
        r["position"]["X"].as_f64().map(|x| x.round()),
        Some(30.0),
        "{r}"
    );
}

#[test]
fn a_bad_plc_section_is_a_usage_error_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    for (toml, key) in [
        ("[plc]\ndelay_ms = [300, 100]\n", "plc.delay_ms"),
        ("[plc]\nfunctions = { Q8 = 5 }\n", "plc.functions"),
        ("[plc]\nlate_every = 0\n", "plc.late_every"),
        ("[plc]\ndelay = 5\n", "delay"),
        ("[plc]\ndelay_ms = \"soon\"\n", "plc.delay_ms"),
        ("[plc]\nchannels = [3]\n", "channel 3 does not exist"),
    ] {
        setup(dir.path(), toml, PROGRAM);
        let out = run(dir.path(), &[]);
        assert_eq!(out.status.code(), Some(2), "{toml}: {}", text(&out));
        assert!(text(&out).contains(key), "{toml}: {}", text(&out));
    }
}
