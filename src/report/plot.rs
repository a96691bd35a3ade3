//! `--plot FILE.svg`: the tool path in the working plane and the path velocity, acceleration and
//! jerk over time, with axes, ticks, legends and the motion interrupts marked — drawn with
//! `plotters` (SVG backend) from the motion trace.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::motion::trace::{Sample, Trace};
use crate::vocab::axis::AXIS_LETTERS;

const WIDTH: u32 = 1400;
const HEIGHT: u32 = 900;
/// Left panel (path) width, px; the time panels take the rest.
const PATH_PANEL: u32 = 620;
const INTERRUPT: RGBColor = RGBColor(214, 39, 40);

/// Write the plot of `trace` to `path`.
pub fn write_svg(path: &Path, trace: &Trace, title: &str) -> std::io::Result<()> {
    std::fs::write(path, render_svg(trace, title))
}

/// The plot as SVG text.
pub fn render_svg(trace: &Trace, title: &str) -> String {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, HEIGHT)).into_drawing_area();
        // Drawing into a string cannot fail for I/O; a plotting error leaves a partial plot,
        // which is still a valid SVG document.
        let _ = draw(&root, trace, title);
        let _ = root.present();
    }
    svg
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

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
}
