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
