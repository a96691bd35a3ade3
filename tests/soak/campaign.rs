//! Campaigns beyond one machine: `soak --shard I/N` runs disjoint parts of scenarios × seeds
//! whose union is the whole campaign, `soak merge` joins the shard reports into the verdict the
//! unsharded run gives, and a failing or missing shard fails the merge.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn ncchannel(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr),
    )
}

fn scenario(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("params/soak")
        .join(name)
        .display()
        .to_string()
}

fn read(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// What identifies a finished run: its place, scenario, seed, length, per-channel checksums and
/// verdicts. Not "memory steady": the resident set is the process's, and a process that ran
/// other runs before (the unsharded campaign) starts this one warmer than a shard that did not.
fn runs(report: &Value) -> Vec<String> {
    report["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let s = &r["report"];
            let sums: Vec<&str> = s["channels"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| c["checksum"].as_str().unwrap())
                .collect();
            let verdicts: Vec<String> = s["invariants"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|v| v["name"] != "memory steady")
                .map(|v| format!("{} {}", v["name"], v["held"]))
                .collect();
            format!(
                "{} {} seed {} {} blocks {} ticks {:?} {:?}",
                r["index"], s["scenario"], s["seed"], s["blocks"], s["ticks"], sums, verdicts
            )
        })
        .collect()
}

/// Run the campaign with three seeds a scenario (`extra` adds the length, --shard, --report).
fn campaign(scenarios: &[&str], extra: &[&str]) -> (i32, String) {
    let mut args = vec!["soak"];
    args.extend_from_slice(scenarios);
    args.extend_from_slice(&["--seeds", "3", "-q"]);
    args.extend_from_slice(extra);
    ncchannel(&args)
}

#[test]
fn shards_partition_the_campaign_and_their_merge_is_the_whole_runs_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let a = scenario("stream_resets.toml");
    let b = scenario("cache_churn.toml");
    let whole = dir.path().join("whole.json");
    let (code, out) = campaign(
        &[&a, &b],
        &["--blocks", "1500", "--report", whole.to_str().unwrap()],
    );
    assert_eq!(code, 0, "{out}");
    let whole = read(&whole);
    assert_eq!(whole["runs"].as_array().unwrap().len(), 6);

    let mut shard_reports: Vec<PathBuf> = Vec::new();
    let mut union = Vec::new();
    for i in 1..=4 {
        let p = dir.path().join(format!("shard{i}.json"));
        let shard = format!("{i}/4");
        let (code, out) = campaign(
            &[&a, &b],
            &[
                "--blocks",
                "1500",
                "--shard",
                &shard,
                "--report",
                p.to_str().unwrap(),
            ],
        );
        assert_eq!(code, 0, "{out}");
        union.extend(runs(&read(&p)));
        shard_reports.push(p);
    }
    union.sort();
    let mut expected = runs(&whole);
    expected.sort();
    assert_eq!(
        union, expected,
        "disjoint shards whose union is the campaign"
    );

    let merged = dir.path().join("merged.json");
    let mut args = vec!["soak", "merge"];
    args.extend(shard_reports.iter().map(|p| p.to_str().unwrap()));
    args.extend(["--report", merged.to_str().unwrap()]);
    let (code, out) = ncchannel(&args);
    assert_eq!(code, 0, "{out}");
    let merged = read(&merged);
    assert_eq!(runs(&merged), runs(&whole), "the merge is the whole run");
    assert_eq!(merged["all_held"], whole["all_held"]);
    assert_eq!(merged["campaign"], whole["campaign"]);

    // A shard missing, or given twice: no verdict (exit 2).
    let (code, out) = ncchannel(&[
        "soak",
        "merge",
        shard_reports[0].to_str().unwrap(),
        shard_reports[1].to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("3/4 4/4 missing"), "{out}");
    let (code, out) = ncchannel(&[
        "soak",
        "merge",
        shard_reports[0].to_str().unwrap(),
        shard_reports[0].to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{out}");
}

#[test]
fn a_failing_shard_fails_the_merge_as_it_fails_the_whole_campaign() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("bad.nc"),
        "N1 G90 G01 F30000\nN2 X1\nN3 X[P77]\nN4 X2\nM30\n",
    )
    .unwrap();
    // An unexpected channel error (P77 is undefined) in every run of this scenario.
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        format!(
            "params = {:?}\n[length]\nticks = 200\n[[channel]]\nnumber = 1\nfile = \"bad.nc\"\n",
            scenario("startup.lis")
        ),
    )
    .unwrap();
    let good = scenario("stream_resets.toml");
    let bad = bad.to_str().unwrap();
    let (code, out) = campaign(&[&good, bad], &["--ticks", "2000"]);
    assert_eq!(code, 1, "{out}");
    let mut reports = Vec::new();
    let mut codes = Vec::new();
    for i in 1..=2 {
        let p = dir.path().join(format!("s{i}.json"));
        let shard = format!("{i}/2");
        let (code, out) = campaign(
            &[&good, bad],
            &[
                "--ticks",
                "2000",
                "--shard",
                &shard,
                "--report",
                p.to_str().unwrap(),
            ],
        );
        codes.push(code);
        assert!(code == 0 || code == 1, "{out}");
        reports.push(p);
    }
    assert!(
        codes.contains(&1),
        "the bad scenario's runs fail their shard"
    );
    let (code, out) = ncchannel(&[
        "soak",
        "merge",
        reports[0].to_str().unwrap(),
        reports[1].to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("VIOLATED") && out.contains("run(s) violated"),
        "{out}"
    );
}

/// A campaign of a quick run (500 blocks) and one that would run for hours, in `dir`: a
/// test waits for the quick run's report on standard output, then signals the soak while the
/// long run goes on.
fn quick_then_endless(dir: &Path) -> [String; 2] {
    let shipped = std::fs::read_to_string(scenario("stream_resets.toml")).unwrap();
    let params = format!("params = {:?}", scenario("startup.lis"));
    ["500", "1_000_000_000"].map(|blocks| {
        let body = shipped
            .replace("params = \"startup.lis\"", &params)
            .replace("blocks = 10_000_000", &format!("blocks = {blocks}"));
        assert_ne!(body, shipped, "stream_resets.toml changed shape");
        let p = dir.join(format!("blocks_{blocks}.toml"));
        std::fs::write(&p, body).unwrap();
        p.display().to_string()
    })
}

/// Start `soak SCENARIOS -q --report REPORT` and return it once the first run's verdict line
/// is on its standard output (the first run is over, the second about to run or running), with
/// the output so far and the thread that reads the rest.
fn soak_past_its_first_run(
    scenarios: &[String],
    report: &Path,
) -> (std::process::Child, String, std::thread::JoinHandle<String>) {
    use std::io::{BufRead, BufReader};
    let mut child = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .arg("soak")
        .args(scenarios)
        .args(["-q", "--report"])
        .arg(report)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut seen = String::new();
    while !seen.contains("result:") {
        let mut line = String::new();
        assert!(out.read_line(&mut line).unwrap() > 0, "soak ended: {seen}");
        seen.push_str(&line);
    }
    // The rest of standard output is read on as it comes, so the soak never blocks on it.
    let rest = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut out, &mut s);
        s
    });
    (child, seen, rest)
}

#[test]
fn a_killed_soak_leaves_no_passing_report_and_merge_refuses_what_it_left() {
    let dir = tempfile::tempdir().unwrap();
    let scenarios = quick_then_endless(dir.path());
    let report = dir.path().join("report.json");
    // Last run's report: passing.
    let mut args = vec![
        "soak",
        &scenarios[0],
        &scenarios[1],
        "-q",
        "--blocks",
        "500",
    ];
    args.extend(["--report", report.to_str().unwrap()]);
    let (code, out) = ncchannel(&args);
    assert_eq!(code, 0, "{out}");
    assert_eq!(read(&report)["all_held"], true);

    let (mut child, seen, _rest) = soak_past_its_first_run(&scenarios, &report);
    child.kill().unwrap(); // SIGKILL: no handler runs
    child.wait().unwrap();
    let left = read(&report);
    assert_eq!(left["status"], "incomplete", "{seen}");
    assert_eq!(left["all_held"], false);
    assert_eq!(left["runs"].as_array().map(Vec::len), Some(0));
    let (code, out) = ncchannel(&["soak", "merge", report.to_str().unwrap()]);
    assert_eq!(code, 2, "{out}");
    assert!(
        out.contains("report.json: the shard never finished"),
        "{out}"
    );
    // Nothing but the report itself in its folder: the temporary files were renamed.
    let stray: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(stray.is_empty(), "{stray:?}");
}

/// SIGINT (Ctrl-C) and SIGTERM on a virtual-time soak: the report of what ran, marked
/// interrupted in the file and on the verdict line, and the exit code a shell gives for the
/// signal; merge takes no verdict from it.
#[test]
fn a_signal_finishes_the_report_of_what_ran_marked_interrupted() {
    let dir = tempfile::tempdir().unwrap();
    let scenarios = quick_then_endless(dir.path());
    for (signal, code) in [("-INT", 130), ("-TERM", 143)] {
        let report = dir.path().join(format!("report{signal}.json"));
        let (mut child, _, rest) = soak_past_its_first_run(&scenarios, &report);
        let sent = Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap();
        assert!(sent.success());
        let mut stderr = String::new();
        std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "{signal}: {stderr}");
        assert!(stderr.contains("interrupted by SIG"), "{stderr}");
        let out = rest.join().unwrap();
        assert!(out.contains("result:   INTERRUPTED, "), "{out}");
        let r = read(&report);
        assert_eq!(r["status"], "interrupted", "{signal}");
        assert_eq!(r["all_held"], false, "an interrupted run is no pass");
        // The quick run, and the endless one if the signal came after it had begun.
        let runs = r["runs"].as_array().unwrap();
        assert_eq!(runs[0]["report"]["status"], "complete");
        assert_eq!(runs[0]["report"]["all_held"], true);
        if let Some(stopped) = runs.get(1) {
            assert_eq!(stopped["report"]["status"], "interrupted");
            assert!(
                out.contains("result:    INTERRUPTED, every invariant held so far"),
                "{out}"
            );
        }
        let (code, out) = ncchannel(&["soak", "merge", report.to_str().unwrap()]);
        assert_eq!(code, 2, "{out}");
        assert!(out.contains("was interrupted"), "{out}");
    }
}

/// A shard report left from another run of the same campaign is stale: merge tells it by the
/// run id every shard records (`--run-id`) and takes no verdict from a mix.
#[test]
fn merge_refuses_a_shard_report_of_another_run() {
    let dir = tempfile::tempdir().unwrap();
    let a = scenario("stream_resets.toml");
    let shard = |i: u32, run: &str| {
        let p = dir.path().join(format!("shard{i}.json"));
        let (code, out) = campaign(
            &[&a],
            &[
                "--blocks",
                "300",
                "--shard",
                &format!("{i}/3"),
                "--run-id",
                run,
                "--report",
                p.to_str().unwrap(),
            ],
        );
        assert_eq!(code, 0, "{out}");
        assert_eq!(read(&p)["run_id"], run);
        p.display().to_string()
    };
    let (one, two, three) = (shard(1, "run-7"), shard(2, "run-6"), shard(3, "run-7"));
    let (code, out) = ncchannel(&["soak", "merge", &one, &two, &three]);
    assert_eq!(code, 2, "{out}");
    assert!(
        out.contains("shard2.json is stale: it is of campaign run run-6, not run-7"),
        "{out}"
    );
    let (code, out) = ncchannel(&["soak", "merge", "--run-id", "run-8", &one, &two, &three]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("shard1.json is stale"), "{out}");
    let two = shard(2, "run-7");
    let (code, out) = ncchannel(&["soak", "merge", "--run-id", "run-7", &one, &two, &three]);
    assert_eq!(code, 0, "{out}");
}
