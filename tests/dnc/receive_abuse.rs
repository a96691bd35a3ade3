//! `ncchannel receive --listen` under abuse, against the real binary over loopback: names that
//! try to leave the output folder, cut transfers, huge lines, binary garbage, a silent sender,
//! a workpiece folder whose name a file already has, and transfers over the per-transfer
//! limits. After each: nothing outside `--out`, no partial file under a final name, no
//! temporary file left, the receiver's resident set within a bound, and the next sender's
//! program filed at once. Figures print as `ABUSE …` lines (`-- --nocapture`).

use std::io::Write;
use std::net::{Shutdown, SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::support::abuse as abuse_common;

const RSS_GROWTH_BOUND_KIB: u64 = 64 * 1024;

/// How long a test waits for a condition before it fails: generous, since it only matters
/// when the behaviour is broken, and a loaded machine must not turn a pass into a failure.
const DEADLINE: Duration = Duration::from_secs(60);

struct Receiver {
    child: Child,
    addr: SocketAddr,
    root: tempfile::TempDir,
    stderr: Arc<Mutex<String>>,
    normal: u32,
}

impl Receiver {
    fn start(extra: &[&str]) -> Receiver {
        let root = tempfile::tempdir().expect("tempdir");
        let out = root.path().join("out");
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_ncchannel"));
        cmd.current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdout(Stdio::null());
        let (child, addr, stderr) = abuse_common::receive_listening(cmd, &out, extra);
        Receiver {
            child,
            addr,
            root,
            stderr,
            normal: 0,
        }
    }

    fn out(&self) -> PathBuf {
        self.root.path().join("out")
    }

    fn log(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    /// The log once it holds `needle` `times` times (the receiver writes a transfer's lines
    /// as it ends, and the reading thread appends them a moment later).
    fn log_with_n(&self, needle: &str, times: usize) -> String {
        abuse_common::log_once_it_holds(&self.stderr, needle, times, DEADLINE)
    }

    fn log_with(&self, needle: &str) -> String {
        self.log_with_n(needle, 1)
    }

    fn rss_kib(&self) -> u64 {
        abuse_common::rss_kib(self.child.id())
    }

    /// One transfer: connect, send, close, and wait until the receiver has closed its side:
    /// it does so once the transfer is over (programs filed or dropped, temporary files gone).
    fn send(&self, data: &[u8]) {
        let mut s = TcpStream::connect(self.addr).expect("connect");
        // A receiver that stops reading at a limit may refuse the rest: that is its close.
        let _ = s.write_all(data);
        let _ = s.shutdown(Shutdown::Write);
        let _ = s.set_read_timeout(Some(DEADLINE));
        let closed = loop {
            match std::io::Read::read(&mut s, &mut [0u8; 16]) {
                Ok(0) => break true,
                Ok(_) => continue,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => {
                    break !matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    )
                }
            }
        };
        assert!(closed, "the receiver ended the transfer\n{}", self.log());
    }

    /// A normal sender's program is filed within a few seconds; then the invariants hold.
    fn check_serving(&mut self, abuse: &str, rss_before: u64) {
        self.normal += 1;
        let name = format!("NORMAL{}", self.normal);
        let asked = Instant::now();
        self.send(format!("%_N_{name}_MPF\r\nG01 X1\r\nM30\r\n").as_bytes());
        let file = self.out().join(format!("{name}.mpf"));
        while !file.exists() && asked.elapsed() < DEADLINE {
            std::thread::sleep(Duration::from_millis(20));
        }
        assert!(
            file.exists(),
            "{abuse}: the next sender's program filed\n{}",
            self.log()
        );
        let rss_after = self.rss_kib();
        println!(
            "ABUSE receive {abuse}: RSS before {rss_before} KiB, after {rss_after} KiB; next program filed in {:.0} ms",
            asked.elapsed().as_secs_f64() * 1e3
        );
        assert!(
            rss_after <= rss_before + RSS_GROWTH_BOUND_KIB,
            "{abuse}: memory"
        );
        self.check_tree(abuse);
    }

    /// Nothing beside `out/` in the root, no temporary or partial file anywhere.
    fn check_tree(&self, abuse: &str) {
        let outside: Vec<_> = std::fs::read_dir(self.root.path())
            .expect("root")
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().to_string())
            .filter(|n| n != "out")
            .collect();
        assert!(
            outside.is_empty(),
            "{abuse}: written outside --out: {outside:?}"
        );
        for f in files(&self.out()) {
            let name = f
                .file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .to_string();
            assert!(
                !name.starts_with(".ncchannel-receive-") && !name.ends_with(".partial"),
                "{abuse}: left {}",
                f.display()
            );
        }
    }
}

impl Drop for Receiver {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(files(&p));
            } else {
                out.push(p);
            }
        }
    }
    out
}

#[test]
fn names_that_try_to_leave_the_output_folder_stay_inside() {
    let mut r = Receiver::start(&[]);
    let rss = r.rss_kib();
    for data in [
        &b"%_N_..%2F.._MPF\r\nG01 X1\r\nM30\r\n"[..],
        b"%_N_EVIL_MPF\r\n;$PATH=/_N_WKS_DIR/_N_../../x_WPD\r\nG01 X1\r\nM30\r\n",
        b"%../../evil.nc\r\nG01 X1\r\nM30\r\n",
        b"%/tmp/evil.nc\r\nG01 X1\r\nM30\r\n",
        b"%_N_A/../../B_MPF\r\nG01 X1\r\nM30\r\n",
        b"%..\r\nG01 X1\r\nM30\r\n",
    ] {
        r.send(data);
    }
    r.check_serving("names leaving the folder", rss);
}

#[test]
fn cut_transfers_leave_no_file_under_a_final_name() {
    let mut r = Receiver::start(&[]);
    let rss = r.rss_kib();
    r.send(b"%_N_CUT1_MPF\r\nG01 X1\r\nG01 X2");
    r.send(b"%_N_CUT2_MPF\r\nG01 X1\r\n");
    let mut s = TcpStream::connect(r.addr).expect("connect");
    s.write_all(b"%_N_CUT3_MPF\r\nG01 X1\r\n").expect("send");
    // Closed without shutdown, mid-program; the receiver removes the program's temporary file
    // before it logs the drop, so once the log says so, check_serving finds none.
    drop(s);
    let dropped = "the transfer ended inside the program from line 1; it was dropped";
    let log = r.log_with_n(dropped, 3);
    assert_eq!(log.matches(dropped).count(), 3, "{log}");
    r.check_serving("cut transfers", rss);
    for n in ["CUT1", "CUT2", "CUT3"] {
        assert!(!r.out().join(format!("{n}.mpf")).exists(), "{n} filed");
    }
}

#[test]
fn huge_lines_and_binary_garbage_are_survived() {
    let mut r = Receiver::start(&[]);
    let rss = r.rss_kib();
    // A 32 MiB line inside a program, and one between programs.
    let mut huge = b"%_N_HUGE_MPF\r\nG01 X".to_vec();
    huge.extend(std::iter::repeat_n(b'9', 32 << 20));
    huge.extend_from_slice(b"\r\nM30\r\n");
    r.send(&huge);
    let mut between = vec![b'x'; 32 << 20];
    between.extend_from_slice(b"\r\n");
    r.send(&between);
    r.check_serving("32 MiB lines", rss);
    let mut junk = vec![0u8; 8 << 20];
    abuse_common::RandomBytes(0x2545_F491_4F6C_DD1D).fill(&mut junk);
    r.send(&junk);
    r.check_serving("8 MiB of binary garbage", rss);
}

#[test]
fn silent_senders_do_not_hold_up_the_others() {
    // Three silent senders hold three of the four slots for an hour (the idle timeout): the
    // program is filed within the deadline only if they hold up nobody. The connections are
    // accepted in the order they were made, so the normal sender gets the fourth slot.
    let mut r = Receiver::start(&["--max-concurrent", "4", "--idle-timeout", "3600"]);
    let rss = r.rss_kib();
    let _silent: Vec<TcpStream> = (0..3)
        .map(|_| TcpStream::connect(r.addr).expect("connect"))
        .collect();
    r.check_serving("3 silent senders, 4 concurrent transfers", rss);
    let log = r.log();
    assert!(!log.contains("timed out"), "{log}");
}

#[test]
fn a_silent_sender_frees_its_slot_after_the_idle_timeout() {
    let mut r = Receiver::start(&["--idle-timeout", "1", "--max-concurrent", "1"]);
    let rss = r.rss_kib();
    let _silent = TcpStream::connect(r.addr).expect("connect");
    r.check_serving("a silent sender in the only slot (idle timeout 1 s)", rss);
    let log = r.log_with("timed out");
    assert!(log.contains("timed out"), "{log}");
}

#[test]
fn a_workpiece_folder_named_like_a_filed_program_refuses_only_that_program() {
    let mut r = Receiver::start(&[]);
    let rss = r.rss_kib();
    r.send(b"%X.wpd\r\nG01 X1\r\nM30\r\n");
    r.send(b"%_N_PART_MPF\r\n;$PATH=/_N_WKS_DIR/_N_X_WPD\r\nG01 X2\r\nM30\r\n");
    r.check_serving("workpiece folder X_WPD after a program X.wpd", rss);
    assert!(r.out().join("X.wpd").is_file());
    let log = r.log_with("is a file, not a folder");
    assert!(log.contains("is a file, not a folder"), "{log}");
}

#[test]
fn transfers_beyond_their_limits_end_and_the_receiver_goes_on() {
    let mut r = Receiver::start(&["--max-transfer-bytes", "4096", "--max-programs", "3"]);
    let rss = r.rss_kib();
    let five: String = (1..=5)
        .map(|i| format!("%_N_MANY{i}_MPF\r\nG01 X{i}\r\nM30\r\n"))
        .collect();
    r.send(five.as_bytes());
    let mut big = b"%_N_BIG_MPF\r\n".to_vec();
    big.extend(b"G01 X1\r\n".repeat(2000));
    big.extend_from_slice(b"M30\r\n");
    r.send(&big);
    r.check_serving("over the limits (3 programs, 4096 bytes)", rss);
    let filed: Vec<bool> = (1..=5)
        .map(|i| r.out().join(format!("MANY{i}.mpf")).exists())
        .collect();
    assert_eq!(filed, [true, true, true, false, false]);
    assert!(!r.out().join("BIG.mpf").exists());
    let log = r.log_with("more than 3 programs");
    assert!(log.contains("more than 3 programs"), "{log}");
    let log = r.log_with("more than 4096 bytes");
    assert!(log.contains("more than 4096 bytes"), "{log}");
}

#[test]
fn concurrent_transfers_of_unnamed_programs_get_distinct_numbers() {
    let mut r = Receiver::start(&[]);
    let rss = r.rss_kib();
    std::thread::scope(|s| {
        for t in 0..4 {
            let r = &r;
            s.spawn(move || {
                let data: String = (0..5)
                    .map(|i| format!("%\r\nG01 X{t}{i}\r\nM30\r\n"))
                    .collect();
                r.send(data.as_bytes());
            });
        }
    });
    r.check_serving("4 concurrent transfers × 5 unnamed programs", rss);
    let mut bodies: Vec<String> = files(&r.out())
        .iter()
        .filter(|p| p.to_string_lossy().contains("received_"))
        .map(|p| std::fs::read_to_string(p).expect("read"))
        .collect();
    bodies.sort();
    bodies.dedup();
    assert_eq!(
        bodies.len(),
        20,
        "every program filed under a number of its own"
    );
}

/// `--listen` on every interface without the opt-in is refused before anything binds, as
/// `serve --bind` is; with `--allow-non-loopback` it listens and says so.
#[test]
fn listen_on_non_loopback_needs_the_opt_in() {
    let root = tempfile::tempdir().expect("tempdir");
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["receive", "--listen", "0.0.0.0:0", "--out"])
        .arg(root.path())
        .stdin(Stdio::null())
        .output()
        .expect("run ncchannel receive");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(
            "refusing to listen on non-loopback address 0.0.0.0:0 without --allow-non-loopback"
        ),
        "{stderr}"
    );
    assert!(!stderr.contains("listening on"), "{stderr}");
}
