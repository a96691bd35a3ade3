//! The lateness histogram of `ncchannel bench --plot`: runtime and bare loop on one log-scaled
//! time axis, as plain SVG text (no plotting dependency), with each p99 marked.

use std::fmt::Write as _;
use std::time::Duration;

use crate::report::stats::Histogram;

const W: f64 = 800.0;
const H: f64 = 420.0;
const LEFT: f64 = 60.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 50.0;
/// Bins per decade of the time axis.
const PER_DECADE: f64 = 10.0;

/// Share of samples per log-spaced bin from `lo_us` (10^k) up, `bins` bins.
fn shares(h: &Histogram, lo_exp: f64, bins: usize) -> Vec<f64> {
    let mut v = vec![0.0; bins];
    let n = h.count().max(1) as f64;
    for (high_ns, c) in h.buckets() {
        let us = (high_ns as f64 / 1000.0).max(1e-3);
        let b = ((us.log10() - lo_exp) * PER_DECADE).floor();
        let b = (b.max(0.0) as usize).min(bins - 1);
        v[b] += c as f64 / n;
    }
    v
}

/// The SVG document.
pub fn lateness_svg(runtime: &Histogram, bare: &Histogram, period: Duration) -> String {
    let max_us = runtime.max_us().max(bare.max_us()).max(1.0);
    let lo_exp = -1.0; // 0.1 µs
    let hi_exp = max_us.log10().ceil().max(lo_exp + 1.0);
    let bins = ((hi_exp - lo_exp) * PER_DECADE) as usize;
    let a = shares(runtime, lo_exp, bins);
    let b = shares(bare, lo_exp, bins);
    let top = a.iter().chain(&b).cloned().fold(0.0, f64::max).max(1e-9);
    let pw = W - LEFT - RIGHT;
    let ph = H - TOP - BOTTOM;
    let x_of = |exp: f64| LEFT + (exp - lo_exp) / (hi_exp - lo_exp) * pw;
    let y_of = |share: f64| TOP + ph - share / top * ph;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{W}" height="{H}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{LEFT}" y="20" font-size="14">Tick lateness at {} µs: runtime (red) vs bare spin_sleep loop (blue)</text>"#,
        period.as_micros()
    );
    // Axes and decade ticks.
    let _ = writeln!(
        s,
        r#"<path d="M{LEFT},{TOP} V{} H{}" stroke="black" fill="none"/>"#,
        TOP + ph,
        LEFT + pw
    );
    let mut e = lo_exp;
    while e <= hi_exp + 1e-9 {
        let x = x_of(e);
        let label = 10f64.powf(e);
        let _ = writeln!(
            s,
            r##"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{}" stroke="#ddd"/><text x="{x:.1}" y="{}" text-anchor="middle">{label} µs</text>"##,
            TOP + ph,
            TOP + ph + 18.0
        );
        e += 1.0;
    }
    let _ = writeln!(
        s,
        r#"<text x="15" y="{}" transform="rotate(-90 15 {})" text-anchor="middle">share of ticks (max {:.1} %)</text>"#,
        TOP + ph / 2.0,
        TOP + ph / 2.0,
        top * 100.0
    );
    for (series, color) in [(&a, "red"), (&b, "blue")] {
        let mut d = format!("M{:.1},{:.1}", x_of(lo_exp), y_of(0.0));
        for (i, v) in series.iter().enumerate() {
            let x0 = x_of(lo_exp + i as f64 / PER_DECADE);
            let x1 = x_of(lo_exp + (i + 1) as f64 / PER_DECADE);
            let y = y_of(*v);
            let _ = write!(d, " L{x0:.1},{y:.1} L{x1:.1},{y:.1}");
        }
        let _ = write!(d, " L{:.1},{:.1}", x_of(hi_exp), y_of(0.0));
        let _ = writeln!(
            s,
            r#"<path d="{d}" stroke="{color}" stroke-width="1.5" fill="none"/>"#
        );
    }
    for (h, color, name, dy) in [
        (runtime, "red", "runtime", 0.0),
        (bare, "blue", "bare", 14.0),
    ] {
        let p99 = h.quantile_us(0.99).max(0.1);
        let x = x_of(p99.log10().clamp(lo_exp, hi_exp));
        let _ = writeln!(
            s,
            r#"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{}" stroke="{color}" stroke-dasharray="4 3"/><text x="{:.1}" y="{}" fill="{color}">{name} p99 {p99:.1} µs</text>"#,
            TOP + ph,
            x + 4.0,
            TOP + 12.0 + dy
        );
    }
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svg_holds_both_series_and_p99_marks() {
        let mut a = Histogram::new();
        let mut b = Histogram::new();
        for i in 0..1000u64 {
            a.record_ns(1000 + i * 10);
            b.record_ns(500 + i);
        }
        let svg = lateness_svg(&a, &b, Duration::from_millis(1));
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("stroke=\"red\" stroke-width").count(), 1);
        assert_eq!(svg.matches("stroke=\"blue\" stroke-width").count(), 1);
        assert!(svg.contains("runtime p99"), "{svg}");
    }
}
