//! The real-time mode as a user meets it: the mode's line where the system grants it, one
//! clear line per refused part where it does not (the run goes on, or exits 5 under
//! `--rt-required`), and `bench` beside cyclictest when it is installed and without it when
//! not. The thread's policy and affinity read back are the unit tests' (runtime/realtime.rs).

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn ncchannel() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_ncchannel"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::null());
    c
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status").is_ok_and(|s| {
        s.lines()
            .any(|l| l.starts_with("Uid:") && l.split_whitespace().nth(1) == Some("0"))
    })
}

fn on_path(program: &str) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|d| d.join(program))
        .find(|p| p.is_file())
}

/// The binary with `args` under a shell that takes the privileges away: RLIMIT_RTPRIO and
/// RLIMIT_MEMLOCK lowered and, for root, every capability dropped with setpriv (util-linux).
/// `None` where that cannot be done (root without setpriv).
fn unprivileged(args: &[&str]) -> Option<Output> {
    let drop_caps = if is_root() {
        on_path("setpriv")?;
        "setpriv --bounding-set=-all --inh-caps=-all "
    } else {
        ""
    };
    let script = format!("ulimit -r 0; ulimit -l 64; exec {drop_caps}\"$@\"");
    let out = Command::new("sh")
        .arg("-c")
        .arg(script)
        .arg("sh")
        .arg(env!("CARGO_BIN_EXE_ncchannel"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::null())
        .output()
        .expect("sh runs");
    Some(out)
}

const RUN_RT: [&str; 8] = [
    "run",
    "nc/demo.nc",
    "--realtime",
    "--max-ticks",
    "5",
    "--rt-priority",
    "80",
    "--rt-lock-memory",
];

#[test]
fn without_the_privilege_each_part_is_one_line_and_the_run_goes_on() {
    let Some(out) = unprivileged(&RUN_RT) else {
        eprintln!("skipped: root without setpriv cannot drop the privilege");
        return;
    };
    let stderr = text(&out.stderr);
    // --max-ticks reached: exit 3, the run went on without the mode.
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    let refused: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("ncchannel run: real-time mode: "))
        .collect();
    assert_eq!(refused.len(), 2, "{stderr}");
    assert!(
        refused[0].contains("memory lock refused") && refused[0].contains("ulimit -l"),
        "{stderr}"
    );
    assert!(
        refused[1].contains("SCHED_FIFO priority 80 refused")
            && refused[1].contains("CAP_SYS_NICE")
            && refused[1].ends_with("running at normal priority"),
        "{stderr}"
    );
}

#[test]
fn rt_required_exits_5_when_a_part_is_refused() {
    let mut args = RUN_RT.to_vec();
    args.push("--rt-required");
    let Some(out) = unprivileged(&args) else {
        eprintln!("skipped: root without setpriv cannot drop the privilege");
        return;
    };
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(5), "{stderr}");
    assert!(
        stderr.contains("ncchannel run: --rt-required: stopping, the real-time mode is incomplete"),
        "{stderr}"
    );
}

/// Where the privilege exists (root in CI) the mode's line names every part.
#[test]
fn with_the_privilege_the_mode_is_said_once() {
    let out = ncchannel()
        .args(RUN_RT)
        .args(["--rt-cpu", "0"])
        .output()
        .expect("the binary runs");
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    let granted = stderr
        .lines()
        .filter(|l| l.starts_with("real-time mode: "))
        .count();
    let refused = stderr.lines().filter(|l| l.contains("refused")).count();
    if refused == 0 {
        assert_eq!(granted, 1, "{stderr}");
        assert!(
            stderr.contains("real-time mode: memory locked, CPU 0, SCHED_FIFO 80"),
            "{stderr}"
        );
    } else {
        // No privilege here: every part said apart, the run went on.
        assert!(refused <= 3, "{stderr}");
    }
}

#[test]
fn rt_options_need_a_real_time_run() {
    let out = ncchannel()
        .args(["run", "nc/demo.nc", "--rt-priority", "80"])
        .output()
        .expect("the binary runs");
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("need --realtime"));
}

/// A folder holding only `sh`'s path and, when `fake` is set, a cyclictest that writes the
/// histogram it is asked for: 40 samples at 10 µs, one at 50 µs.
fn path_with(dir: &Path, fake: bool) -> String {
    if fake {
        let script = "#!/bin/sh\nfor a in \"$@\"; do case \"$a\" in --histfile=*) f=\"${a#--histfile=}\";; esac; done\nprintf '# Histogram\\n000010 000040\\n000050 000001\\n# Total: 000000041\\n# Max Latencies: 00050\\n# Histogram Overflows: 00000\\n' > \"$f\"\n";
        let p = dir.join("cyclictest");
        std::fs::write(&p, script).unwrap();
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    dir.display().to_string()
}

fn bench(path: &str, plot: Option<&Path>) -> (Option<i32>, String) {
    let mut c = ncchannel();
    c.args(["bench", "--seconds", "0.05", "--channels", "1"])
        .env("PATH", path);
    if let Some(p) = plot {
        c.arg("--plot").arg(p);
    }
    let out = c.output().expect("the binary runs");
    (out.status.code(), text(&out.stdout) + &text(&out.stderr))
}

#[test]
fn bench_without_cyclictest_says_how_to_install_it() {
    let dir = tempfile::tempdir().unwrap();
    let (code, out) = bench(&path_with(dir.path(), false), None);
    assert_eq!(code, Some(0), "{out}");
    assert!(
        out.contains(
            "cyclictest not found: install rt-tests (Debian/Ubuntu: apt-get install rt-tests"
        ),
        "{out}"
    );
    assert!(!out.contains("runtime / cyclictest"), "{out}");
    assert!(
        out.contains("lateness ratio runtime / bare loop: p99"),
        "{out}"
    );
    // The warm figure runs the same ticks back to back: as many ticks as the real-time one.
    let ticks = |name: &str| {
        out.lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.rsplit_once("(n = "))
            .map(|(_, n)| n.trim_end_matches(')').to_string())
            .unwrap_or_else(|| panic!("no {name:?} line: {out}"))
    };
    assert_eq!(ticks("tick work   "), ticks("tick work, warm"), "{out}");
    assert_eq!(ticks("tick work, warm"), "50", "{out}");
}

#[test]
fn bench_with_cyclictest_prints_the_ratio_and_plots_its_histogram() {
    let dir = tempfile::tempdir().unwrap();
    let plot = dir.path().join("lateness.svg");
    let (code, out) = bench(&path_with(dir.path(), true), Some(&plot));
    assert_eq!(code, Some(0), "{out}");
    let line = out
        .lines()
        .find(|l| l.starts_with("cyclictest latency"))
        .unwrap_or_else(|| panic!("{out}"));
    assert!(
        line.contains("max     50.00") && line.ends_with("(n = 41)"),
        "{line}"
    );
    assert!(
        out.contains("lateness ratio runtime / cyclictest: p99 "),
        "{out}"
    );
    assert!(!out.contains("cyclictest not found"), "{out}");
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(
        svg.contains("cyclictest p99"),
        "the plot shows cyclictest's histogram"
    );
}
