//! `ncchannel serve` stopped by SIGTERM or SIGINT mid-program: an orderly stop. The event log
//! parses line by line, holds every block the channel executed and ends with the last one,
//! and the summary is printed. While it runs, a reader tailing the log sees each block soon
//! after its tick. Also the command-line checks of `run --packet`.

use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::support::Rig;
use serde_json::Value;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_ncchannel")
}

/// Start `serve --start long.nc --events FILE`; returns once it listens (its runtime then
/// starts), with the moment it said so.
fn serve(rig: &Rig, events: &std::path::Path) -> (Child, Instant, std::thread::JoinHandle<String>) {
    let mut child = rig.serve_long(events).spawn().expect("serve starts");
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut first = String::new();
    err.read_line(&mut first).unwrap();
    let listening = Instant::now();
    // Led by its time, as every serve line.
    let listening_on = crate::support::abuse::unstamped(&first);
    assert!(listening_on.starts_with("listening on"), "{first}");
    let rest = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    (child, listening, rest)
}

fn kill(child: &Child, signal: &str) {
    let ok = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap()
        .success();
    assert!(ok, "kill {signal}");
}

fn wait(child: &mut Child, limit: Duration) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        assert!(
            start.elapsed() < limit,
            "serve did not stop within {limit:?}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Checks after an orderly stop: every line whole JSON, the last event a block, the block
/// count the summary prints equal to the block events.
fn check_stopped_log(log: &str, stderr: &str) {
    assert!(log.ends_with('\n'), "the log ends with a whole line");
    let events: Vec<Value> = log
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    let blocks: Vec<&Value> = events.iter().filter(|e| e["ev"] == "block").collect();
    assert!(
        blocks.len() > 10,
        "the program ran: {} blocks",
        blocks.len()
    );
    let summary = stderr
        .lines()
        .find_map(|l| l.split_once(" stopped after").map(|(_, rest)| rest))
        .unwrap_or_else(|| panic!("no summary in {stderr}"));
    // "<RFC 3339 time> stopped after T ticks (S s), B blocks; …"
    let printed: usize = summary
        .split("), ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no block count in {summary}"));
    assert_eq!(printed, blocks.len(), "summary: {summary}");
    // In order, each once.
    for w in blocks.windows(2) {
        assert_eq!(
            w[1]["counter"].as_u64().unwrap(),
            w[0]["counter"].as_u64().unwrap() + 1
        );
    }
}

/// Whole `block` lines in the log file so far.
fn block_lines(events: &std::path::Path) -> usize {
    std::fs::read_to_string(events)
        .map(|t| t.lines().filter(|l| l.contains(r#""ev":"block""#)).count())
        .unwrap_or(0)
}

fn stopped_by(signal: &str) {
    let rig = Rig::new();
    rig.long_program();
    let events = rig.dir.path().join("events.jsonl");
    let (mut child, _, stderr) = serve(&rig, &events);
    // Stopped once the program has run a while (the log shows more than 10 blocks), however
    // slowly a loaded machine runs it.
    let until = Instant::now() + Duration::from_secs(60);
    while block_lines(&events) <= 10 {
        assert!(
            Instant::now() < until,
            "the program did not run 10 blocks in 60 s"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    kill(&child, signal);
    let status = wait(&mut child, Duration::from_secs(30));
    let stderr = stderr.join().unwrap();
    assert_eq!(status.code(), Some(0), "orderly stop exits 0: {stderr}");
    // Every line after the first is led by its time too (the first was checked on reading).
    for line in stderr.lines() {
        crate::support::abuse::unstamped(line);
    }
    let log = std::fs::read_to_string(&events).unwrap();
    check_stopped_log(&log, &stderr);
}

#[test]
fn serve_stopped_by_sigterm_mid_program_leaves_a_whole_log_and_a_summary() {
    stopped_by("-TERM");
}

#[test]
fn serve_stopped_by_sigint_mid_program_leaves_a_whole_log_and_a_summary() {
    stopped_by("-INT");
}

/// A reader tailing `--events` sees the blocks while `serve` runs (the log is flushed at least
/// every 100 ms), and the test prints how soon after its tick: the tick's wall time is taken
/// as the moment serve said it listens plus the block's channel time, an upper bound, since
/// the runtime starts after.
#[test]
fn a_tailing_reader_sees_the_blocks_while_serve_runs() {
    let rig = Rig::new();
    rig.long_program();
    let events = rig.dir.path().join("events.jsonl");
    let (mut child, listening, stderr) = serve(&rig, &events);
    let mut f = loop {
        if let Ok(f) = std::fs::File::open(&events) {
            break f;
        }
        std::thread::sleep(Duration::from_millis(1));
    };
    let mut pending = String::new();
    let mut latencies_ms = Vec::new();
    // At least 4 s of tailing, longer (up to 60 s) until more than 20 blocks were seen.
    let started = Instant::now();
    let mut pos = 0u64;
    while started.elapsed() < Duration::from_secs(4)
        || (latencies_ms.len() <= 20 && started.elapsed() < Duration::from_secs(60))
    {
        let mut chunk = String::new();
        f.seek(SeekFrom::Start(pos)).unwrap();
        let n = f.read_to_string(&mut chunk).unwrap();
        pos += n as u64;
        let now = Instant::now();
        pending.push_str(&chunk);
        while let Some(i) = pending.find('\n') {
            let line: String = pending.drain(..=i).collect();
            let e: Value = serde_json::from_str(line.trim_end()).unwrap();
            if e["ev"] == "block" {
                let tick_at = listening + Duration::from_secs_f64(e["t"].as_f64().unwrap());
                latencies_ms.push(now.saturating_duration_since(tick_at).as_secs_f64() * 1e3);
            }
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    kill(&child, "-INT");
    wait(&mut child, Duration::from_secs(30));
    let _ = stderr.join();
    assert!(
        latencies_ms.len() > 20,
        "{} blocks seen",
        latencies_ms.len()
    );
    latencies_ms.sort_by(f64::total_cmp);
    let q = |p: f64| latencies_ms[((latencies_ms.len() - 1) as f64 * p) as usize];
    eprintln!(
        "tail latency over {} blocks: p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms",
        latencies_ms.len(),
        q(0.5),
        q(0.99),
        q(1.0)
    );
    // The latency is a figure, not an assertion: on a loaded machine (CI, other builds) the
    // reader's own scheduling adds to it, and a wall-clock bound there fails now and then.
    // What the test holds is that the blocks reached the reader while `serve` ran, not at
    // its stop: more than 20 of them within the 4 s of tailing.
}

#[test]
fn run_refuses_a_packet_above_992_up_front() {
    for bad in ["993", "0", "4096"] {
        let out = Command::new(bin())
            .args(["run", "--packet", bad, "--stream", "nc/none.nc"])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "--packet {bad}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("1..=992"), "{err}");
    }
}

/// The shipped slow-feeder scenario does what it says: the channel starves and interrupts.
#[test]
fn slow_feeder_scenario_starves_the_channel() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/params/soak/slow_feeder.toml");
    let scenario = ncchannel::soak::scenario::Scenario::load(std::path::Path::new(path)).unwrap();
    let opts = ncchannel::soak::Options {
        length: Some(ncchannel::soak::scenario::Length {
            blocks: Some(20_000),
            ..Default::default()
        }),
        ..Default::default()
    };
    let report = ncchannel::soak::run(&scenario, &opts).unwrap();
    // Memory is left out: tests share one process, its resident set is not this run's.
    assert!(report
        .invariants
        .iter()
        .all(|v| v.held || v.name == "memory steady"));
    let c = &report.channels[0];
    assert!(c.interrupts > 50, "{} interrupts", c.interrupts);
}

/// `receive --listen` stops in order on SIGTERM: the transfers so far are filed and counted,
/// the summary printed, exit 0.
#[test]
fn receive_listen_stops_in_order_on_sigterm() {
    use std::io::Write;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("prog");
    let mut cmd = Command::new(bin());
    cmd.stdout(Stdio::piped());
    let (mut child, addr, _stderr) = crate::support::abuse::receive_listening(cmd, &out, &[]);
    {
        let mut s = std::net::TcpStream::connect(addr).unwrap();
        s.write_all(b"%A\nN1 X1\nM30\n").unwrap();
    }
    // The program is filed when its file is there: then the stop has something to count.
    let t0 = Instant::now();
    while !out.join("A.nc").exists() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "A.nc was never filed"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    kill(&child, "-TERM");
    let status = wait(&mut child, Duration::from_secs(10));
    let mut stdout = String::new();
    child
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut stdout)
        .unwrap();
    assert_eq!(status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("1 program(s) filed"), "{stdout}");
    assert!(stdout.contains("1 transfer(s)"), "{stdout}");
    assert!(out.join("A.nc").exists());
}
