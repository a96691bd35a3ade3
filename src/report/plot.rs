//! The SVG plots, drawn with `plotters` (SVG backend):
//! - `run --plot FILE.svg`: the tool path in the working plane and the path velocity,
//!   acceleration and jerk over time, with axes, ticks, legends and the motion interrupts
//!   marked, from the motion trace;
//! - `bench --plot`: the lateness histogram, runtime and bare loop on one log-scaled time axis
//!   with decade ticks, units and a legend, each p99 marked.

use std::path::Path;
use std::time::Duration;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::motion::trace::{Sample, Trace};
use crate::vocab::axis::AXIS_LETTERS;
use crate::vocab::stats::Histogram;

const WIDTH: u32 = 1400;
const HEIGHT: u32 = 900;
/// Left panel (path) width, px; the time panels take the rest.
const PATH_PANEL: u32 = 620;
const INTERRUPT: RGBColor = RGBColor(214, 39, 40);

/// Write the plot of `trace` to `path`.
pub(crate) fn write_svg(path: &Path, trace: &Trace, title: &str) -> std::io::Result<()> {
    std::fs::write(path, render_svg(trace, title))
}

/// The plot as SVG text.
pub(crate) fn render_svg(trace: &Trace, title: &str) -> String {
    svg_of((WIDTH, HEIGHT), |root| draw(root, trace, title))
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// An SVG document of `size` px drawn by `draw`. Drawing into a string cannot fail for I/O;
/// a plotting error leaves a partial plot, which is still a valid SVG document.
fn svg_of(
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> DrawResult,
) -> String {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        let _ = draw(&root);
        let _ = root.present();
    }
    svg
}

/// One time panel: caption, axis label, the sampled quantity, colour.
type Series = (&'static str, &'static str, fn(&Sample) -> f64, RGBColor);

fn draw(root: &DrawingArea<SVGBackend<'_>, Shift>, trace: &Trace, title: &str) -> DrawResult {
    root.fill(&WHITE)?;
    let n = trace.interrupts().len();
    let root = root.titled(
        &format!("{title} — {n} interrupt(s)"),
        ("sans-serif", 20).into_font(),
    )?;
    let (left, right) = root.split_horizontally(PATH_PANEL);
    path_panel(&left, trace)?;
    let rows = right.split_evenly((3, 1));
    let series: [Series; 3] = [
        (
            "path velocity",
            "v (mm/s)",
            |s| s.velocity_mm_per_s,
            RGBColor(44, 160, 44),
        ),
        (
            "path acceleration",
            "a (mm/s²)",
            |s| s.accel_mm_per_s2,
            RGBColor(31, 95, 191),
        ),
        (
            "path jerk",
            "j (mm/s³)",
            |s| s.jerk_mm_per_s3,
            RGBColor(148, 103, 189),
        ),
    ];
    for (area, (name, unit, value, color)) in rows.iter().zip(series) {
        time_panel(area, trace, name, unit, value, color)?;
    }
    Ok(())
}

/// Lower and upper bound of `values` with a margin; a flat or empty series still gets a range.
fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(1e-6);
    (lo - pad, hi + pad)
}

fn path_panel(area: &DrawingArea<SVGBackend<'_>, Shift>, trace: &Trace) -> DrawResult {
    let (a, b, _) = trace.plane().axes();
    let (la, lb) = (AXIS_LETTERS[a] as char, AXIS_LETTERS[b] as char);
    let samples = trace.samples();
    let (a0, a1) = range(samples.iter().map(|s| s.pos[a]));
    let (b0, b1) = range(samples.iter().map(|s| s.pos[b]));
    // Equal scale on both axes, centred.
    let span = (a1 - a0).max(b1 - b0);
    let (ca, cb) = ((a0 + a1) / 2.0, (b0 + b1) / 2.0);
    let mut chart = ChartBuilder::on(&area.margin(10, 10, 10, 10))
        .caption("tool path", ("sans-serif", 16))
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (ca - span / 2.0)..(ca + span / 2.0),
            (cb - span / 2.0)..(cb + span / 2.0),
        )?;
    chart
        .configure_mesh()
        .x_desc(format!("{la} (mm)"))
        .y_desc(format!("{lb} (mm)"))
        .draw()?;
    chart
        .draw_series(LineSeries::new(
            samples.iter().map(|s| (s.pos[a], s.pos[b])),
            RGBColor(31, 95, 191),
        ))?
        .label("axes")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RGBColor(31, 95, 191)));
    chart
        .draw_series(
            trace
                .interrupts()
                .iter()
                .map(|m| Circle::new((m.pos[a], m.pos[b]), 5, INTERRUPT.stroke_width(2))),
        )?
        .label("interrupt")
        .legend(|(x, y)| PathElement::new(vec![(x, y - 5), (x + 20, y + 5)], INTERRUPT));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

fn time_panel(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    trace: &Trace,
    name: &str,
    unit: &str,
    value: fn(&Sample) -> f64,
    color: RGBColor,
) -> DrawResult {
    let samples = trace.samples();
    let (t0, t1) = match (samples.first(), samples.last()) {
        (Some(f), Some(l)) => (f.time_s, l.time_s.max(f.time_s + 1e-6)),
        _ => (0.0, 1.0),
    };
    let (y0, y1) = range(samples.iter().map(value));
    let mut chart = ChartBuilder::on(&area.margin(5, 10, 5, 10))
        .caption(name, ("sans-serif", 14))
        .x_label_area_size(30)
        .y_label_area_size(70)
        .build_cartesian_2d(t0..t1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc("channel time (s)")
        .y_desc(unit)
        .draw()?;
    chart
        .draw_series(LineSeries::new(
            samples.iter().map(|s| (s.time_s, value(s))),
            color,
        ))?
        .label(name)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
    if !trace.interrupts().is_empty() {
        chart
            .draw_series(
                trace
                    .interrupts()
                    .iter()
                    .map(|m| PathElement::new(vec![(m.time_s, y0), (m.time_s, y1)], INTERRUPT)),
            )?
            .label("interrupt")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], INTERRUPT));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

// The lateness histogram of `bench --plot`.

/// Size of the lateness histogram, px.
const LATENESS_SIZE: (u32, u32) = (900, 480);
/// Bins per decade of the time axis.
const PER_DECADE: f64 = 10.0;
/// The time axis starts here, µs (0.1 µs: below any tick's lateness we can measure).
const LOWEST_US: f64 = 0.1;
const RUNTIME: RGBColor = RGBColor(214, 39, 40);
const BARE: RGBColor = RGBColor(31, 95, 191);

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

/// The lateness histogram as SVG text.
pub(crate) fn lateness_svg(runtime: &Histogram, bare: &Histogram, period: Duration) -> String {
    svg_of(LATENESS_SIZE, |root| {
        draw_lateness(root, runtime, bare, period)
    })
}

fn draw_lateness(
    root: &DrawingArea<SVGBackend<'_>, Shift>,
    runtime: &Histogram,
    bare: &Histogram,
    period: Duration,
) -> DrawResult {
    root.fill(&WHITE)?;
    let max_us = runtime.max_us().max(bare.max_us()).max(1.0);
    let decades = (max_us / LOWEST_US).log10().ceil().max(1.0);
    let hi_us = LOWEST_US * 10f64.powf(decades);
    let bins = (decades * PER_DECADE) as usize;
    let series = [
        ("runtime", RUNTIME, shares(runtime, bins), runtime),
        ("bare spin_sleep loop", BARE, shares(bare, bins), bare),
    ];
    let top_pct = series
        .iter()
        .flat_map(|s| s.2.iter())
        .fold(0.0f64, |a, &b| a.max(b))
        .max(1e-9)
        * 100.0
        * 1.1;
    let mut chart = ChartBuilder::on(&root.margin(10, 20, 10, 10))
        .caption(
            format!("Tick lateness at a {} µs cycle", period.as_micros()),
            ("sans-serif", 18),
        )
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d((LOWEST_US..hi_us).log_scale(), 0.0..top_pct)?;
    chart
        .configure_mesh()
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
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_has_path_velocity_acceleration_jerk_legends_and_interrupt_marks() {
        let mut t = Trace::new(100);
        for k in 0..10 {
            t.record(Sample {
                time_s: k as f64 * 0.001,
                pos: [k as f64, 2.0 * k as f64, 0.0, 0.0, 0.0, 0.0],
                velocity_mm_per_s: k as f64,
                accel_mm_per_s2: 1000.0,
                jerk_mm_per_s3: 0.0,
            });
        }
        t.mark_interrupt(Sample {
            time_s: 0.005,
            pos: [5.0, 10.0, 0.0, 0.0, 0.0, 0.0],
            velocity_mm_per_s: 0.0,
            accel_mm_per_s2: 0.0,
            jerk_mm_per_s3: 0.0,
        });
        let svg = render_svg(&t, "a <b> & c");
        assert!(svg.starts_with("<svg"));
        assert!(svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("<circle").count(), 1, "one interrupt mark");
        for label in [
            "tool path",
            "path velocity",
            "path acceleration",
            "path jerk",
            "channel time (s)",
            "X (mm)",
            "1 interrupt(s)",
            "interrupt",
        ] {
            assert!(svg.contains(label), "{label}");
        }
        assert!(svg.contains("&lt;b&gt;"), "title escaped");
    }

    #[test]
    fn svg_holds_both_series_axes_and_p99_marks() {
        let mut a = Histogram::new();
        let mut b = Histogram::new();
        for i in 0..1000u64 {
            a.record_ns(1000 + i * 10);
            b.record_ns(500 + i);
        }
        let svg = lateness_svg(&a, &b, Duration::from_millis(1));
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        for label in [
            "Tick lateness at a 1000 µs cycle",
            "share of ticks (%)",
            "µs, log scale",
            "runtime p99",
            "bare spin_sleep loop p99",
        ] {
            assert!(svg.contains(label), "{label} missing");
        }
    }
}
