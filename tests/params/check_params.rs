//! `ncchannel check` on parameter lists: the shipped ones pass, a broken one names file, line,
//! column and parameter, and exits 1.

use std::process::Command;

fn check(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .arg("check")
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

#[test]
fn shipped_lists_and_programs_pass() {
    let (code, out) = check(&[
        "params/startup.lis",
        "params/channel1.lis",
        "params/runtime.toml",
        "nc",
    ]);
    assert_eq!(code, 0, "{out}");
}

#[test]
fn a_broken_list_gives_file_line_column_and_exit_1() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("startup.lis");
    std::fs::write(&p, "kanal_anzahl 1\nsda_mds[0] missing.lis\n").unwrap();
    let (code, out) = check(&[p.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(out.contains("startup.lis:2:12: error"), "{out}");
    assert!(out.contains("sda_mds[0]"), "{out}");
    let t = d.path().join("runtime.toml");
    std::fs::write(&t, "cycle_period_us = 1000\nbogus = 1\n").unwrap();
    let (code, out) = check(&[t.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(out.contains("bogus"), "{out}");
}

#[test]
fn the_shipped_folders_pass_as_the_issue_names_them() {
    // `check nc/* params/*.lis` as a shell expands it: nc/README.md is skipped, not an error.
    let mut args: Vec<String> = std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/nc"))
        .unwrap()
        .map(|e| format!("nc/{}", e.unwrap().file_name().to_string_lossy()))
        .collect();
    args.extend([
        "params/startup.lis".to_string(),
        "params/channel1.lis".to_string(),
    ]);
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, out) = check(&refs);
    assert_eq!(code, 0, "{out}");
}

/// `ncchannel run --params` on `dir`'s start-up list: exit code and everything printed.
fn run_with(dir: &std::path::Path) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(["run", "--params"])
        .arg(dir.join("startup.lis"))
        .arg("--max-ticks")
        .arg("10")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr),
    )
}

#[test]
fn check_and_run_refuse_the_same_bad_files_with_the_same_words() {
    // Each runtime.toml is refused by both, naming the same key; a good one passes both.
    let cases = [
        ("[[axes]]\nname = \"Q1\"\n", "axes[0].name"),
        ("[[axes]]\nname = \"F\"\n", "axes[0].name"),
        (
            "[decoder]\nblocks_per_tick = 0\n",
            "decoder.blocks_per_tick",
        ),
        ("[ads]\nmax_connections = 0\n", "ads.max_connections"),
    ];
    for (runtime, key) in cases {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("startup.lis"),
            "kanal_anzahl 1\nsda_mds[0] channel1.lis\n",
        )
        .unwrap();
        std::fs::write(
            dir.path().join("channel1.lis"),
            "streaming_prog_file s.nc\n",
        )
        .unwrap();
        let toml = dir.path().join("runtime.toml");
        std::fs::write(&toml, runtime).unwrap();
        let (code, out) = check(&[toml.to_str().unwrap()]);
        assert_eq!(code, 1, "check {runtime}: {out}");
        assert!(out.contains(key), "check {runtime}: {out}");
        let (code, out) = run_with(dir.path());
        assert_eq!(code, 2, "run {runtime}: {out}");
        assert!(out.contains(key), "run {runtime}: {out}");
    }
}

#[test]
fn check_of_the_example_installation_counts_each_lists_entries() {
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(["check", "params/installation"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert!(stdout.is_empty(), "no finding: {stdout}");
    // Each list once, whether reached from hochlauf.lis or by the folder walk.
    for line in [
        "params/installation/listen/hochlauf.lis: start-up list, 19 entries: 16 used, 3 inert, 0 unknown",
        "params/installation/listen/sda_mds1.lis: channel list, 20 entries: 17 used, 3 inert, 0 unknown",
        "params/installation/listen/default_mds.lis: axis list, 15 entries: 9 used, 6 inert, 0 unknown",
        "params/installation/listen/achsmds1.lis: axis list, 4 entries: 4 used, 0 inert, 0 unknown",
        "params/installation/listen/achsmds3.lis: axis list, 7 entries: 7 used, 0 inert, 0 unknown",
        "params/installation/listen/werkz_d.lis: tool list, 10 entries: 10 used, 0 inert, 0 unknown",
        "params/installation/listen/nullp_d.lis: zero-offset list, 6 entries: 6 used, 0 inert, 0 unknown",
        "params/installation/listen/ext_var1.lis: external variable list, 27 entries: 27 used, 0 inert, 0 unknown",
    ] {
        assert_eq!(
            stderr.matches(line).count(),
            1,
            "`{line}` once in:\n{stderr}"
        );
    }
    assert!(stderr.contains("0 error(s), 0 warning(s)"), "{stderr}");
}

/// A 5 MB unknown name is quoted once, as a bounded excerpt with its length: neither the
/// message nor the source line under it echoes it whole.
#[test]
fn a_huge_unknown_name_is_quoted_once_as_an_excerpt() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("achsmds1.lis");
    let name = "k".repeat(5_000_000);
    std::fs::write(&p, format!("kopf.achs_nr 1\n{name} 5\nEnde\n")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .arg("check")
        .arg(&p)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0));
    assert!(stdout.len() < 1000, "{} bytes of findings", stdout.len());
    let excerpt = format!("{}…(5000000 bytes)", "k".repeat(64));
    assert!(
        stdout.contains(&format!(
            "achsmds1.lis:2:1: warning: unknown parameter {excerpt}: kept"
        )),
        "{stdout}"
    );
    assert_eq!(stdout.matches(&"k".repeat(64)).count(), 1, "{stdout}");
}

#[test]
fn unknown_entries_are_counted_and_warned_about() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("achsmds1.lis");
    std::fs::write(
        &p,
        "kopf.achs_nr 1\nlr_param.kv_faktor 1000\nkenngr.mystery 5\n#kenngr.other 1\nEnde\n",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .arg("check")
        .arg(&p)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stdout}{stderr}");
    assert!(
        stdout.contains("achsmds1.lis:3:1: warning: unknown parameter kenngr.mystery"),
        "{stdout}"
    );
    assert!(
        stderr.contains("axis list, 3 entries: 1 used, 1 inert, 1 unknown"),
        "{stderr}"
    );
}
