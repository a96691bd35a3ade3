//! `--plot FILE.svg`: the tool path in the working plane and the path velocity over time, with
//! motion interrupts marked, drawn as plain SVG from the motion trace.

use std::fmt::Write as _;
use std::path::Path;

use crate::motion::trace::{Sample, Trace};
use crate::queue::AXIS_LETTERS;

const WIDTH: f64 = 1200.0;
const HEIGHT: f64 = 520.0;
const MARGIN: f64 = 50.0;
/// Left panel (path) width; the velocity panel takes the rest.
const PATH_PANEL: f64 = 480.0;

/// Write the plot of `trace` to `path`.
pub fn write_svg(path: &Path, trace: &Trace, title: &str) -> std::io::Result<()> {
    std::fs::write(path, render_svg(trace, title))
}

/// The plot as SVG text.
pub fn render_svg(trace: &Trace, title: &str) -> String {
    let mut s = String::with_capacity(64 * 1024 + trace.samples().len() * 32);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{MARGIN}" y="22" font-size="15">{}</text>"#,
        escape(title)
    );
    path_panel(&mut s, trace);
    velocity_panel(&mut s, trace);
    s.push_str("</svg>\n");
    s
}

fn path_panel(s: &mut String, trace: &Trace) {
    let (a, b, _) = trace.plane().axes();
    let pts: Vec<(f64, f64)> = trace
        .samples()
        .iter()
        .map(|p| (p.pos[a], p.pos[b]))
        .collect();
    let (x0, y0, w, h) = (MARGIN, MARGIN, PATH_PANEL - MARGIN, HEIGHT - 2.0 * MARGIN);
    frame(s, x0, y0, w, h);
    let (la, lb) = (AXIS_LETTERS[a] as char, AXIS_LETTERS[b] as char);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">tool path, {la} → / {lb} ↑ (mm)</text>"#,
        x0 + w / 2.0,
        y0 - 8.0
    );
    if pts.is_empty() {
        return;
    }
    let (mut min_a, mut max_a, mut min_b, mut max_b) = bounds(&pts);
    // Equal scale on both axes, centred; a point or a line still gets a visible box.
    let span = (max_a - min_a).max(max_b - min_b).max(1e-3) * 1.05;
    let (ca, cb) = ((min_a + max_a) / 2.0, (min_b + max_b) / 2.0);
    min_a = ca - span / 2.0;
    max_a = ca + span / 2.0;
    min_b = cb - span / 2.0;
    max_b = cb + span / 2.0;
    let side = w.min(h);
    let map = |pa: f64, pb: f64| {
        (
            x0 + (pa - min_a) / (max_a - min_a) * side,
            y0 + side - (pb - min_b) / (max_b - min_b) * side,
        )
    };
    polyline(s, pts.iter().map(|&(pa, pb)| map(pa, pb)), "#1f5fbf");
    for m in trace.interrupts() {
        let (x, y) = map(m.pos[a], m.pos[b]);
        let _ = writeln!(
            s,
            r##"<circle cx="{x:.2}" cy="{y:.2}" r="4" fill="none" stroke="#d62728" stroke-width="2"/>"##
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{x0}" y="{}">{la} {:.3} … {:.3}, {lb} {:.3} … {:.3}</text>"#,
        y0 + side + 18.0,
        min_a,
        max_a,
        min_b,
        max_b
    );
}

fn velocity_panel(s: &mut String, trace: &Trace) {
    let samples = trace.samples();
    let x0 = PATH_PANEL + MARGIN;
    let (y0, w, h) = (MARGIN, WIDTH - x0 - MARGIN, HEIGHT - 2.0 * MARGIN);
    frame(s, x0, y0, w, h);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">path velocity (mm/s) over time (s); interrupts in red</text>"#,
        x0 + w / 2.0,
        y0 - 8.0
    );
    let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
        return;
    };
    let t0 = first.time_s;
    let t1 = last.time_s.max(t0 + 1e-6);
    let vmax = samples
        .iter()
        .map(|p| p.velocity_mm_per_s)
        .fold(0.0_f64, f64::max)
        .max(1e-6)
        * 1.05;
    let map = |p: &Sample| {
        (
            x0 + (p.time_s - t0) / (t1 - t0) * w,
            y0 + h - p.velocity_mm_per_s / vmax * h,
        )
    };
    for m in trace.interrupts() {
        let x = x0 + (m.time_s - t0) / (t1 - t0) * w;
        let _ = writeln!(
            s,
            r##"<line x1="{x:.2}" y1="{y0}" x2="{x:.2}" y2="{}" stroke="#d62728" stroke-dasharray="4 3"/>"##,
            y0 + h
        );
    }
    polyline(s, samples.iter().map(map), "#2ca02c");
    let _ = writeln!(
        s,
        r#"<text x="{x0}" y="{}">t {:.3} … {:.3} s, v max {:.2} mm/s, {} interrupt(s)</text>"#,
        y0 + h + 18.0,
        t0,
        t1,
        vmax / 1.05,
        trace.interrupts().len()
    );
}

fn frame(s: &mut String, x: f64, y: f64, w: f64, h: f64) {
    let _ = writeln!(
        s,
        r##"<rect x="{x}" y="{y}" width="{w}" height="{h}" fill="none" stroke="#888"/>"##
    );
}

fn polyline(s: &mut String, pts: impl Iterator<Item = (f64, f64)>, color: &str) {
    s.push_str(r#"<polyline fill="none" stroke=""#);
    s.push_str(color);
    s.push_str(r#"" stroke-width="1.2" points=""#);
    for (x, y) in pts {
        let _ = write!(s, "{x:.2},{y:.2} ");
    }
    s.push_str("\"/>\n");
}

fn bounds(pts: &[(f64, f64)]) -> (f64, f64, f64, f64) {
    pts.iter().fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a0, a1, b0, b1), &(a, b)| (a0.min(a), a1.max(a), b0.min(b), b1.max(b)),
    )
}

fn escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_has_path_velocity_and_interrupt_marks() {
        let mut t = Trace::new(100);
        for k in 0..10 {
            t.record(Sample {
                time_s: k as f64 * 0.001,
                pos: [k as f64, 2.0 * k as f64, 0.0, 0.0, 0.0, 0.0],
                velocity_mm_per_s: k as f64,
                accel_mm_per_s2: 0.0,
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
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert_eq!(svg.matches("<circle").count(), 1);
        assert!(svg.contains("a &lt;b&gt; &amp; c"));
        assert!(svg.contains("1 interrupt(s)"));
    }
}
