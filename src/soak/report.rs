//! The soak's final report, of `ncchannel soak` and `serve --soak` alike: JSON for machines
//! (`--report FILE`, read back by `soak merge`), a summary for people.

use std::io::{self, Write};

use serde::{Deserialize, Serialize};

use super::driver::SoakCounters;
use super::invariants::Verdict;
use crate::vocab::stats::{CycleStats, Histogram};

/// Percentiles of one histogram, µs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Percentiles {
    pub(crate) p50_us: f64,
    pub(crate) p99_us: f64,
    pub(crate) p999_us: f64,
    pub(crate) max_us: f64,
    pub count: u64,
}

impl From<&Histogram> for Percentiles {
    fn from(h: &Histogram) -> Self {
        Percentiles {
            p50_us: h.quantile_us(0.5),
            p99_us: h.quantile_us(0.99),
            p999_us: h.quantile_us(0.999),
            max_us: h.max_us(),
            count: h.count(),
        }
    }
}

#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CycleFigures {
    pub period_us: f64,
    pub work: Percentiles,
    /// Empty in virtual time, where ticks are never late.
    pub lateness: Percentiles,
    pub overruns: u64,
}

impl CycleFigures {
    pub fn new(period_us: f64, s: &CycleStats) -> Self {
        CycleFigures {
            period_us,
            work: Percentiles::from(&s.work),
            lateness: Percentiles::from(&s.lateness),
            overruns: s.overruns,
        }
    }
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct MemoryReport {
    /// Resident set after warm-up, KiB (`None` without /proc).
    pub(crate) warmup_kib: Option<u64>,
    pub(crate) end_kib: Option<u64>,
    pub(crate) growth_kib: Option<i64>,
}

/// Whether a report covers what it set out to: a run that ran to its length, one a signal
/// stopped before, or the placeholder a run writes at its start (so that a run killed before
/// it could write its report leaves this, never the previous run's report).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RunStatus {
    /// The run (every run of a campaign shard) ran to its length.
    #[default]
    Complete,
    /// SIGINT or SIGTERM stopped it; the report covers what ran until then.
    Interrupted,
    /// Written when the run started: it never finished (killed, or still running).
    Incomplete,
}

impl RunStatus {
    /// The verdict line's word for a report that is not complete ("" for a complete one).
    pub(crate) fn verdict_prefix(self) -> &'static str {
        match self {
            RunStatus::Complete => "",
            RunStatus::Interrupted => "INTERRUPTED, ",
            RunStatus::Incomplete => "INCOMPLETE, ",
        }
    }
}

#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SoakReport {
    /// Complete, interrupted by a signal, or the placeholder of a run that never finished.
    pub status: RunStatus,
    pub scenario: String,
    pub seed: u64,
    pub(crate) clock: String,
    pub ticks: u64,
    pub(crate) sim_seconds: f64,
    pub(crate) wall_seconds: f64,
    pub blocks: u64,
    pub(crate) blocks_per_wall_second: f64,
    /// The run completed and every invariant held (false for an interrupted run whatever its
    /// invariants say, so that a reader of this field alone never takes it for a pass).
    pub all_held: bool,
    pub invariants: Vec<Verdict>,
    pub channels: Vec<SoakCounters>,
    pub memory: MemoryReport,
    pub cycle: CycleFigures,
}

/// What a run was and how long it took.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RunFigures {
    pub seed: u64,
    pub(crate) realtime: bool,
    pub ticks: u64,
    pub(crate) sim_seconds: f64,
    pub(crate) wall_seconds: f64,
    /// Stream blocks checked, all channels.
    pub blocks: u64,
}

impl SoakReport {
    /// The report of a run of `scenario` (`ncchannel soak` and `serve --soak` alike).
    pub fn new(
        scenario: &std::path::Path,
        run: RunFigures,
        invariants: Vec<Verdict>,
        channels: Vec<SoakCounters>,
        memory: MemoryReport,
        cycle: CycleFigures,
    ) -> Self {
        SoakReport {
            status: RunStatus::Complete,
            scenario: scenario.display().to_string(),
            seed: run.seed,
            clock: if run.realtime { "real" } else { "virtual" }.into(),
            ticks: run.ticks,
            sim_seconds: run.sim_seconds,
            wall_seconds: run.wall_seconds,
            blocks: run.blocks,
            blocks_per_wall_second: run.blocks as f64 / run.wall_seconds.max(1e-9),
            all_held: invariants.iter().all(|v| v.held),
            invariants,
            channels,
            memory,
            cycle,
        }
    }

    /// The placeholder a run of `scenario` with `seed` writes to its report file when it
    /// starts: incomplete, not held, until the finished report replaces it.
    pub fn incomplete(scenario: &std::path::Path, seed: u64) -> Self {
        SoakReport {
            status: RunStatus::Incomplete,
            scenario: scenario.display().to_string(),
            seed,
            all_held: false,
            ..SoakReport::default()
        }
    }

    /// Mark the report of a run a signal stopped: interrupted, and not a pass.
    pub(crate) fn interrupted(mut self) -> Self {
        self.status = RunStatus::Interrupted;
        self.all_held = false;
        self
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"))
    }

    pub fn print_human(&self, w: &mut dyn Write) -> io::Result<()> {
        writeln!(
            w,
            "soak {} (seed {}, {} time)",
            self.scenario, self.seed, self.clock
        )?;
        writeln!(
            w,
            "run:       {} blocks in {} ticks, {:.3} s channel time, {:.2} s wall ({:.0} blocks/s)",
            self.blocks,
            self.ticks,
            self.sim_seconds,
            self.wall_seconds,
            self.blocks_per_wall_second
        )?;
        for c in &self.channels {
            let errors: Vec<String> = c.errors.iter().map(|(k, v)| format!("{k}×{v}")).collect();
            writeln!(
                w,
                "channel {}: {} blocks, {} resets ({} after errors), {} restarts, {} holds, {} overrides, {} forced rejections",
                c.number, c.blocks, c.resets, c.error_resets, c.restarts, c.holds, c.overrides, c.forced_rejections
            )?;
            writeln!(
                w,
                "           writes {} ok / {} rejected / {} skipped, {} bytes, {} lines accepted{}, {} pauses, {} interrupts, {} warnings, errors [{}], checksum {}",
                c.writes_ok, c.writes_rejected, c.writes_skipped, c.bytes, c.lines_accepted,
                // Counted for external clients (`serve --soak`) only.
                if c.lines_dropped > 0 { format!(" ({} dropped unexecuted by resets)", c.lines_dropped) } else { String::new() },
                c.pauses, c.interrupts, c.warnings, errors.join(" "), c.checksum
            )?;
        }
        let kib = |v: Option<u64>| v.map_or("n/a".to_string(), |k| format!("{k} KiB"));
        writeln!(
            w,
            "memory:    resident {} after warm-up, {} at the end ({} KiB growth)",
            kib(self.memory.warmup_kib),
            kib(self.memory.end_kib),
            self.memory
                .growth_kib
                .map_or("n/a".into(), |g| g.to_string())
        )?;
        let c = &self.cycle;
        writeln!(
            w,
            "cycle:     {} µs period, work p50 {:.1} p99 {:.1} p99.9 {:.1} max {:.1} µs; late p99 {:.1} max {:.1} µs; {} overruns",
            c.period_us, c.work.p50_us, c.work.p99_us, c.work.p999_us, c.work.max_us, c.lateness.p99_us, c.lateness.max_us, c.overruns
        )?;
        for v in &self.invariants {
            let mark = if v.held { "held    " } else { "VIOLATED" };
            writeln!(w, "{mark}  {} ({} violations)", v.name, v.violations)?;
            for d in &v.details {
                writeln!(w, "          {d}")?;
            }
        }
        // `all_held` is false for a run that did not complete; the verdict line still says
        // whether the invariants held as far as it ran.
        let held = self.invariants.iter().all(|v| v.held);
        let verdict = match (self.status, held) {
            (RunStatus::Complete, _) if self.all_held => "every invariant held",
            (RunStatus::Interrupted, true) => "every invariant held so far",
            (RunStatus::Incomplete, _) => "no verdict (the run never finished)",
            _ => "an invariant was violated",
        };
        writeln!(w, "result:    {}{verdict}", self.status.verdict_prefix())
    }
}
