//! Cycle statistics: bounded-memory latency histograms of tick work time and lateness.
//!
//! The histogram is log-linear (the HDR idea): values below 128 ns get one bucket per
//! nanosecond, above that every power of two is split into 64 buckets, so any recorded value
//! is known to within 1/64 (1.6 %) over the whole `u64` nanosecond range in 3 776 buckets
//! (30 KiB). That resolves a 2 µs spin_sleep lateness as well as a 40 ms hiccup, which a
//! 1 µs-bucket linear table would not; the exact maximum and minimum are kept on the side.

use std::time::Duration;

/// Buckets per power of two above the linear range.
const SUB_BUCKETS: u64 = 64;
const SUB_BITS: u32 = 6;
/// Values below this get one bucket each.
const LINEAR_LIMIT: u64 = 2 * SUB_BUCKETS;
/// Total buckets: the linear range plus 64 per remaining power of two up to 2^64.
const BUCKETS: usize = (LINEAR_LIMIT + (64 - (SUB_BITS as u64 + 1)) * SUB_BUCKETS) as usize;

/// A latency histogram over nanoseconds with fixed memory.
#[derive(Clone)]
pub struct Histogram {
    counts: Box<[u64]>,
    count: u64,
    sum_ns: u128,
    min_ns: u64,
    max_ns: u64,
}

impl std::fmt::Debug for Histogram {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Histogram")
            .field("count", &self.count)
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

fn bucket_of(v: u64) -> usize {
    if v < LINEAR_LIMIT {
        return v as usize;
    }
    // v >= 128: top bit position b >= 7; keep the 6 bits below it.
    let b = 63 - v.leading_zeros();
    let shift = b - SUB_BITS;
    let mantissa = (v >> shift) - SUB_BUCKETS; // 0..64
    (LINEAR_LIMIT + (u64::from(shift) - 1) * SUB_BUCKETS + mantissa) as usize
}

/// The largest value that lands in bucket `i`.
fn bucket_high(i: usize) -> u64 {
    let i = i as u64;
    if i < LINEAR_LIMIT {
        return i;
    }
    let k = i - LINEAR_LIMIT;
    let shift = k / SUB_BUCKETS + 1;
    let mantissa = k % SUB_BUCKETS + SUB_BUCKETS;
    // Saturate at the very top of the range.
    (((mantissa + 1) as u128) << shift)
        .saturating_sub(1)
        .min(u64::MAX as u128) as u64
}

impl Histogram {
    pub fn new() -> Self {
        Histogram {
            counts: vec![0; BUCKETS].into_boxed_slice(),
            count: 0,
            sum_ns: 0,
            min_ns: u64::MAX,
            max_ns: 0,
        }
    }

    /// Record one value in nanoseconds.
    pub fn record_ns(&mut self, ns: u64) {
        self.counts[bucket_of(ns)] += 1;
        self.count += 1;
        self.sum_ns += u128::from(ns);
        self.min_ns = self.min_ns.min(ns);
        self.max_ns = self.max_ns.max(ns);
    }

    /// Record one duration (saturating at `u64::MAX` ns, 584 years).
    pub fn record(&mut self, d: Duration) {
        self.record_ns(u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
    }

    /// Add another histogram's samples to this one.
    pub fn merge(&mut self, other: &Histogram) {
        for (a, b) in self.counts.iter_mut().zip(other.counts.iter()) {
            *a += *b;
        }
        self.count += other.count;
        self.sum_ns += other.sum_ns;
        self.min_ns = self.min_ns.min(other.min_ns);
        self.max_ns = self.max_ns.max(other.max_ns);
    }

    pub fn count(&self) -> u64 {
        self.count
    }

    /// Largest value recorded (exact), 0 when empty.
    pub fn max_ns(&self) -> u64 {
        self.max_ns
    }

    /// Smallest value recorded (exact), 0 when empty.
    pub fn min_ns(&self) -> u64 {
        if self.count == 0 {
            0
        } else {
            self.min_ns
        }
    }

    /// Mean in nanoseconds, 0 when empty.
    pub fn mean_ns(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.sum_ns as f64 / self.count as f64
        }
    }

    /// The value at quantile `q` (0..=1): the smallest bucket top that at least `q` of the
    /// samples lie at or below, capped by the exact maximum. Errs high by at most 1/64, so a
    /// reported p99 is never optimistic. 0 when empty.
    pub fn quantile_ns(&self, q: f64) -> u64 {
        if self.count == 0 {
            return 0;
        }
        let rank = ((q.clamp(0.0, 1.0) * self.count as f64).ceil() as u64).max(1);
        let mut seen = 0;
        for (i, &c) in self.counts.iter().enumerate() {
            seen += c;
            if seen >= rank {
                return bucket_high(i).min(self.max_ns).max(self.min_ns);
            }
        }
        self.max_ns
    }

    /// [`Histogram::quantile_ns`] in microseconds.
    pub fn quantile_us(&self, q: f64) -> f64 {
        self.quantile_ns(q) as f64 / 1000.0
    }

    /// The maximum in microseconds.
    pub fn max_us(&self) -> f64 {
        self.max_ns as f64 / 1000.0
    }

    /// The non-empty buckets as (largest value in the bucket in ns, count), ascending: what a
    /// plot of the distribution needs.
    pub fn buckets(&self) -> impl Iterator<Item = (u64, u64)> + '_ {
        self.counts
            .iter()
            .enumerate()
            .filter(|(_, &c)| c > 0)
            .map(|(i, &c)| (bucket_high(i), c))
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
}

impl CycleStats {
    /// One line for humans: p50/p99/p99.9/max of both histograms and the overruns.
    pub fn describe(&self) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_are_monotonic_and_contain_their_values() {
        let mut last = 0;
        for v in (0..5000u64).chain([1 << 20, (1 << 40) + 12345, u64::MAX]) {
            let b = bucket_of(v);
            assert!(b < BUCKETS, "{v} -> {b}");
            assert!(b >= last, "bucket index falls at {v}");
            last = b;
            assert!(
                bucket_high(b) >= v,
                "{v} above its bucket top {}",
                bucket_high(b)
            );
            if b > 0 {
                assert!(bucket_high(b - 1) < v, "{v} in the wrong bucket");
            }
        }
        assert_eq!(bucket_of(u64::MAX), BUCKETS - 1);
    }

    #[test]
    fn quantiles_within_resolution() {
        let mut h = Histogram::new();
        for v in 1..=10_000u64 {
            h.record_ns(v * 10);
        }
        let p50 = h.quantile_ns(0.5);
        assert!((50_000..=50_000 + 50_000 / 64).contains(&p50), "{p50}");
        let p99 = h.quantile_ns(0.99);
        assert!((99_000..=99_000 + 99_000 / 64).contains(&p99), "{p99}");
        assert_eq!(h.quantile_ns(1.0), 100_000);
        assert_eq!(h.max_ns(), 100_000);
        assert_eq!(h.min_ns(), 10);
        assert_eq!(Histogram::new().quantile_ns(0.99), 0);
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
