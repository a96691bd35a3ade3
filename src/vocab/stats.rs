//! Cycle statistics: bounded-memory latency histograms of tick work time and lateness.
//!
//! The histogram is `hdrhistogram` (Gil Tene's HdrHistogram, the Rust port) with two
//! significant digits from 1 ns to one hour: every recorded value is known to within 1 %
//! (a 2 µs spin_sleep lateness as well as a 40 ms hiccup) in a fixed ~36 KiB, allocated once
//! when the histogram is made, never in the tick. Longer values are counted at one hour; the
//! exact minimum and maximum are kept on the side.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use hdrhistogram::Histogram as Hdr;

/// Significant decimal digits kept: 2 (at most 1 % above the value).
const SIGNIFICANT_DIGITS: u8 = 2;
/// Largest value the buckets cover, ns (one hour); longer values count at this value.
const HIGHEST_NS: u64 = 3_600_000_000_000;

/// A latency histogram over nanoseconds with fixed memory.
#[derive(Clone)]
pub struct Histogram {
    hdr: Hdr<u64>,
    sum_ns: u128,
    min_ns: u64,
    max_ns: u64,
}

impl std::fmt::Debug for Histogram {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Histogram")
            .field("count", &self.count())
            .field("min_ns", &self.min_ns)
            .field("max_ns", &self.max_ns)
            .finish()
    }
}

impl Default for Histogram {
    fn default() -> Self {
        Self::new()
    }
}

/// The bucket layout every histogram shares, so any two can be merged.
fn empty_hdr() -> Hdr<u64> {
    // Constants inside hdrhistogram's accepted range (low ≥ 1, high ≥ 2·low, digits ≤ 5).
    Hdr::new_with_bounds(1, HIGHEST_NS, SIGNIFICANT_DIGITS)
        .expect("constant histogram bounds are valid")
}

impl Histogram {
    pub fn new() -> Self {
        Histogram {
            hdr: empty_hdr(),
            sum_ns: 0,
            min_ns: u64::MAX,
            max_ns: 0,
        }
    }

    /// Record one value in nanoseconds.
    pub fn record_ns(&mut self, ns: u64) {
        // 0 ns (a tick that took no measurable time) counts in the lowest bucket.
        self.hdr.saturating_record(ns.max(1));
        self.sum_ns += u128::from(ns);
        self.min_ns = self.min_ns.min(ns);
        self.max_ns = self.max_ns.max(ns);
    }

    /// Record `n` values of `ns` nanoseconds each (a histogram read from elsewhere, as
    /// cyclictest's per-microsecond counts).
    pub(crate) fn record_ns_n(&mut self, ns: u64, n: u64) {
        if n == 0 {
            return;
        }
        self.hdr.saturating_record_n(ns.max(1), n);
        self.sum_ns += u128::from(ns) * u128::from(n);
        self.min_ns = self.min_ns.min(ns);
        self.max_ns = self.max_ns.max(ns);
    }

    /// Record one duration (saturating at `u64::MAX` ns, 584 years).
    pub fn record(&mut self, d: Duration) {
        self.record_ns(u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
    }

    /// Add another histogram's samples to this one.
    pub(crate) fn merge(&mut self, other: &Histogram) {
        // Same layout on both sides (`empty_hdr`), so `add` has nothing to refuse; were it
        // ever to, the samples are added one bucket at a time instead of being lost.
        if self.hdr.add(&other.hdr).is_err() {
            for v in other.hdr.iter_recorded() {
                self.hdr
                    .saturating_record_n(v.value_iterated_to(), v.count_at_value());
            }
        }
        self.sum_ns += other.sum_ns;
        self.min_ns = self.min_ns.min(other.min_ns);
        self.max_ns = self.max_ns.max(other.max_ns);
    }

    pub fn count(&self) -> u64 {
        self.hdr.len()
    }

    /// Largest value recorded (exact), 0 when empty.
    pub fn max_ns(&self) -> u64 {
        self.max_ns
    }

    /// Smallest value recorded (exact), 0 when empty.
    pub fn min_ns(&self) -> u64 {
        if self.count() == 0 {
            0
        } else {
            self.min_ns
        }
    }

    /// Mean in nanoseconds, 0 when empty.
    pub fn mean_ns(&self) -> f64 {
        match self.count() {
            0 => 0.0,
            n => self.sum_ns as f64 / n as f64,
        }
    }

    /// The value at quantile `q` (0..=1): the top of the bucket that at least `q` of the
    /// samples lie at or below, capped by the exact maximum. Errs high by at most 1 %, so a
    /// reported p99 is never optimistic. 0 when empty.
    pub fn quantile_ns(&self, q: f64) -> u64 {
        if self.count() == 0 {
            return 0;
        }
        self.hdr
            .value_at_quantile(q.clamp(0.0, 1.0))
            .min(self.max_ns)
            .max(self.min_ns)
    }

    /// [`Histogram::quantile_ns`] in microseconds.
    pub fn quantile_us(&self, q: f64) -> f64 {
        self.quantile_ns(q) as f64 / 1000.0
    }

    /// The maximum in microseconds.
    pub(crate) fn max_us(&self) -> f64 {
        self.max_ns as f64 / 1000.0
    }

    /// The non-empty buckets as (largest value in the bucket in ns, count), ascending: what a
    /// plot of the distribution needs.
    pub(crate) fn buckets(&self) -> impl Iterator<Item = (u64, u64)> + '_ {
        self.hdr
            .iter_recorded()
            .map(|v| (v.value_iterated_to(), v.count_at_value()))
    }
}

/// Per-tick statistics of a run: how long the tick's work took, how late it started against
/// its ideal start, and how often the two together overran the period.
#[derive(Debug, Clone, Default)]
pub struct CycleStats {
    /// Time from the tick's start to the end of its work (requests + step).
    pub work: Histogram,
    /// Actual start minus ideal start (real time only; empty in virtual time).
    pub lateness: Histogram,
    /// Ticks whose lateness plus work exceeded the period (real time only).
    pub overruns: u64,
    /// Virtual time only: wall time the clock stood still while a tick waited for the program
    /// loader to read a large file (`source::loader`); not part of `work`.
    pub clock_stopped: Duration,
}

impl CycleStats {
    /// One line for humans: p50/p99/p99.9/max of both histograms and the overruns.
    pub(crate) fn describe(&self) -> String {
        format!(
            "work µs p50 {:.2} p99 {:.2} p99.9 {:.2} max {:.2}; lateness µs p50 {:.2} p99 {:.2} p99.9 {:.2} max {:.2}; overruns {}",
            self.work.quantile_us(0.5),
            self.work.quantile_us(0.99),
            self.work.quantile_us(0.999),
            self.work.max_us(),
            self.lateness.quantile_us(0.5),
            self.lateness.quantile_us(0.99),
            self.lateness.quantile_us(0.999),
            self.lateness.max_us(),
            self.overruns
        )
    }
}

/// The runtime's lateness and overruns as readers on other threads see them while it runs
/// (the live web view): a few relaxed atomics the tick stores into, so a reader never waits on
/// the tick nor the tick on a reader. Work times reach readers through the channel door
/// (`Status::cycle_times`); lateness is only known to the runtime.
#[derive(Debug)]
pub struct LiveCycleStats {
    /// Ticks by work time: bucket `b` counts works from `2^((b + WORK_BUCKET_FIRST) / 4)` ns
    /// (four buckets an octave, about 19 % wide; the first holds everything shorter, the last
    /// everything longer), so a reader takes quantiles over any window from two readings.
    work_buckets: [AtomicU64; WORK_BUCKETS],
    ticks: AtomicU64,
    late_last_ns: AtomicU64,
    late_max_ns: AtomicU64,
    overruns: AtomicU64,
}

impl Default for LiveCycleStats {
    fn default() -> Self {
        LiveCycleStats {
            work_buckets: std::array::from_fn(|_| AtomicU64::new(0)),
            ticks: AtomicU64::new(0),
            late_last_ns: AtomicU64::new(0),
            late_max_ns: AtomicU64::new(0),
            overruns: AtomicU64::new(0),
        }
    }
}

/// Buckets of [`LiveCycleStats`]' work histogram: 512 ns (2^9) to 32 ms (2^25).
pub const WORK_BUCKETS: usize = 64;
const WORK_BUCKET_FIRST: f64 = 36.0;

/// The work-time bucket of `ns`.
fn work_bucket(ns: u64) -> usize {
    let b = (ns.max(1) as f64).log2() * 4.0 - WORK_BUCKET_FIRST;
    // Truncation is the bucket's floor; below the first and above the last are clamped.
    (b.max(0.0) as usize).min(WORK_BUCKETS - 1)
}

/// Lower edge of work-time bucket `b`, µs.
pub fn work_bucket_floor_us(b: usize) -> f64 {
    2f64.powf((b as f64 + WORK_BUCKET_FIRST) / 4.0) / 1000.0
}

/// The `q` quantile of bucket counts (differences of two [`LiveCycleStats::work_buckets`]
/// readings), µs: the upper edge of the bucket it falls in; 0 without ticks.
pub fn work_quantile_us(counts: &[u64], q: f64) -> f64 {
    let total: u64 = counts.iter().sum();
    if total == 0 {
        return 0.0;
    }
    let rank = ((total as f64) * q).ceil().max(1.0) as u64;
    let mut seen = 0;
    for (b, &n) in counts.iter().enumerate() {
        seen += n;
        if seen >= rank {
            return work_bucket_floor_us(b + 1);
        }
    }
    work_bucket_floor_us(counts.len())
}

/// One reading of [`LiveCycleStats`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LiveCycleReading {
    pub ticks: u64,
    pub late_last: Duration,
    pub late_max: Duration,
    pub overruns: u64,
}

impl LiveCycleStats {
    /// One tick done: its work, its lateness (real time only) and whether it overran.
    pub(crate) fn publish(&self, work: Duration, late: Option<Duration>, overrun: bool) {
        let ns = u64::try_from(work.as_nanos()).unwrap_or(u64::MAX);
        if let Some(b) = self.work_buckets.get(work_bucket(ns)) {
            b.fetch_add(1, Ordering::Relaxed);
        }
        self.ticks.fetch_add(1, Ordering::Relaxed);
        if let Some(late) = late {
            let ns = u64::try_from(late.as_nanos()).unwrap_or(u64::MAX);
            self.late_last_ns.store(ns, Ordering::Relaxed);
            self.late_max_ns.fetch_max(ns, Ordering::Relaxed);
        }
        if overrun {
            self.overruns.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// The work histogram's counts since the start (see [`work_quantile_us`]).
    pub fn work_buckets(&self) -> [u64; WORK_BUCKETS] {
        std::array::from_fn(|b| self.work_buckets[b].load(Ordering::Relaxed))
    }

    pub fn read(&self) -> LiveCycleReading {
        LiveCycleReading {
            ticks: self.ticks.load(Ordering::Relaxed),
            late_last: Duration::from_nanos(self.late_last_ns.load(Ordering::Relaxed)),
            late_max: Duration::from_nanos(self.late_max_ns.load(Ordering::Relaxed)),
            overruns: self.overruns.load(Ordering::Relaxed),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_quantiles_from_work_buckets() {
        let live = LiveCycleStats::default();
        for _ in 0..99 {
            live.publish(Duration::from_micros(10), None, false);
        }
        let before = live.work_buckets();
        for _ in 0..990 {
            live.publish(Duration::from_micros(20), None, false);
        }
        for _ in 0..10 {
            live.publish(Duration::from_micros(400), None, false);
        }
        let after = live.work_buckets();
        let window: Vec<u64> = after.iter().zip(before).map(|(a, b)| a - b).collect();
        // The window holds the 20 µs and 400 µs ticks only: p50 20 µs, p99 just above it,
        // p99.9 the 400 µs ones, each within a bucket's width (19 %).
        let p50 = work_quantile_us(&window, 0.5);
        assert!((20.0..=20.0 * 1.19).contains(&p50), "{p50}");
        let p999 = work_quantile_us(&window, 0.999);
        assert!((400.0..=400.0 * 1.19).contains(&p999), "{p999}");
        assert_eq!(work_quantile_us(&[0; WORK_BUCKETS], 0.99), 0.0);
    }

    #[test]
    fn quantiles_within_resolution() {
        let mut h = Histogram::new();
        for v in 1..=10_000u64 {
            h.record_ns(v * 10);
        }
        let p50 = h.quantile_ns(0.5);
        assert!((50_000..=50_000 + 50_000 / 100).contains(&p50), "{p50}");
        let p99 = h.quantile_ns(0.99);
        assert!((99_000..=99_000 + 99_000 / 100).contains(&p99), "{p99}");
        assert_eq!(h.quantile_ns(1.0), 100_000);
        assert_eq!(h.max_ns(), 100_000);
        assert_eq!(h.min_ns(), 10);
        assert_eq!(Histogram::new().quantile_ns(0.99), 0);
    }

    #[test]
    fn small_and_huge_values_keep_their_resolution() {
        let mut h = Histogram::new();
        h.record_ns(2_000); // a 2 µs spin_sleep lateness
        h.record_ns(40_000_000); // a 40 ms hiccup
        h.record_ns(u64::MAX); // beyond an hour: counted, maximum exact
        let tops: Vec<u64> = h.buckets().map(|(top, _)| top).collect();
        assert_eq!(tops.len(), 3, "{tops:?}");
        assert!((2_000..=2_020).contains(&tops[0]), "{tops:?}");
        assert!((40_000_000..=40_400_000).contains(&tops[1]), "{tops:?}");
        assert_eq!(h.max_ns(), u64::MAX);
        assert_eq!(h.count(), 3);
    }

    #[test]
    fn merge_adds_samples() {
        let mut a = Histogram::new();
        let mut b = Histogram::new();
        a.record_ns(5);
        b.record_ns(7_000);
        a.merge(&b);
        assert_eq!(a.count(), 2);
        assert_eq!(a.max_ns(), 7_000);
        assert_eq!(a.min_ns(), 5);
    }
}
