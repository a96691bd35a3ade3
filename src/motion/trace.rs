//! Trace: per-tick samples of position and path velocity kept for `--plot`, decimated so a long
//! run never holds more than a fixed number of points.

use crate::queue::Plane;
use crate::vocab::axis::Position;

/// One recorded tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Channel time since the motion was created, s.
    pub time_s: f64,
    pub pos: Position,
    /// Path velocity over the tick, mm/s.
    pub velocity_mm_per_s: f64,
    /// Path acceleration (change of the path velocity), mm/s².
    pub(crate) accel_mm_per_s2: f64,
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
pub(crate) const MAX_INTERRUPT_MARKS: usize = 10_000;

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

    pub(crate) fn mark_interrupt(&mut self, s: Sample) {
        if self.interrupts.len() < MAX_INTERRUPT_MARKS {
            self.interrupts.push(s);
        }
    }

    pub(crate) fn set_plane(&mut self, p: Plane) {
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

/// `run --trace FILE.csv`: the interpolated motion streamed to a file, one row every `every`
/// ticks — channel time, each configured axis' position, path velocity, acceleration and jerk.
/// Nothing is kept in memory beyond the writer's buffer; the first write error stops the
/// trace and is reported by [`CsvTrace::finish`].
pub(crate) struct CsvTrace {
    out: std::io::BufWriter<Box<dyn std::io::Write + Send>>,
    /// Axis indices written, in order.
    axes: Vec<usize>,
    every: u64,
    ticks: u64,
    error: Option<std::io::Error>,
}

impl std::fmt::Debug for CsvTrace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CsvTrace")
            .field("axes", &self.axes)
            .field("every", &self.every)
            .field("ticks", &self.ticks)
            .finish_non_exhaustive()
    }
}

impl CsvTrace {
    /// Create `path` (`-`: standard output) and write the header.
    pub fn create(path: &std::path::Path, axes: &[usize], every: u64) -> std::io::Result<Self> {
        use std::io::Write;
        let mut out = std::io::BufWriter::new(crate::destination::create(path)?);
        let mut header = String::from("time_s");
        for &i in axes {
            let unit = if i < 3 { "mm" } else { "deg" };
            header.push_str(&format!(
                ",{}_{unit}",
                crate::vocab::axis::AXIS_LETTERS[i] as char
            ));
        }
        header.push_str(",velocity_mm_per_s,acceleration_mm_per_s2,jerk_mm_per_s3");
        writeln!(out, "{header}")?;
        Ok(CsvTrace {
            out,
            axes: axes.to_vec(),
            every: every.max(1),
            ticks: 0,
            error: None,
        })
    }

    /// One tick; written if it falls on the stride.
    pub fn record(&mut self, s: &Sample) {
        use std::io::Write;
        let keep = self.ticks.is_multiple_of(self.every);
        self.ticks += 1;
        if !keep || self.error.is_some() {
            return;
        }
        let mut row = format!("{:.6}", s.time_s);
        for &i in &self.axes {
            row.push_str(&format!(",{:.6}", s.pos[i]));
        }
        row.push_str(&format!(
            ",{:.6},{:.3},{:.1}",
            s.velocity_mm_per_s, s.accel_mm_per_s2, s.jerk_mm_per_s3
        ));
        if let Err(e) = writeln!(self.out, "{row}") {
            self.error = Some(e);
        }
    }

    /// Flush; the first error of the whole trace, if any.
    pub fn finish(mut self) -> std::io::Result<()> {
        use std::io::Write;
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.out.flush()
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
