//! `ncchannel receive --listen` on a disk that refuses a program, for real and without root:
//! the receiver runs under a file-size limit (`ulimit -f`, RLIMIT_FSIZE, SIGXFSZ ignored so
//! the write fails with EFBIG as a full disk fails with ENOSPC), so every small program fits
//! and a big one does not. The receiver names the program lost and where the transfer
//! stopped, counts the programs it did file, leaves no temporary file, and takes the next
//! transfer.

use std::io::Write;
use std::net::{Shutdown, SocketAddr, TcpStream};
use std::path::Path;
use std::process::{Command, Stdio};

use crate::support::abuse as abuse_common;

/// The limit in 512-byte blocks (dash's unit; bash counts 1024): 32 or 64 KiB, far above the
/// small programs and far below the big one.
const FILE_SIZE_LIMIT_BLOCKS: u32 = 64;

fn send(addr: SocketAddr, data: &[u8]) {
    let mut s = TcpStream::connect(addr).expect("connect");
    // The receiver stops reading after the program it lost: the rest may be refused.
    let _ = s.write_all(data);
    let _ = s.shutdown(Shutdown::Write);
}

fn program(name: &str, lines: usize) -> String {
    let mut p = format!("%_N_{name}_MPF\r\n");
    for i in 0..lines {
        p.push_str(&format!("N{i} G01 X{i} F1000\r\n"));
    }
    p.push_str("M30\r\n");
    p
}

#[test]
fn a_program_the_disk_refuses_is_named_and_the_rest_counted() {
    let root = tempfile::tempdir().expect("tempdir");
    let out = root.path().join("out");
    let script = format!("trap '' XFSZ; ulimit -f {FILE_SIZE_LIMIT_BLOCKS}; exec \"$0\" \"$@\"");
    let mut sh = Command::new("sh");
    sh.arg("-c")
        .arg(&script)
        .arg(env!("CARGO_BIN_EXE_ncchannel"))
        .stdout(Stdio::piped());
    let (child, addr, stderr) = abuse_common::receive_listening(
        sh,
        &out,
        &["--max-transfers", "2", "--max-concurrent", "1"],
    );
    let (a, b, big, c) = (
        program("A", 3),
        program("B", 3),
        program("BIG", 40_000),
        program("C", 3),
    );
    let big_first = a.lines().count() + b.lines().count() + 1;
    let big_last = big_first + big.lines().count() - 1;
    send(addr, format!("{a}{b}{big}{c}").as_bytes());
    // One transfer at a time: the next one is taken once the first has ended.
    send(addr, program("D", 3).as_bytes());
    let o = child
        .wait_with_output()
        .expect("the receiver ends after two transfers");
    let stdout = String::from_utf8_lossy(&o.stdout);
    // The stderr reader has read to the end once the process is gone and the pipe closed.
    let err = abuse_common::log_once_it_holds(
        &stderr,
        "transfer from",
        1,
        std::time::Duration::from_secs(60),
    );
    println!("DISK FULL stdout:\n{stdout}\nstderr:\n{err}");
    assert_eq!(o.status.code(), Some(1), "a program was lost\n{err}");
    let names = |dir: &Path| -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .expect("out")
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().to_string())
            .collect();
        v.sort();
        v
    };
    assert_eq!(
        names(&out),
        ["A.mpf", "B.mpf", "D.mpf"],
        "no temporary file left"
    );
    assert!(
        stdout.contains("3 program(s) filed") && stdout.contains("1 lost to write errors"),
        "{stdout}"
    );
    let lost = out.join("BIG.mpf");
    assert!(
        stdout.contains(&format!("lost {}", lost.display())),
        "the log line names the program\n{stdout}"
    );
    assert!(
        err.contains(&format!(
            "{} (lines {big_first}-{big_last}) was lost",
            lost.display()
        )),
        "{err}"
    );
    assert!(
        err.contains(&format!("from line {}, was not taken", big_last + 1)),
        "{err}"
    );
    assert!(
        !err.contains(".ncchannel-receive-"),
        "no temporary path named\n{err}"
    );
}
