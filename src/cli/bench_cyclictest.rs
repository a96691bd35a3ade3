//! `bench`'s reference for the machine's timer latency: `cyclictest` of rt-tests, Linux's own
//! measure of how late a thread wakes for an absolute deadline (rt-tests' cyclictest(8)
//! manual page), run between the bench's own slices at the same period, policy, priority, CPU
//! and memory lock as the runtime thread.
//!
//! Each slice runs `cyclictest -q -l LOOPS -i PERIOD -h MAX --histfile FILE` and reads the
//! histogram back: one line `LATENCY_US COUNT` per microsecond, then `# Max Latencies:` and
//! `# Histogram Overflows:` (the samples above MAX).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::runtime::realtime::RealtimeConfig;
use crate::vocab::stats::Histogram;

/// The histogram's range, µs: 10 ms, ten periods of the usual 1 ms cycle. Later samples are
/// counted as overflows and recorded at this value, the exact maximum beside.
const HISTOGRAM_MAX_US: u64 = 10_000;

/// The command to install cyclictest, said when it is missing.
pub(super) const INSTALL_HINT: &str =
    "cyclictest not found: install rt-tests (Debian/Ubuntu: apt-get install rt-tests; Fedora: dnf install realtime-tests) for the ratio to the machine's timer latency";

/// cyclictest on the PATH, if installed.
pub(super) fn find() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("cyclictest"))
        .find(|p| is_executable(p))
}

fn is_executable(p: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        p.metadata()
            .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
    }
    #[cfg(not(unix))]
    {
        p.is_file()
    }
}

/// The arguments of one slice: `loops` wake-ups `period_us` apart, under the real-time mode
/// that applies to the runtime thread (`mode`, its refused parts left out).
pub(super) fn args(period_us: u64, loops: u64, mode: &RealtimeConfig, hist: &Path) -> Vec<String> {
    let mut a = vec![
        "-q".to_string(),
        format!("-l{loops}"),
        format!("-i{period_us}"),
        format!("-h{HISTOGRAM_MAX_US}"),
        format!("--histfile={}", hist.display()),
    ];
    match mode.priority {
        Some(p) => {
            a.push(format!("--policy={}", mode.policy.cyclictest_name()));
            a.push(format!("-p{p}"));
        }
        None => {
            a.push("--policy=other".into());
            a.push("-p0".into());
        }
    }
    if let Some(cpu) = mode.cpu {
        a.push(format!("-a{cpu}"));
    }
    if mode.lock_memory {
        a.push("-m".into());
    }
    a
}

/// Run one slice and add its samples to `into`.
pub(super) fn run_slice(
    program: &Path,
    period_us: u64,
    loops: u64,
    mode: &RealtimeConfig,
    into: &mut Histogram,
) -> Result<(), String> {
    let dir = tempfile::tempdir().map_err(|e| format!("cyclictest: a temporary folder: {e}"))?;
    let hist = dir.path().join("histogram.txt");
    let out = Command::new(program)
        .args(args(period_us, loops, mode, &hist))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .map_err(|e| format!("{}: {e}", program.display()))?;
    if !out.status.success() {
        let why = String::from_utf8_lossy(&out.stderr);
        return Err(format!(
            "{} ended {}: {}",
            program.display(),
            out.status,
            why.trim()
        ));
    }
    let text = crate::bounded::read_file(&hist, 16 * HISTOGRAM_MAX_US * 16)
        .map_err(|e| format!("cyclictest's histogram: {e}"))?;
    parse_histogram(&String::from_utf8_lossy(&text), into)
}

/// Read a cyclictest histogram file into `into` (µs buckets as ns).
pub(super) fn parse_histogram(text: &str, into: &mut Histogram) -> Result<(), String> {
    let mut max_us = None;
    let mut overflows = 0u64;
    let mut samples = 0u64;
    for line in text.lines() {
        if let Some(v) = line.strip_prefix("# Max Latencies:") {
            max_us = v
                .split_whitespace()
                .next()
                .and_then(|n| n.parse::<u64>().ok());
        } else if let Some(v) = line.strip_prefix("# Histogram Overflows:") {
            overflows = v
                .split_whitespace()
                .next()
                .and_then(|n| n.parse().ok())
                .unwrap_or(0);
        } else if !line.starts_with('#') {
            let mut f = line.split_whitespace().map(str::parse::<u64>);
            if let (Some(Ok(us)), Some(Ok(n)), None) = (f.next(), f.next(), f.next()) {
                if n > 0 {
                    into.record_ns_n(us.saturating_mul(1000), n);
                    samples += n;
                }
            }
        }
    }
    if overflows > 0 {
        into.record_ns_n(HISTOGRAM_MAX_US * 1000, overflows - 1);
        into.record_ns(max_us.unwrap_or(HISTOGRAM_MAX_US).saturating_mul(1000));
        samples += overflows;
    }
    if samples == 0 {
        return Err("cyclictest's histogram holds no sample".into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runtime::realtime::Policy;

    #[test]
    fn histogram_lines_overflows_and_maximum_are_read() {
        let text = "# Histogram\n000000 000000\n000012 000003\n000020 000001\n# Total: 000000006\n# Min Latencies: 00012\n# Avg Latencies: 00048\n# Max Latencies: 12345\n# Histogram Overflows: 00002\n# Histogram Overflow at cycle number:\n# Thread 0: 00003 00004\n";
        let mut h = Histogram::new();
        parse_histogram(text, &mut h).unwrap();
        assert_eq!(h.count(), 6);
        assert_eq!(h.min_ns(), 12_000);
        assert_eq!(h.max_ns(), 12_345_000);
        assert!(parse_histogram("# Histogram\n", &mut Histogram::new()).is_err());
    }

    #[test]
    fn the_slice_runs_under_the_runtimes_mode() {
        let hist = Path::new("/tmp/h.txt");
        let mode = RealtimeConfig {
            policy: Policy::Fifo,
            priority: Some(80),
            cpu: Some(1),
            lock_memory: true,
            required: false,
        };
        assert_eq!(
            args(1000, 500, &mode, hist).join(" "),
            "-q -l500 -i1000 -h10000 --histfile=/tmp/h.txt --policy=fifo -p80 -a1 -m"
        );
        assert_eq!(
            args(250, 4, &RealtimeConfig::default(), hist).join(" "),
            "-q -l4 -i250 -h10000 --histfile=/tmp/h.txt --policy=other -p0"
        );
    }
}
