//! How `ncchannel receive --listen` stops, against the real binary with real signals: SIGTERM
//! while a sender trickles one byte at a time ends the receiver within its grace period; a
//! second signal ends it at once; neither leaves a temporary file, and each run removes the
//! temporary files a receiver that was killed left behind.

use std::io::Write;
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::support::abuse as abuse_common;

/// Generous: a deadline only matters when the behaviour is broken, and a loaded CI machine
/// must not turn a pass into a failure.
const DEADLINE: Duration = Duration::from_secs(60);

struct Listening {
    child: Child,
    addr: SocketAddr,
    stderr: Arc<Mutex<String>>,
}

fn listen(out: &Path, extra: &[&str]) -> Listening {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_ncchannel"));
    cmd.stdout(Stdio::null());
    let (child, addr, stderr) = abuse_common::receive_listening(cmd, out, extra);
    Listening {
        child,
        addr,
        stderr,
    }
}

impl Listening {
    fn signal(&self, name: &str) {
        let ok = Command::new("kill")
            .arg(format!("-{name}"))
            .arg(self.child.id().to_string())
            .status()
            .expect("kill runs")
            .success();
        assert!(ok, "kill -{name}");
    }

    /// The exit status once the receiver has exited, `None` if it still runs at the deadline.
    fn exit_within(&mut self, deadline: Duration) -> Option<ExitStatus> {
        let until = Instant::now() + deadline;
        loop {
            if let Some(s) = self.child.try_wait().expect("try_wait") {
                return Some(s);
            }
            if Instant::now() >= until {
                return None;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    fn log_with(&self, needle: &str) -> String {
        abuse_common::log_once_it_holds(&self.stderr, needle, 1, DEADLINE)
    }
}

impl Drop for Listening {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn temp_files(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| {
                    p.file_name()
                        .is_some_and(|n| n.to_string_lossy().starts_with(".ncchannel-receive-"))
                })
                .collect()
        })
        .unwrap_or_default()
}

fn wait_for(what: &str, mut f: impl FnMut() -> bool) {
    let t0 = Instant::now();
    while !f() {
        assert!(t0.elapsed() < DEADLINE, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// A sender that opens a program and then sends one byte every 200 ms (well inside the idle
/// timeout) until `stop` is set or the receiver closes the connection.
fn trickle(addr: SocketAddr, stop: Arc<AtomicBool>) -> std::thread::JoinHandle<()> {
    let mut s = TcpStream::connect(addr).expect("connect");
    s.write_all(b"%_N_SLOW_MPF\r\nG01 X1\r\n").expect("send");
    std::thread::spawn(move || {
        while !stop.load(Ordering::Acquire) {
            if s.write_all(b"1").is_err() {
                return;
            }
            std::thread::sleep(Duration::from_millis(200));
        }
    })
}

#[test]
fn sigterm_ends_a_trickled_transfer_after_the_grace_period() {
    let root = tempfile::tempdir().expect("tempdir");
    let out = root.path().join("out");
    let mut r = listen(&out, &["--stop-grace", "1", "--idle-timeout", "30"]);
    let stop = Arc::new(AtomicBool::new(false));
    let sender = trickle(r.addr, Arc::clone(&stop));
    wait_for("the program's temporary file", || {
        !temp_files(&out).is_empty()
    });
    let asked = Instant::now();
    r.signal("TERM");
    let status = r.exit_within(DEADLINE);
    stop.store(true, Ordering::Release);
    let _ = sender.join();
    let status = status.expect("the receiver ends although the sender keeps trickling");
    println!(
        "RECEIVE SIGTERM with a trickling sender: exited after {:.1} s (grace 1 s)",
        asked.elapsed().as_secs_f64()
    );
    assert_eq!(status.code(), Some(1), "a program was cut off");
    let log = r.log_with("grace period of 1.0 s ended");
    assert!(log.contains("grace period of 1.0 s ended"), "{log}");
    assert!(temp_files(&out).is_empty(), "{:?}", temp_files(&out));
    assert!(!out.join("SLOW.mpf").exists());
}

#[test]
fn a_second_signal_stops_at_once_and_leaves_no_temporary_file() {
    let root = tempfile::tempdir().expect("tempdir");
    let out = root.path().join("out");
    let mut r = listen(&out, &["--stop-grace", "3600"]);
    let stop = Arc::new(AtomicBool::new(false));
    let sender = trickle(r.addr, Arc::clone(&stop));
    wait_for("the program's temporary file", || {
        !temp_files(&out).is_empty()
    });
    r.signal("TERM");
    // Two signals sent back to back can merge into one; the second goes after the first
    // was taken (the receiver says so).
    let log = r.log_with("a second signal cuts them");
    assert!(log.contains("a second signal cuts them"), "{log}");
    r.signal("INT");
    let status = r.exit_within(DEADLINE);
    stop.store(true, Ordering::Release);
    let _ = sender.join();
    let status = status.expect("the second signal ends the receiver");
    assert_eq!(status.code(), Some(130));
    assert!(temp_files(&out).is_empty(), "{:?}", temp_files(&out));
    assert!(!out.join("SLOW.mpf").exists());
}

/// A file counts as live while its writer holds its lock, whatever pid its name carries: one
/// named for a running process but unlocked is stale, one named for no process but locked is
/// live.
#[test]
fn a_run_removes_the_temporary_files_a_stopped_receiver_left_and_only_those() {
    let root = tempfile::tempdir().expect("tempdir");
    let out = root.path().join("out");
    std::fs::create_dir_all(&out).expect("out");
    // No process can have a pid above the kernel's pid_max.
    let pid_max: u64 = std::fs::read_to_string("/proc/sys/kernel/pid_max")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or(4_194_304);
    // This test process runs, but holds no lock on it: its writer is gone.
    let stale = out.join(format!(
        ".ncchannel-receive-{}-Ab12Cd.tmp",
        std::process::id()
    ));
    // Named for no process here (a receiver in another PID namespace), but locked.
    let live = out.join(format!(".ncchannel-receive-{}-Ab12Cd.tmp", pid_max + 1));
    let foreign = [
        out.join(".ncchannel-receive-Ab12Cd.tmp"),
        out.join("other.tmp"),
    ];
    for f in [&stale, &live].into_iter().chain(&foreign) {
        std::fs::write(f, b"G01 X1\r\n").expect("write");
    }
    let held = std::fs::File::open(&live).expect("open live");
    rustix::fs::flock(&held, rustix::fs::FlockOperation::NonBlockingLockExclusive)
        .expect("lock live");
    let input = root.path().join("in.txt");
    std::fs::write(&input, b"%_N_PART_MPF\r\nG01 X1\r\nM30\r\n").expect("input");
    let o = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .arg("receive")
        .arg(&input)
        .args(["--start", "%", "--end", "M30", "--out"])
        .arg(&out)
        .output()
        .expect("receive runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(out.join("PART.mpf").is_file());
    assert!(!stale.exists(), "the stale file was removed");
    assert!(live.exists(), "a running receiver's file is kept");
    for f in &foreign {
        assert!(f.exists(), "{} is not ours and was kept", f.display());
    }
    assert!(err.contains("removed 1 temporary file(s)"), "{err}");
    drop(held);
}

/// The `unshare` prefix that runs a command as pid 1 of a new PID namespace (with its own
/// /proc), or why this machine cannot.
fn pid_namespace_prefix() -> Result<Vec<&'static str>, String> {
    let plain = vec!["--pid", "--fork", "--mount-proc", "--kill-child"];
    let as_user = vec![
        "--user",
        "--map-root-user",
        "--pid",
        "--fork",
        "--mount-proc",
        "--kill-child",
    ];
    let mut why = String::new();
    for prefix in [plain, as_user] {
        match Command::new("unshare").args(&prefix).arg("true").output() {
            Ok(o) if o.status.success() => return Ok(prefix),
            Ok(o) => why = String::from_utf8_lossy(&o.stderr).trim().to_string(),
            Err(e) => why = format!("unshare: {e}"),
        }
    }
    Err(why)
}

/// Two receivers sharing a folder, each in its own PID namespace (two containers on one
/// volume): both are pid 1 there, and neither sees the other in /proc. The second one's start
/// leaves the first one's live temporary file alone, and the first files its program whole.
#[test]
fn a_receiver_in_another_pid_namespace_keeps_a_live_transfer() {
    let prefix = match pid_namespace_prefix() {
        Ok(p) => p,
        Err(why) => {
            println!("SKIPPED: no PID namespace here ({why})");
            return;
        }
    };
    let root = tempfile::tempdir().expect("tempdir");
    let out = root.path().join("out");
    std::fs::create_dir_all(&out).expect("out");
    let mut cmd = Command::new("unshare");
    cmd.args(&prefix)
        .arg(env!("CARGO_BIN_EXE_ncchannel"))
        .stdout(Stdio::null());
    let (mut first, addr, _stderr) = abuse_common::receive_listening(cmd, &out, &[]);
    let mut s = TcpStream::connect(addr).expect("connect");
    s.write_all(b"%_N_LIVE_MPF\r\nG01 X1\r\n")
        .expect("send the start");
    wait_for("the live transfer's temporary file", || {
        !temp_files(&out).is_empty()
    });
    assert_eq!(temp_files(&out).len(), 1, "the live transfer's file");

    let input = root.path().join("in.txt");
    std::fs::write(&input, b"%_N_OTHER_MPF\r\nG01 X2\r\nM30\r\n").expect("input");
    let second = Command::new("unshare")
        .args(&prefix)
        .arg(env!("CARGO_BIN_EXE_ncchannel"))
        .arg("receive")
        .arg(&input)
        .args(["--start", "%", "--end", "M30", "--out"])
        .arg(&out)
        .output()
        .expect("second receiver runs");
    let err = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(0), "{err}");
    assert!(!err.contains("removed"), "{err}");
    assert_eq!(temp_files(&out).len(), 1, "the live file is kept: {err}");

    s.write_all(b"G01 X3\r\nM30\r\n").expect("send the rest");
    s.shutdown(std::net::Shutdown::Write).expect("shutdown");
    s.set_read_timeout(Some(DEADLINE)).expect("timeout");
    // The receiver closes its side once the transfer is filed.
    let _ = std::io::Read::read(&mut s, &mut [0u8; 16]);
    let _ = first.kill();
    let _ = first.wait();
    let filed = std::fs::read(out.join("LIVE.mpf")).expect("LIVE.mpf is filed");
    assert_eq!(filed, b"%_N_LIVE_MPF\r\nG01 X1\r\nG01 X3\r\nM30\r\n");
    assert!(out.join("OTHER.mpf").is_file());
}
