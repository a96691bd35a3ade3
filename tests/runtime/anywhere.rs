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
