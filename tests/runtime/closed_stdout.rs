//! Every command that writes to standard output ends as a normal run would when the reader of
//! its output has gone (`ncchannel check FILE | head`): its own exit code, no panic message,
//! no exit 101 (src/cli/out.rs).
//!
//! The reader end of the pipe is closed before the command starts, so its first write already
//! finds no reader: the case is reached every time, whatever the scheduling.

use std::io::Write;
use std::path::Path;
use std::process::{Command, Stdio};

/// Run the binary with `args`, its standard output a pipe nobody reads; exit code and stderr.
fn run_with_closed_stdout(args: &[&str]) -> (Option<i32>, String) {
    let (reader, writer) = std::io::pipe().expect("a pipe");
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::null())
        .stdout(Stdio::from(writer))
        .stderr(Stdio::piped())
        .output()
        .expect("the binary runs");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn assert_quiet(what: &str, code: Option<i32>, stderr: &str, expected: i32) {
    assert!(
        !stderr.contains("panicked") && !stderr.contains("Broken pipe"),
        "{what}: {stderr}"
    );
    assert_eq!(code, Some(expected), "{what}: {stderr}");
}

/// A program with one finding per line, many more bytes of findings than a pipe holds.
fn many_findings(dir: &Path) -> String {
    let path = dir.join("many.nc");
    let mut f = std::fs::File::create(&path).expect("create");
    for n in 0..3000 {
        writeln!(f, "N{n} G999 X1").expect("write");
    }
    writeln!(f, "M30").expect("write");
    path.to_string_lossy().into_owned()
}

#[test]
fn check_ends_quietly_with_its_exit_code() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = many_findings(dir.path());
    let (code, stderr) = run_with_closed_stdout(&["check", &file]);
    // Findings: exit 1, and the summary still goes to stderr.
    assert_quiet("check", code, &stderr, 1);
    assert!(stderr.contains("ncchannel check: 1 file(s),"), "{stderr}");
}

#[test]
fn run_summary_and_event_log_end_quietly() {
    let (code, stderr) = run_with_closed_stdout(&["run", "nc/contour_square.nc"]);
    assert_quiet("run", code, &stderr, 0);
    let (code, stderr) = run_with_closed_stdout(&["run", "nc/contour_square.nc", "--events", "-"]);
    assert_quiet("run --events -", code, &stderr, 0);
    // The summary went to stderr, as always with `--events -`.
    assert!(stderr.contains("program ended"), "{stderr}");
}

#[test]
fn bench_ends_quietly() {
    let (code, stderr) = run_with_closed_stdout(&["bench", "--seconds", "0.05"]);
    assert_quiet("bench", code, &stderr, 0);
}

#[test]
fn help_ends_quietly() {
    let (code, stderr) = run_with_closed_stdout(&["help", "check"]);
    assert_quiet("help", code, &stderr, 0);
}
