//! The binary outside a clone: the shipped set built in, `init`, `NCCHANNEL_PARAMS`, program
//! paths against the current folder, a missing program as a usage error.

use std::path::Path;
use std::process::{Command, Output};

/// The binary in `cwd`, with its own cache folder (no other test's or user's cached set).
fn ncchannel(cwd: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(args)
        .current_dir(cwd)
        .env("XDG_CACHE_HOME", cwd.join("cache"))
        .env_remove("NCCHANNEL_PARAMS")
        .output()
        .expect("ncchannel starts")
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn the_demo_runs_in_an_empty_folder_from_the_built_in_set() {
    let dir = tempfile::tempdir().unwrap();
    let o = ncchannel(dir.path(), &[]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}\n{err}");
    assert!(out.contains("outcome:    program ended"), "{out}");
    assert!(err.contains("built into ncchannel"), "{err}");
    // The set is cached once, under the given cache folder, and nothing is written here.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["cache"]);
}

#[test]
fn a_program_in_the_current_folder_runs_by_its_file_name() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("far.nc"), "G01 X12.5 F1000\nM30\n").unwrap();
    let o = ncchannel(dir.path(), &["run", "far.nc"]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}\n{err}");
    assert!(out.contains("X=12.500"), "{out}");
}

#[test]
fn a_missing_program_is_a_usage_error_before_any_channel_runs() {
    let dir = tempfile::tempdir().unwrap();
    for (arg, says) in [
        ("./nosuch.nc", "no such program file"),
        (
            "nosuch.nc",
            "not found in the current folder nor in channel 1's search paths",
        ),
    ] {
        let o = ncchannel(dir.path(), &["run", arg]);
        let (out, err) = text(&o);
        assert_eq!(o.status.code(), Some(2), "{arg}: {out}\n{err}");
        assert!(err.contains(says), "{arg}: {err}");
        assert!(out.is_empty(), "{arg}: no summary of zeros: {out}");
    }
}

#[test]
fn init_writes_the_set_that_the_commands_then_read() {
    let dir = tempfile::tempdir().unwrap();
    let o = ncchannel(dir.path(), &["init", "ws"]);
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
    let ws = dir.path().join("ws");
    assert!(ws.join("params/startup.lis").is_file());
    assert!(ws.join("nc/demo.nc").is_file());
    // A second init refuses and writes nothing.
    let again = ncchannel(dir.path(), &["init", "ws"]);
    assert_eq!(again.status.code(), Some(2));
    assert!(text(&again).1.contains("already exists"));
    // The written set is the one read: an edit to its demo shows in the run.
    std::fs::write(ws.join("nc/demo.nc"), "G01 X7 Y3 F2000\nM30\n").unwrap();
    let o = ncchannel(&ws, &[]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}\n{err}");
    assert!(out.contains("X=7.000"), "{out}");
    assert!(!err.contains("built into ncchannel"), "{err}");
}

#[test]
fn ncchannel_params_names_the_start_up_list() {
    let dir = tempfile::tempdir().unwrap();
    assert_eq!(
        ncchannel(dir.path(), &["init", "ws"]).status.code(),
        Some(0)
    );
    let list = dir.path().join("ws/params/startup.lis");
    let o = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(["run", "demo.nc"])
        .current_dir(dir.path())
        .env("XDG_CACHE_HOME", dir.path().join("cache"))
        .env("NCCHANNEL_PARAMS", &list)
        .output()
        .unwrap();
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}\n{err}");
    assert!(!err.contains("built into ncchannel"), "{err}");
    // A list named by the variable that does not exist is refused, not replaced.
    let o = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(["run", "demo.nc"])
        .current_dir(dir.path())
        .env("NCCHANNEL_PARAMS", dir.path().join("no/such.lis"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{:?}", text(&o));
}

#[test]
fn a_shipped_soak_scenario_runs_outside_a_clone() {
    let dir = tempfile::tempdir().unwrap();
    let o = ncchannel(
        dir.path(),
        &[
            "soak",
            "params/soak/stream_resets.toml",
            "--blocks",
            "300",
            "-q",
        ],
    );
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}\n{err}");
}

#[test]
fn an_unwritable_cache_folder_reads_the_set_from_a_private_copy_removed_at_exit() {
    let dir = tempfile::tempdir().unwrap();
    // A cache folder under a regular file cannot be created, whoever runs the test.
    std::fs::write(dir.path().join("file"), "").unwrap();
    let tmp = dir.path().join("tmp");
    std::fs::create_dir(&tmp).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .current_dir(dir.path())
        .env("XDG_CACHE_HOME", dir.path().join("file/cache"))
        .env("TMPDIR", &tmp)
        .env_remove("NCCHANNEL_PARAMS")
        .output()
        .expect("ncchannel starts");
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}\n{err}");
    assert!(out.contains("outcome:    program ended"), "{out}");
    assert_eq!(
        err.matches("the cache folder cannot be written").count(),
        1,
        "said once: {err}"
    );
    assert_eq!(
        std::fs::read_dir(&tmp).unwrap().count(),
        0,
        "the private copy is removed at exit"
    );
}

/// `serve` in `cwd` until it exits, its standard output says `until`, or 30 s pass (then it
/// is killed): exit code, whether it exited by itself, stdout and stderr.
fn serve_until(cwd: &Path, args: &[&str], until: &str) -> (Option<i32>, bool, String, String) {
    use std::io::Read;
    use std::sync::{Arc, Mutex};
    let mut child = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(["serve", "--bind", "127.0.0.1:0"])
        .args(args)
        .current_dir(cwd)
        .env("XDG_CACHE_HOME", cwd.join("cache"))
        .env_remove("NCCHANNEL_PARAMS")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("serve starts");
    let collect = |mut r: Box<dyn Read + Send>| {
        let text = Arc::new(Mutex::new(String::new()));
        let sink = Arc::clone(&text);
        let reader = std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n @ 1..) = r.read(&mut buf) {
                sink.lock()
                    .unwrap()
                    .push_str(&String::from_utf8_lossy(&buf[..n]));
            }
        });
        (text, reader)
    };
    let (out, out_reader) = collect(Box::new(child.stdout.take().expect("stdout")));
    let (err, err_reader) = collect(Box::new(child.stderr.take().expect("stderr")));
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    let exited = loop {
        if child.try_wait().expect("try_wait").is_some() {
            break true;
        }
        if out.lock().unwrap().contains(until) || std::time::Instant::now() >= deadline {
            let _ = child.kill();
            break false;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let status = child.wait().expect("wait");
    let _ = (out_reader.join(), err_reader.join());
    let text = |t: &Arc<Mutex<String>>| t.lock().unwrap().clone();
    (status.code(), exited, text(&out), text(&err))
}

#[test]
fn serve_start_finds_a_program_of_the_current_folder_and_fails_on_one_found_nowhere() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("part.nc"), "G01 X12.5 F1000\nM30\n").unwrap();
    // Found as `run part.nc` finds it: its blocks run (the server runs on until killed).
    let end = r#""ev":"program_end","prog":"part.nc","end":"M30""#;
    let (_, exited, out, err) =
        serve_until(dir.path(), &["--start", "part.nc", "--events", "-"], end);
    assert!(!exited, "serve runs on: {err}");
    assert!(out.contains(end), "{out}\n{err}");
    // Found nowhere: a usage error at once, not a server with its channel in ERROR.
    let (code, exited, _, err) = serve_until(dir.path(), &["--start", "nosuch.nc"], "never");
    assert!(exited, "serve exits: {err}");
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("nosuch.nc not found in the current folder"),
        "{err}"
    );
}
