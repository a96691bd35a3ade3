//! The end-of-run report: the `--report` JSON and the human summary printed at
//! the end of `run` and the demo.

use std::collections::BTreeMap;
use std::io::{self, Write};
use std::time::Duration;

use serde::{Deserialize, Serialize};

use crate::source::stream::StreamCounters;
use crate::vocab::stats::CycleStats;

/// How the run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The program ended normally.
    Ended,
    /// A channel error stopped it.
    Error,
    /// `--max-ticks` ran out first.
    MaxTicks,
    /// SIGINT or SIGTERM stopped it (an orderly stop).
    Stopped,
}

/// Stream interface totals.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StreamReport {
    pub writes_ok: u64,
    pub writes_rejected: u64,
    /// Bytes accepted.
    pub bytes: u64,
}

impl From<&StreamCounters> for StreamReport {
    fn from(c: &StreamCounters) -> Self {
        StreamReport {
            writes_ok: c.writes_ok,
            writes_rejected: c.writes_rejected(),
            bytes: c.bytes_written,
        }
    }
}

/// Technology functions (M, H, S, T) handed to the PLC through the HLI units.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct TechnoReport {
    /// Functions output to the PLC.
    pub output: u64,
    /// Functions acknowledged (by the PLC, or without one after their process time).
    pub acknowledged: u64,
    /// Channel time from output to acknowledgement, summed, seconds.
    pub waited_s: f64,
    /// Functions a reset dropped while output or waiting to be.
    pub dropped_by_reset: u64,
}

/// Program file accesses: what the file cache (`#CACHE`) saves.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct FilesReport {
    /// Program files opened and read from the file system (main program, uncached calls,
    /// `#CACHE LOAD`).
    pub opens: u64,
    /// Bytes those opens read.
    pub bytes_read: u64,
    /// Calls served from the file cache.
    pub cache_hits: u64,
    /// Simulated file-system latency charged (runtime.toml `fs_latency_us…`), seconds.
    pub latency_s: f64,
}

/// One channel error or warning raised during the run.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ErrorReport {
    pub code: u32,
    pub msg: String,
    /// The program and 1-based line that raised the error, when one did (absent in reports of
    /// versions before they were recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prog: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub line: Option<u64>,
}

/// Cycle statistics in microseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct CycleReport {
    pub period_us: f64,
    pub work_us_p50: f64,
    pub work_us_p99: f64,
    pub work_us_max: f64,
    /// 0 in virtual time, where ticks are never late.
    pub late_us_p99: f64,
    pub overruns: u64,
    /// Virtual time: seconds of wall time the clock stood still while the program loader read
    /// a large file (not part of the work figures; absent in older reports).
    #[serde(default)]
    pub clock_stopped_s: f64,
}

impl CycleReport {
    pub fn new(period: Duration, stats: &CycleStats) -> Self {
        CycleReport {
            period_us: period.as_secs_f64() * 1e6,
            work_us_p50: stats.work.quantile_us(0.5),
            work_us_p99: stats.work.quantile_us(0.99),
            work_us_max: stats.work.max_us(),
            late_us_p99: stats.lateness.quantile_us(0.99),
            overruns: stats.overruns,
            clock_stopped_s: stats.clock_stopped.as_secs_f64(),
        }
    }
}

/// The `--report` JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Report {
    pub outcome: Outcome,
    pub ticks: u64,
    /// Channel time in seconds (simulated in virtual time).
    pub time_s: f64,
    /// Wall-clock seconds the run took.
    pub wall_s: f64,
    /// Blocks that took effect.
    pub blocks: u64,
    /// Final axis positions in mm, by axis name (sorted, so the JSON is stable).
    pub position: BTreeMap<String, f64>,
    pub stream: StreamReport,
    /// Motion interrupts for lack of stream data.
    pub interrupts: u64,
    pub errors: Vec<ErrorReport>,
    pub cycle: CycleReport,
    /// File-system opens, bytes read and cache hits (absent in reports of versions without the file cache).
    #[serde(default)]
    pub files: FilesReport,
    /// Technology functions output and acknowledged (absent in reports of versions without
    /// the technology units).
    #[serde(default)]
    pub techno: TechnoReport,
}

impl Report {
    /// Pretty JSON, as written to the `--report` file.
    pub fn to_json_pretty(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Write the report JSON to a file (`-`: standard output).
    pub(crate) fn write_file(&self, path: &std::path::Path) -> io::Result<()> {
        let mut text = self.to_json_pretty();
        text.push('\n');
        crate::destination::write(path, text.as_bytes())
    }

    /// The human summary: outcome, blocks, simulated and wall time, interrupts, writes.
    pub fn print_human(&self, w: &mut dyn Write) -> io::Result<()> {
        let outcome = match self.outcome {
            Outcome::Ended => "program ended",
            Outcome::Error => "channel error",
            Outcome::MaxTicks => "stopped at --max-ticks",
            Outcome::Stopped => "stopped by a signal",
        };
        writeln!(w, "outcome:    {outcome}")?;
        for e in &self.errors {
            let at = match (&e.prog, e.line) {
                (Some(p), Some(l)) => format!(" ({p}, line {l})"),
                (None, Some(l)) => format!(" (line {l})"),
                (Some(p), None) => format!(" ({p})"),
                (None, None) => String::new(),
            };
            writeln!(w, "  error {}: {}{at}", e.code, e.msg)?;
        }
        writeln!(w, "blocks:     {}", self.blocks)?;
        writeln!(
            w,
            "time:       {:.3} s channel time in {} ticks, {:.3} s wall",
            self.time_s, self.ticks, self.wall_s
        )?;
        if !self.position.is_empty() {
            let pos: Vec<String> = self
                .position
                .iter()
                .map(|(axis, mm)| format!("{axis}={mm:.3}"))
                .collect();
            writeln!(w, "position:   {} mm", pos.join(" "))?;
        }
        writeln!(w, "interrupts: {}", self.interrupts)?;
        writeln!(
            w,
            "stream:     {} writes accepted, {} rejected, {} bytes",
            self.stream.writes_ok, self.stream.writes_rejected, self.stream.bytes
        )?;
        writeln!(
            w,
            "files:      {} opens, {} bytes read, {} cache hits, {:.6} s simulated latency",
            self.files.opens, self.files.bytes_read, self.files.cache_hits, self.files.latency_s
        )?;
        if self.techno.output > 0 {
            writeln!(
                w,
                "techno:     {} functions output, {} acknowledged, {:.3} s waiting for the PLC",
                self.techno.output, self.techno.acknowledged, self.techno.waited_s
            )?;
        }
        writeln!(
            w,
            "cycle:      {:.0} µs period, work p50 {:.1} µs p99 {:.1} µs max {:.1} µs, late p99 {:.1} µs, {} overruns",
            self.cycle.period_us,
            self.cycle.work_us_p50,
            self.cycle.work_us_p99,
            self.cycle.work_us_max,
            self.cycle.late_us_p99,
            self.cycle.overruns
        )?;
        if self.cycle.clock_stopped_s > 0.0 {
            writeln!(
                w,
                "loader:     the clock stood still {:.3} s while large program files were read",
                self.cycle.clock_stopped_s
            )?;
        }
        Ok(())
    }
}
