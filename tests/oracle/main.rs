//! What the program does, pinned byte for byte: the event logs, reports and motion traces of
//! `ncchannel run` on the shipped programs and on programs that use every control-flow
//! statement, and the soak's checksums, tick counts and counters for every shipped scenario.
//!
//! A change to the code's shape (a part cut out of the decoder or the channel, a cycle shared)
//! must leave every file here as it is. A deliberate change of behaviour re-pins them with
//! `NCCHANNEL_BLESS=1 cargo test --test oracle` and says so in its commit; `git diff
//! tests/oracle/golden` then shows exactly what changed.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn golden(name: &str) -> PathBuf {
    root().join("tests/oracle/golden").join(name)
}

fn blessing() -> bool {
    std::env::var_os("NCCHANNEL_BLESS").is_some()
}

/// Compares `actual` with the golden file `name`, or rewrites it when blessing. Returns a
/// description of the difference (the first differing line) for the caller to collect.
fn check(name: &str, actual: &str) -> Option<String> {
    let path = golden(name);
    if blessing() {
        std::fs::write(&path, actual).expect("golden file written");
        return None;
    }
    let expected = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) => return Some(format!("{name}: cannot read {}: {e}", path.display())),
    };
    if expected == actual {
        return None;
    }
    let first = expected
        .lines()
        .zip(actual.lines())
        .enumerate()
        .find(|(_, (e, a))| e != a)
        .map_or_else(
            || {
                format!(
                    "lengths differ: {} lines pinned, {} now",
                    expected.lines().count(),
                    actual.lines().count()
                )
            },
            |(i, (e, a))| format!("line {}:\n  pinned: {e}\n  now:    {a}", i + 1),
        );
    Some(format!("{name} differs from the pinned file, {first}"))
}

/// Removes the keys whose values are wall-clock measurements (they differ run to run).
fn without_timings(mut v: Value, keys: &[&str]) -> Value {
    if let Value::Object(m) = &mut v {
        for k in keys {
            m.remove(*k);
        }
    }
    v
}

fn pretty(v: &Value) -> String {
    let mut s = serde_json::to_string_pretty(v).expect("JSON value");
    s.push('\n');
    s
}

/// One pinned `ncchannel run`: its name (the golden files' stem) and its arguments.
const RUNS: &[(&str, &[&str])] = &[
    ("demo", &["nc/demo.nc"]),
    ("demo_streamed", &["--stream", "nc/demo.nc"]),
    (
        "demo_streamed_small_packets",
        &["--stream", "nc/demo.nc", "--packet", "128", "--every", "2"],
    ),
    ("demo_search_n300", &["nc/demo.nc", "--search", "n:300"]),
    (
        "demo_skip_search_count",
        &["nc/demo.nc", "--skip-mask", "2", "--search", "count:40"],
    ),
    (
        "activate_stream",
        &["nc/activate_stream.nc", "--stream", "nc/goto_forward.nc"],
    ),
    ("cache_example", &["nc/cache_example.nc"]),
    (
        "commentstream_streamed",
        &["--stream", "nc/commentstream.nc"],
    ),
    ("contour_square", &["nc/contour_square.nc"]),
    ("flush_continue", &["nc/flush_continue.nc"]),
    (
        "flush_continue_streamed",
        &["--stream", "nc/flush_continue.nc"],
    ),
    ("goto_forward", &["nc/goto_forward.nc"]),
    ("streaming_spline", &["nc/streaming_spline.nc"]),
    (
        "streaming_spline_streamed",
        &[
            "--stream",
            "nc/streaming_spline.nc",
            "--packet",
            "100",
            "--every",
            "3",
        ],
    ),
    ("subroutine_call", &["nc/subroutine_call.nc"]),
    ("switchstream", &["nc/switchstream.nc"]),
    ("switchstream_streamed", &["--stream", "nc/switchstream.nc"]),
    ("flow", &["tests/oracle/programs/flow.nc"]),
    (
        "flow_skip",
        &["tests/oracle/programs/flow.nc", "--skip-mask", "2"],
    ),
    (
        "flow_streamed",
        &[
            "--stream",
            "tests/oracle/programs/flow.nc",
            "--packet",
            "100",
        ],
    ),
    ("nested_calls", &["tests/oracle/programs/nested_calls.nc"]),
    ("error_line", &["tests/oracle/programs/error_line.nc"]),
    (
        "installation_part",
        &[
            "part.nc",
            "--params",
            "params/installation/listen/hochlauf.lis",
        ],
    ),
];

/// Runs `ncchannel run ARGS` in the repository with an event log, a report and a trace, and
/// returns the three texts as pinned (the report without its wall-clock figures).
fn pinned_run(args: &[&str], dir: &Path) -> (String, String, String) {
    let events = dir.join("events.jsonl");
    let report = dir.join("report.json");
    let trace = dir.join("trace.csv");
    let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
        .current_dir(root())
        .env_remove("NCCHANNEL_PARAMS")
        .arg("run")
        .args(args)
        .args(["--max-ticks", "2000000", "--trace-every", "100"])
        .arg("--events")
        .arg(&events)
        .arg("--report")
        .arg(&report)
        .arg("--trace")
        .arg(&trace)
        .output()
        .expect("ncchannel runs");
    assert!(
        out.status.code().is_some(),
        "ncchannel run {args:?} ended by a signal: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = |p: &Path| std::fs::read_to_string(p).unwrap_or_default();
    let report_json: Value = serde_json::from_str(&read(&report)).unwrap_or(Value::Null);
    let mut report_json = without_timings(report_json, &["wall_s", "cycle"]);
    if let Value::Object(m) = &mut report_json {
        m.insert("exit_code".into(), Value::from(out.status.code()));
    }
    (read(&events), pretty(&report_json), read(&trace))
}

#[test]
fn run_event_logs_reports_and_traces_are_pinned() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut diffs = Vec::new();
    for (name, args) in RUNS {
        let (events, report, trace) = pinned_run(args, dir.path());
        assert!(
            !events.is_empty(),
            "ncchannel run {args:?} wrote no event log"
        );
        diffs.extend(check(&format!("{name}.events.jsonl"), &events));
        diffs.extend(check(&format!("{name}.report.json"), &report));
        diffs.extend(check(&format!("{name}.trace.csv"), &trace));
    }
    assert!(
        diffs.is_empty(),
        "{}\n(a deliberate change re-pins: NCCHANNEL_BLESS=1 cargo test --test oracle)",
        diffs.join("\n")
    );
}

/// Each shipped scenario, 20,000 blocks at its own seed: ticks, channel time and every
/// counter of every channel (checksum over the executed blocks included), and which
/// invariants held.
#[test]
fn soak_scenarios_are_pinned() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut diffs = Vec::new();
    for scenario in [
        "cache_churn",
        "four_channels",
        "slow_feeder",
        "stream_resets",
    ] {
        let report = dir.path().join(format!("{scenario}.json"));
        let out = Command::new(env!("CARGO_BIN_EXE_ncchannel"))
            .current_dir(root())
            .args(["soak", &format!("params/soak/{scenario}.toml")])
            .args(["--blocks", "20000", "-q", "--report"])
            .arg(&report)
            .output()
            .expect("ncchannel runs");
        assert!(
            out.status.success(),
            "soak {scenario}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = std::fs::read_to_string(&report).expect("soak report");
        let v: Value = serde_json::from_str(&text).expect("soak report JSON");
        let mut v = without_timings(
            v,
            &[
                "wall_seconds",
                "blocks_per_wall_second",
                "memory",
                "cycle",
                "scenario",
            ],
        );
        // The memory invariant's details are the process's resident set: keep its verdict.
        if let Some(Value::Array(inv)) = v.get_mut("invariants") {
            for i in inv.iter_mut() {
                if i["name"] == "memory steady" {
                    if let Value::Object(m) = i {
                        m.remove("details");
                    }
                }
            }
        }
        diffs.extend(check(&format!("soak_{scenario}.json"), &pretty(&v)));
    }
    assert!(
        diffs.is_empty(),
        "{}\n(a deliberate change re-pins: NCCHANNEL_BLESS=1 cargo test --test oracle)",
        diffs.join("\n")
    );
}
