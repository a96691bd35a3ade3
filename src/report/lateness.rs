//! The lateness histogram of `bench --plot`: runtime, bare loop and (when installed)
//! cyclictest on one log-scaled time axis with decade ticks, units and a legend, each p99
//! marked.

use std::time::Duration;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::picture::{DrawResult, Picture, FAMILY};
use crate::vocab::stats::Histogram;

/// Size of the lateness histogram, px.
const LATENESS_SIZE: (u32, u32) = (900, 480);
/// Bins per decade of the time axis.
const PER_DECADE: f64 = 10.0;
/// The time axis starts here, µs (0.1 µs: below any tick's lateness we can measure).
const LOWEST_US: f64 = 0.1;
const RUNTIME: RGBColor = RGBColor(214, 39, 40);
const BARE: RGBColor = RGBColor(31, 95, 191);
const CYCLICTEST: RGBColor = RGBColor(44, 160, 44);

/// The lateness distributions of a bench run.
pub(crate) struct Lateness<'a> {
    pub runtime: &'a Histogram,
    pub bare: &'a Histogram,
    /// cyclictest's wake-up latency at the same period, policy and CPU, when it ran.
    pub cyclictest: Option<&'a Histogram>,
    pub period: Duration,
}

/// Share of samples per log-spaced bin (`PER_DECADE` a decade) from [`LOWEST_US`] up.
fn shares(h: &Histogram, bins: usize) -> Vec<f64> {
    let mut v = vec![0.0; bins];
    let n = h.count().max(1) as f64;
    for (high_ns, c) in h.buckets() {
        let us = (high_ns as f64 / 1000.0).max(LOWEST_US);
        let b = ((us / LOWEST_US).log10() * PER_DECADE).floor();
        let b = (b.max(0.0) as usize).min(bins - 1);
        v[b] += c as f64 / n;
    }
    v
}

impl Picture for Lateness<'_> {
    fn size(&self) -> (u32, u32) {
        LATENESS_SIZE
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (runtime, bare) = (self.runtime, self.bare);
        root.fill(&WHITE)?;
        let max_us = runtime
            .max_us()
            .max(bare.max_us())
            .max(self.cyclictest.map_or(0.0, Histogram::max_us))
            .max(1.0);
        let decades = (max_us / LOWEST_US).log10().ceil().max(1.0);
        let hi_us = LOWEST_US * 10f64.powf(decades);
        let bins = (decades * PER_DECADE) as usize;
        let mut series = vec![
            ("runtime", RUNTIME, shares(runtime, bins), runtime),
            ("bare spin_sleep loop", BARE, shares(bare, bins), bare),
        ];
        if let Some(c) = self.cyclictest {
            series.push(("cyclictest", CYCLICTEST, shares(c, bins), c));
        }
        let top_pct = series
            .iter()
            .flat_map(|s| s.2.iter())
            .fold(0.0f64, |a, &b| a.max(b))
            .max(1e-9)
            * 100.0
            * 1.1;
        let mut chart = ChartBuilder::on(&root.margin(10, 20, 10, 10))
            .caption(
                format!("Tick lateness at a {} µs cycle", self.period.as_micros()),
                (FAMILY, 18),
            )
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d((LOWEST_US..hi_us).log_scale(), 0.0..top_pct)?;
        chart
            .configure_mesh()
            .label_style((FAMILY, 12))
            .x_desc("lateness against the ideal tick start (µs, log scale)")
            .y_desc("share of ticks (%)")
            .x_label_formatter(&|v| format!("{v}"))
            .draw()?;
        let bin_edge = |i: usize| LOWEST_US * 10f64.powf(i as f64 / PER_DECADE);
        for (name, color, shares, h) in &series {
            let color = *color;
            // A step line: each bin's share held across the bin.
            let steps = shares
                .iter()
                .enumerate()
                .flat_map(|(i, &s)| [(bin_edge(i), s * 100.0), (bin_edge(i + 1), s * 100.0)]);
            chart
                .draw_series(LineSeries::new(steps, color.stroke_width(2)))?
                .label(*name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            let p99 = h.quantile_us(0.99).clamp(LOWEST_US, hi_us);
            chart
                .draw_series(DashedLineSeries::new(
                    [(p99, 0.0), (p99, top_pct)],
                    6,
                    4,
                    color.stroke_width(1),
                ))?
                .label(format!("{name} p99 {p99:.1} µs"))
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 6, y), (x + 10, y), (x + 16, y)], color)
                });
        }
        chart
            .configure_series_labels()
            .label_font((FAMILY, 12))
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::picture::{encode, Format};

    #[test]
    fn svg_holds_both_series_axes_and_p99_marks() {
        let mut a = Histogram::new();
        let mut b = Histogram::new();
        for i in 0..1000u64 {
            a.record_ns(1000 + i * 10);
            b.record_ns(500 + i);
        }
        let c = b.clone();
        let pic = Lateness {
            runtime: &a,
            bare: &b,
            cyclictest: Some(&c),
            period: Duration::from_millis(1),
        };
        let svg = String::from_utf8(encode(&pic, Format::Svg).unwrap()).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        for label in [
            "Tick lateness at a 1000 µs cycle",
            "share of ticks (%)",
            "µs, log scale",
            "runtime p99",
            "bare spin_sleep loop p99",
            "cyclictest p99",
        ] {
            assert!(svg.contains(label), "{label} missing");
        }
    }
}
