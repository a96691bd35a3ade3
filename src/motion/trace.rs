//! Trace: per-tick samples of position and path velocity kept for `--plot`, decimated so a long
//! run never holds more than a fixed number of points.

use crate::queue::{Plane, Position};

/// One recorded tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Channel time since the motion was created, s.
    pub time_s: f64,
    pub pos: Position,
    /// Path velocity over the tick, mm/s.
    pub velocity_mm_per_s: f64,
    /// Path acceleration (change of the path velocity), mm/s².
    pub accel_mm_per_s2: f64,
    /// Path jerk, mm/s³.
    pub jerk_mm_per_s3: f64,
}

/// Samples at a stride that doubles whenever the buffer fills; interrupts are kept apart and
/// never decimated (bounded by their own cap).
#[derive(Debug, Clone)]
pub struct Trace {
    samples: Vec<Sample>,
    max_samples: usize,
    /// Record every `stride`-th tick.
    stride: u64,
    ticks: u64,
    interrupts: Vec<Sample>,
    /// Working plane of the last arc, the plane the plot draws (G17 until an arc says else).
    plane: Plane,
}

/// Interrupt marks kept at most.
pub const MAX_INTERRUPT_MARKS: usize = 10_000;

impl Trace {
    /// `max_samples` at least 2.
    pub fn new(max_samples: usize) -> Self {
        let max_samples = max_samples.max(2);
        Trace {
            samples: Vec::with_capacity(max_samples.min(1 << 16)),
            max_samples,
            stride: 1,
            ticks: 0,
            interrupts: Vec::new(),
            plane: Plane::Xy,
        }
    }

    /// Offer one tick's sample; kept if it falls on the stride.
    pub fn record(&mut self, s: Sample) {
        let keep = self.ticks.is_multiple_of(self.stride);
        self.ticks += 1;
        if !keep {
            return;
        }
        if self.samples.len() >= self.max_samples {
            // Halve: keep every second sample, record half as often from now on.
            let mut i = 0;
            self.samples.retain(|_| {
                i += 1;
                i % 2 == 1
            });
            self.stride = self.stride.saturating_mul(2);
        }
        self.samples.push(s);
    }

    pub fn mark_interrupt(&mut self, s: Sample) {
        if self.interrupts.len() < MAX_INTERRUPT_MARKS {
            self.interrupts.push(s);
        }
    }

    pub fn set_plane(&mut self, p: Plane) {
        self.plane = p;
    }

    pub fn samples(&self) -> &[Sample] {
        &self.samples
    }
    pub fn interrupts(&self) -> &[Sample] {
        &self.interrupts
    }
    pub fn plane(&self) -> Plane {
        self.plane
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimation_keeps_the_bound_and_the_time_order() {
        let mut t = Trace::new(100);
        for k in 0..10_000 {
            t.record(Sample {
                time_s: k as f64,
                pos: [0.0; 6],
                velocity_mm_per_s: 0.0,
                accel_mm_per_s2: 0.0,
                jerk_mm_per_s3: 0.0,
            });
        }
        assert!(t.samples().len() <= 100);
        assert!(t.samples().len() >= 50);
        assert!(t.samples().windows(2).all(|w| w[0].time_s < w[1].time_s));
        assert_eq!(t.samples()[0].time_s, 0.0);
    }
}
