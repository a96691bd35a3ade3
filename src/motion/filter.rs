//! Axis filter: two moving averages in series over the interpolated axis positions — the corner
//! filter (spreads the velocity jumps at block junctions over `corner_smoothing`) and the jerk
//! filter (turns the acceleration-limited profile into a jerk-limited one).
//!
//! Why a filter after interpolation. A moving average of length T over positions is also a
//! moving average over their finite differences: the filtered velocity and acceleration of
//! every axis are means of the unfiltered ones, so they never exceed them, and the filtered
//! jerk is (a(t) − a(t − T)) / T, at most (max a − min a) / T. With the acceleration in
//! [−A, A] a window T = 2·A / J bounds every axis' jerk by J on every tick, whatever the
//! geometry. This is the axis-wise jerk limitation of post-interpolation smoothing ("FIR jerk
//! filter", e.g. SINUMERIK MD32402 `AX_JERK_MODE` = 2 "filter", FANUC "acceleration/
//! deceleration after interpolation"); its price is a lag of T and rounded corners (the path
//! seen through the window), which docs/motion.md quantifies.
//!
//! Rounding. The window's sum is kept relative to a nearby origin and recomputed exactly once
//! per turn of the window, so nothing drifts; once the window holds one position only, the
//! output is that position exactly, so programmed end points are reached exactly.

use crate::vocab::axis::{Position, MAX_AXES};

/// Longest window, ticks (bounds memory and tick work whatever the limits say).
pub(crate) const MAX_WINDOW_TICKS: usize = 4096;

/// One moving average: the last `len` inputs.
#[derive(Debug, Clone)]
struct Stage {
    ring: Vec<Position>,
    /// Index of the oldest entry (next to be replaced).
    head: usize,
    /// Consecutive pushes equal to the newest input (≥ len: settled).
    same: usize,
    /// Σ (entry − origin) over the ring; recomputed exactly once per turn of the ring.
    sum: Position,
    /// Reference the sum is kept relative to (small terms, small rounding).
    origin: Position,
    out: Position,
    /// 1 / the ring's length, the mean's factor (a division once, not every tick).
    inv_len: f64,
}

impl Stage {
    fn new(len: usize, p: Position) -> Self {
        let len = len.clamp(1, MAX_WINDOW_TICKS);
        Stage {
            ring: vec![p; len],
            head: 0,
            same: usize::MAX,
            sum: [0.0; MAX_AXES],
            origin: p,
            out: p,
            inv_len: 1.0 / len as f64,
        }
    }

    fn len(&self) -> usize {
        self.ring.len()
    }

    fn settled(&self) -> bool {
        self.same >= self.ring.len()
    }

    fn push(&mut self, p: Position) -> Position {
        let n = self.ring.len();
        if n == 1 {
            self.ring[0] = p;
            self.out = p;
            return p;
        }
        // The ring's indices wrap by a compare, not `%`: an integer division each was a few
        // percent of a soak's tick (perf).
        let newest = if self.head == 0 { n - 1 } else { self.head - 1 };
        if self.ring[newest] == p {
            self.same = self.same.saturating_add(1);
        } else {
            self.same = 1;
        }
        let old = self.ring[self.head];
        self.ring[self.head] = p;
        self.head = if self.head + 1 == n { 0 } else { self.head + 1 };
        if self.settled() {
            // Every entry is p: the sum relative to p is exactly 0. Keeping the old sum would
            // leave out this push's update, an offset the first output after rest carries.
            self.origin = p;
            self.sum = [0.0; MAX_AXES];
            self.out = p;
            return p;
        }
        if self.head == 0 {
            // Once per turn: the sum afresh, relative to the newest input (no drift).
            self.origin = p;
            for i in 0..MAX_AXES {
                self.sum[i] = self.ring.iter().map(|q| q[i] - p[i]).sum();
            }
        } else {
            for i in 0..MAX_AXES {
                self.sum[i] += (p[i] - self.origin[i]) - (old[i] - self.origin[i]);
            }
        }
        let inv = self.inv_len;
        let mut out = p;
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.origin[i] + self.sum[i] * inv;
        }
        self.out = out;
        out
    }
}

/// The corner filter followed by the jerk filter.
#[derive(Debug, Clone)]
pub(crate) struct AxisFilter {
    /// Corner smoothing window, s (0 = off).
    corner_s: f64,
    /// Jerk window, s (0 = off): 2·aᵢ / jᵢ, the largest over the axes with a jerk limit.
    jerk_s: f64,
    /// Tick length the stage lengths were made for, s.
    dt_s: f64,
    corner: Stage,
    jerk: Stage,
}

impl AxisFilter {
    pub(crate) fn new(corner_s: f64, jerk_s: f64, p: Position) -> Self {
        let ok = |t: f64| if t.is_finite() { t.max(0.0) } else { 0.0 };
        AxisFilter {
            corner_s: ok(corner_s),
            jerk_s: ok(jerk_s),
            dt_s: 0.0,
            corner: Stage::new(1, p),
            jerk: Stage::new(1, p),
        }
    }

    /// Window in ticks for `t_s` at `dt_s`: at least `t_s` long (so the bound holds).
    pub(crate) fn ticks(t_s: f64, dt_s: f64) -> usize {
        if t_s <= 0.0 || dt_s <= 0.0 {
            return 1;
        }
        ((t_s / dt_s - 1e-9).ceil() as usize).clamp(1, MAX_WINDOW_TICKS)
    }

    /// Size the windows for tick length `dt_s`; a change refills them with the current output
    /// (only the first tick or a changed cycle period does this).
    pub(crate) fn configure(&mut self, dt_s: f64) {
        if dt_s <= 0.0 || dt_s == self.dt_s {
            return;
        }
        self.dt_s = dt_s;
        let (nc, nj) = (
            Self::ticks(self.corner_s, dt_s),
            Self::ticks(self.jerk_s, dt_s),
        );
        if nc != self.corner.len() || nj != self.jerk.len() {
            let p = self.jerk.out;
            self.corner = Stage::new(nc, p);
            self.jerk = Stage::new(nj, p);
        }
    }

    /// The windows for tick length `dt_s` with the configured corner and jerk times, ticks.
    pub(crate) fn general_ticks(&self, dt_s: f64) -> (usize, usize) {
        (
            Self::ticks(self.corner_s, dt_s),
            Self::ticks(self.jerk_s, dt_s),
        )
    }

    /// Use windows of `corner_ticks` and `jerk_ticks` from now on. Only while settled: the
    /// output then equals the input, so refilling the windows with it moves nothing and the
    /// new windows start from rest. Returns whether the windows are the ones asked for.
    pub(crate) fn use_windows(&mut self, corner_ticks: usize, jerk_ticks: usize) -> bool {
        let (nc, nj) = (
            corner_ticks.clamp(1, MAX_WINDOW_TICKS),
            jerk_ticks.clamp(1, MAX_WINDOW_TICKS),
        );
        if nc == self.corner.len() && nj == self.jerk.len() {
            return true;
        }
        if !self.settled() {
            return false;
        }
        let p = self.jerk.out;
        self.corner = Stage::new(nc, p);
        self.jerk = Stage::new(nj, p);
        true
    }

    /// Corner window actually used, s (whole ticks).
    pub(crate) fn corner_window_s(&self) -> f64 {
        self.corner.len() as f64 * self.dt_s
    }

    /// Both windows, s: the lag of a stop and the time the output takes to settle.
    pub fn total_window_s(&self) -> f64 {
        (self.corner.len() + self.jerk.len()) as f64 * self.dt_s
    }

    /// One tick's interpolated position in, the filtered position out.
    pub(crate) fn push(&mut self, p: Position) -> Position {
        let c = self.corner.push(p);
        self.jerk.push(c)
    }

    /// The output equals the last input: the axes stand where the interpolator stands.
    pub(crate) fn settled(&self) -> bool {
        self.corner.settled() && self.jerk.settled()
    }

    /// Stop at once at `p` (reset, start-up position).
    pub(crate) fn fill(&mut self, p: Position) {
        let (nc, nj) = (self.corner.len(), self.jerk.len());
        self.corner = Stage::new(nc, p);
        self.jerk = Stage::new(nj, p);
    }

    /// Filtering does anything at all (with the windows now in use).
    pub(crate) fn active(&self) -> bool {
        self.corner.len() > 1 || self.jerk.len() > 1
    }
}

/// Jerk window for these axes, s: max over axes with a jerk limit of 2·aᵢ / jᵢ (0 if none).
pub(crate) fn jerk_window_s(axes: &[super::AxisLimits]) -> f64 {
    axes.iter()
        .filter_map(|a| {
            let j = a.max_jerk_mm_per_s3?;
            (j.is_finite() && j > 0.0).then(|| 2.0 * a.max_accel_mm_per_s2.max(0.0) / j)
        })
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean of the last `n` inputs, the ring starting full of `start`.
    fn naive_means(n: usize, start: f64, inputs: &[f64]) -> Vec<f64> {
        let mut all = vec![start; n];
        all.extend_from_slice(inputs);
        (0..inputs.len())
            .map(|k| all[k + 1..k + 1 + n].iter().sum::<f64>() / n as f64)
            .collect()
    }

    #[test]
    fn leaving_rest_after_settling_starts_from_the_exact_mean() {
        // Move, stand long enough to settle, move again: every output is the plain mean of
        // the window. (The settled pushes once skipped the running sum's update, so the first
        // output after rest was off by one update.)
        let n = 5;
        // Every length of rest, so the departure falls at every place of the ring.
        for hold in n..3 * n {
            let mut inputs: Vec<f64> = (1..=7).map(|k| k as f64 * 0.3).collect();
            inputs.extend(std::iter::repeat_n(2.1, hold));
            inputs.extend((1..=9).map(|k| 2.1 - k as f64 * 0.7));
            let mut st = Stage::new(n, [0.0; MAX_AXES]);
            let want = naive_means(n, 0.0, &inputs);
            for (k, (&x, &w)) in inputs.iter().zip(&want).enumerate() {
                let got = st.push([x, 0.0, 0.0, 0.0, 0.0, 0.0])[0];
                assert!(
                    (got - w).abs() < 1e-12,
                    "rest {hold}, push {k}: {got} against the mean {w}"
                );
            }
        }
    }

    #[test]
    fn a_step_becomes_a_ramp_and_settles_exactly() {
        let mut f = AxisFilter::new(0.0, 0.004, [0.0; MAX_AXES]);
        f.configure(0.001);
        let mut p = [0.0; MAX_AXES];
        p[0] = 1.0;
        let outs: Vec<f64> = (0..6).map(|_| f.push(p)[0]).collect();
        assert_eq!(outs, vec![0.25, 0.5, 0.75, 1.0, 1.0, 1.0]);
        assert!(f.settled());
    }
}
