//! The event log when the process or the disk fails under it, against the real binary:
//! `serve --events FILE` killed with SIGKILL leaves a log that parses to its last line, and a
//! log the disk refuses (`/dev/full` answers every write with ENOSPC) is reported on stderr
//! while `serve` still runs, not hours later at the stop.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::support::Rig;
use serde_json::Value;

/// Generous: only a broken behaviour waits this long.
const DEADLINE: Duration = Duration::from_secs(60);

/// `serve --start long.nc --events <events>`, its stderr collected as it comes.
fn serve(rig: &Rig, events: &Path) -> (Child, Arc<Mutex<String>>) {
    let mut child = rig.serve_long(events).spawn().expect("serve starts");
    let err = BufReader::new(child.stderr.take().expect("stderr"));
    let text = Arc::new(Mutex::new(String::new()));
    let sink = Arc::clone(&text);
    std::thread::spawn(move || {
        for line in err.lines().map_while(Result::ok) {
            let mut t = sink.lock().unwrap_or_else(|p| p.into_inner());
            t.push_str(&line);
            t.push('\n');
        }
    });
    (child, text)
}

fn wait_for(what: &str, mut f: impl FnMut() -> bool) {
    let t0 = Instant::now();
    while !f() {
        assert!(t0.elapsed() < DEADLINE, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

#[test]
fn a_sigkilled_serve_leaves_an_event_log_of_whole_lines() {
    let rig = Rig::new();
    rig.long_program();
    let events = rig.dir.path().join("events.jsonl");
    let (mut child, _err) = serve(&rig, &events);
    // Killed while it writes: after many flushes, at no particular moment.
    let size = |p: &Path| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0);
    wait_for("50 KB of events", || size(&events) > 50_000);
    child.kill().expect("SIGKILL");
    child.wait().expect("reaped");
    let log = std::fs::read_to_string(&events).expect("the log");
    assert!(log.ends_with('\n'), "the log ends with a whole line");
    for line in log.lines() {
        serde_json::from_str::<Value>(line).unwrap_or_else(|e| panic!("{e}: {line}"));
    }
    println!(
        "EVENTS SIGKILL: {} whole lines, {} bytes",
        log.lines().count(),
        log.len()
    );
}

#[test]
fn a_full_disk_under_the_event_log_is_reported_while_serve_runs() {
    let full = Path::new("/dev/full");
    if !full.exists() {
        eprintln!("no /dev/full on this system: nothing to check");
        return;
    }
    let rig = Rig::new();
    rig.long_program();
    let (mut child, err) = serve(&rig, full);
    let needle = "event log /dev/full: No space left on device";
    wait_for("the report of the failed write", || {
        err.lock()
            .unwrap_or_else(|p| p.into_inner())
            .contains(needle)
    });
    assert!(
        child.try_wait().expect("try_wait").is_none(),
        "reported while serve runs (the cycle goes on without its log)"
    );
    let ok = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill runs")
        .success();
    assert!(ok);
    let status = child.wait().expect("serve stops");
    assert_eq!(
        status.code(),
        Some(1),
        "the lost log is an error at the stop"
    );
}
