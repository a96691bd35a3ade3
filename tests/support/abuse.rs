//! Helpers shared by the abuse tests (`ads_abuse`, `receive_abuse`): a spawned process's
//! resident set, its standard error collected as it comes, and deterministic random bytes.
#![allow(dead_code)]

use std::io::{BufRead, BufReader, Read};
use std::net::SocketAddr;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};

/// `VmRSS` of process `pid` in KiB, from /proc/<pid>/status.
pub fn rss_kib(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).expect("/proc status");
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next()?.parse().ok())
        .expect("VmRSS")
}

/// Read `err` line by line on a thread of its own, after its `first` line (returned), into
/// the shared string (so a test can look at the log while the process runs).
pub fn collect(err: impl Read + Send + 'static) -> (String, Arc<Mutex<String>>) {
    let mut err = BufReader::new(err);
    let mut first = String::new();
    err.read_line(&mut first).expect("first line");
    let text = Arc::new(Mutex::new(String::new()));
    let sink = Arc::clone(&text);
    std::thread::spawn(move || {
        let mut line = String::new();
        while err.read_line(&mut line).is_ok_and(|n| n > 0) {
            sink.lock()
                .unwrap_or_else(|p| p.into_inner())
                .push_str(&line);
            line.clear();
        }
    });
    (first, text)
}

/// A `serve` stderr line without the RFC 3339 UTC time that leads it (asserted: every serve
/// line has one), e.g. `listening on 127.0.0.1:PORT (AMS NetId …`.
pub fn unstamped(line: &str) -> &str {
    let (time, rest) = line
        .split_once(' ')
        .unwrap_or_else(|| panic!("no time: {line}"));
    humantime::parse_rfc3339(time).unwrap_or_else(|e| panic!("{e}: {line}"));
    rest
}

/// `receive --listen` on a loopback port splitting by `%` … `M30` into `out`, with `extra`
/// options, run by `cmd` (the binary itself, or a shell that sets limits and execs it; its
/// standard output as `cmd` says): the process, the address its first stderr line names, and
/// its stderr as it comes.
pub fn receive_listening(
    mut cmd: Command,
    out: &Path,
    extra: &[&str],
) -> (Child, SocketAddr, Arc<Mutex<String>>) {
    let mut child = cmd
        .args([
            "receive",
            "--listen",
            "127.0.0.1:0",
            "--start",
            "%",
            "--end",
            "M30",
        ])
        .arg("--out")
        .arg(out)
        .args(extra)
        .stderr(Stdio::piped())
        .spawn()
        .expect("receive starts");
    let (first, stderr) = collect(child.stderr.take().expect("stderr"));
    let addr = first
        .trim()
        .strip_prefix("listening on ")
        .and_then(|a| a.parse().ok())
        .unwrap_or_else(|| panic!("{first}"));
    (child, addr, stderr)
}

/// The collected log once it holds `needle` `times` times, or as it is after `deadline` if it
/// never does. A process writes its log line when it has done the work, and the reading thread
/// appends it a moment later: a test that asserts on the line waits for it instead of racing it.
pub fn log_once_it_holds(
    log: &Mutex<String>,
    needle: &str,
    times: usize,
    deadline: std::time::Duration,
) -> String {
    let until = std::time::Instant::now() + deadline;
    loop {
        let text = log.lock().unwrap_or_else(|p| p.into_inner()).clone();
        if text.matches(needle).count() >= times || std::time::Instant::now() >= until {
            return text;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

/// Deterministic random bytes (xorshift64*), so a failing run can be repeated.
pub struct RandomBytes(pub u64);

impl RandomBytes {
    pub fn fill(&mut self, out: &mut [u8]) {
        for b in out {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            *b = (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 56) as u8;
        }
    }
}
