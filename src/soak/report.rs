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

#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SoakReport {
    pub scenario: String,
    pub seed: u64,
    pub(crate) clock: String,
    pub ticks: u64,
    pub(crate) sim_seconds: f64,
    pub(crate) wall_seconds: f64,
    pub blocks: u64,
    pub(crate) blocks_per_wall_second: f64,
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
        writeln!(
            w,
            "result:    {}",
            if self.all_held {
                "every invariant held"
            } else {
                "an invariant was violated"
            }
        )
    }
}
