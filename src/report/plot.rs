//! `run --plot FILE`: the tool path at 1:1 in the working plane and in two side views along the
//! tool axis (so a path that bends out of the plane shows its bend), and the path velocity,
//! acceleration and jerk over channel time, with axes in mm and s, legends and the motion
//! interrupts marked, from the motion trace. Written as SVG or PNG by `super::picture`.

use std::ops::Range;
use std::path::Path;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::picture::{DrawResult, Picture, PictureError, FAMILY};
use crate::motion::trace::{Sample, Trace};
use crate::queue::Plane;
use crate::vocab::axis::AXIS_LETTERS;

const WIDTH: u32 = 1500;
const HEIGHT: u32 = 1000;
/// Left column (the path views) width, px; the time panels take the rest.
const PATH_COLUMN: u32 = 760;
/// Height of the plane view, px, below the title; the side views take the rest.
const PLANE_VIEW: u32 = 560;
/// The tool path's colour in every view (tests find the path by it).
pub(crate) const PATH: RGBColor = RGBColor(31, 95, 191);
const INTERRUPT: RGBColor = RGBColor(214, 39, 40);

/// The plot of a run's trace.
pub(crate) struct RunPlot<'a> {
    pub trace: &'a Trace,
    pub title: &'a str,
}

/// Write the plot of `trace` to `path` (SVG or PNG by its extension, `-` SVG on stdout).
pub(crate) fn write(path: &Path, trace: &Trace, title: &str) -> Result<(), PictureError> {
    super::picture::write(path, &RunPlot { trace, title })
}

/// One time panel: caption, axis label, the sampled quantity, colour.
type Series = (&'static str, &'static str, fn(&Sample) -> f64, RGBColor);

const TIME_SERIES: [Series; 3] = [
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
        RGBColor(255, 127, 14),
    ),
    (
        "path jerk",
        "j (mm/s³)",
        |s| s.jerk_mm_per_s3,
        RGBColor(148, 103, 189),
    ),
];

impl Picture for RunPlot<'_> {
    fn size(&self) -> (u32, u32) {
        (WIDTH, HEIGHT)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let trace = self.trace;
        root.fill(&WHITE)?;
        let n = trace.interrupts().len();
        let root = root.titled(
            &format!("{} — {n} interrupt(s)", self.title),
            (FAMILY, 20).into_font(),
        )?;
        let (left, right) = root.split_horizontally(PATH_COLUMN);
        let (top, bottom) = left.split_vertically(PLANE_VIEW);
        let plane = trace.plane();
        let (a, b, normal) = plane.axes();
        let name = |i: usize| AXIS_LETTERS[i] as char;
        let caption = format!(
            "tool path, {} plane {}–{}, 1:1",
            g_code(plane),
            name(a),
            name(b)
        );
        path_view(&top, trace, (a, b), &caption, Marks::Interrupts)?;
        let sides = bottom.split_evenly((1, 2));
        for (area, first) in sides.iter().zip([a, b]) {
            let caption = format!("side view {}–{}, 1:1", name(first), name(normal));
            path_view(area, trace, (first, normal), &caption, Marks::None)?;
        }
        let rows = right.split_evenly((3, 1));
        for (area, series) in rows.iter().zip(TIME_SERIES) {
            time_panel(area, trace, series)?;
        }
        Ok(())
    }
}

/// The G code that selects `plane`.
fn g_code(plane: Plane) -> &'static str {
    match plane {
        Plane::Xy => "G17",
        Plane::Zx => "G18",
        Plane::Yz => "G19",
    }
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

type Chart2d<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A chart on `area` holding `x` and `y` (mm) at one scale for both axes: the range of the
/// axis with room to spare is widened around its middle until a millimetre is as many pixels
/// across as up, so a circle is drawn round.
fn one_to_one<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    x: (f64, f64),
    y: (f64, f64),
) -> Result<Chart2d<'_, DB>, DrawingAreaErrorKind<DB::ErrorType>> {
    let build = |x: Range<f64>, y: Range<f64>| {
        ChartBuilder::on(area)
            .margin(8)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x, y)
    };
    // A chart without a caption draws nothing when built: this one only measures.
    let (w_px, h_px) = build(x.0..x.1, y.0..y.1)?.plotting_area().dim_in_pixel();
    let (w_px, h_px) = (f64::from(w_px.max(1)), f64::from(h_px.max(1)));
    let mm_per_px = ((x.1 - x.0) / w_px).max((y.1 - y.0) / h_px);
    let (cx, cy) = ((x.0 + x.1) / 2.0, (y.0 + y.1) / 2.0);
    let (hw, hh) = (mm_per_px * w_px / 2.0, mm_per_px * h_px / 2.0);
    build((cx - hw)..(cx + hw), (cy - hh)..(cy + hh))
}

/// What a path view marks besides the path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Marks {
    /// A red circle where the motion was interrupted (the plane view).
    Interrupts,
    None,
}

/// The tool path projected on the axes `(x, y)`, at 1:1.
fn path_view<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    trace: &Trace,
    (x, y): (usize, usize),
    caption: &str,
    marks: Marks,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let area = area.margin(6, 6, 6, 6).titled(caption, (FAMILY, 15))?;
    let samples = trace.samples();
    let xr = range(samples.iter().map(|s| s.pos[x]));
    let yr = range(samples.iter().map(|s| s.pos[y]));
    let mut chart = one_to_one(&area, xr, yr)?;
    chart
        .configure_mesh()
        .x_desc(format!("{} (mm)", AXIS_LETTERS[x] as char))
        .y_desc(format!("{} (mm)", AXIS_LETTERS[y] as char))
        .draw()?;
    chart
        .draw_series(LineSeries::new(
            samples.iter().map(|s| (s.pos[x], s.pos[y])),
            PATH,
        ))?
        .label("tool path")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], PATH));
    if marks == Marks::Interrupts && !trace.interrupts().is_empty() {
        chart
            .draw_series(
                trace
                    .interrupts()
                    .iter()
                    .map(|m| Circle::new((m.pos[x], m.pos[y]), 5, INTERRUPT.stroke_width(2))),
            )?
            .label("interrupt")
            .legend(|(x, y)| PathElement::new(vec![(x, y - 5), (x + 20, y + 5)], INTERRUPT));
    }
    // The side views' captions say what they show; a legend there would hide the path.
    if marks == Marks::Interrupts {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    Ok(())
}

fn time_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    trace: &Trace,
    (name, unit, value, color): Series,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let samples = trace.samples();
    let (t0, t1) = match (samples.first(), samples.last()) {
        (Some(f), Some(l)) => (f.time_s, l.time_s.max(f.time_s + 1e-6)),
        _ => (0.0, 1.0),
    };
    let (y0, y1) = range(samples.iter().map(value));
    let mut chart = ChartBuilder::on(&area.margin(5, 10, 5, 10))
        .caption(name, (FAMILY, 14))
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
    use crate::report::picture::{encode, Format};

    fn sample(k: f64, pos: [f64; 3]) -> Sample {
        Sample {
            time_s: k * 0.001,
            pos: [pos[0], pos[1], pos[2], 0.0, 0.0, 0.0],
            velocity_mm_per_s: k,
            accel_mm_per_s2: 1000.0,
            jerk_mm_per_s3: 0.0,
        }
    }

    #[test]
    fn plot_has_three_path_views_the_time_panels_legends_and_interrupt_marks() {
        let mut t = Trace::new(100);
        for k in 0..10 {
            let k = f64::from(k);
            t.record(sample(k, [k, 2.0 * k, 0.0]));
        }
        t.mark_interrupt(sample(5.0, [5.0, 10.0, 0.0]));
        let pic = RunPlot {
            trace: &t,
            title: "a <b> & c",
        };
        let svg = String::from_utf8(encode(&pic, Format::Svg).unwrap()).unwrap();
        assert!(svg.starts_with("<svg"));
        assert!(svg.trim_end().ends_with("</svg>"));
        assert_eq!(svg.matches("<circle").count(), 1, "one interrupt mark");
        for label in [
            "tool path, G17 plane X–Y, 1:1",
            "side view X–Z, 1:1",
            "side view Y–Z, 1:1",
            "path velocity",
            "path acceleration",
            "path jerk",
            "channel time (s)",
            "X (mm)",
            "Z (mm)",
            "mm/s²",
            "1 interrupt(s)",
            "interrupt",
        ] {
            assert!(svg.contains(label), "{label}");
        }
        assert!(svg.contains("&lt;b&gt;"), "title escaped");
    }

    /// The plot of `t` as a PNG, decoded: its size (px) and RGB bytes.
    fn png_pixels(t: &Trace) -> ((u32, u32), Vec<u8>) {
        let png = encode(
            &RunPlot {
                trace: t,
                title: "t",
            },
            Format::Png,
        )
        .unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(png))
            .read_info()
            .unwrap();
        let size = (reader.info().width, reader.info().height);
        let mut rgb = vec![0; reader.output_buffer_size()];
        reader.next_frame(&mut rgb).unwrap();
        (size, rgb)
    }

    #[test]
    fn png_is_a_png_of_the_plot_size() {
        let mut t = Trace::new(100);
        for k in 0..10 {
            let k = f64::from(k);
            t.record(sample(k, [k, k, k]));
        }
        assert_eq!(png_pixels(&t).0, (WIDTH, HEIGHT));
    }

    /// Pixels of the tool path's colour in the PNG of a straight line along X at about a
    /// pixel a sample, traced from `from_x` to `to_x` (mm).
    fn path_pixels_of_line(from_x: f64, to_x: f64) -> usize {
        let mut t = Trace::new(2000);
        for k in 0..=1000 {
            let x = from_x + (to_x - from_x) * f64::from(k) / 1000.0;
            t.record(sample(f64::from(k), [x, 5.0, 1.0]));
        }
        png_pixels(&t)
            .1
            .chunks_exact(3)
            .filter(|p| *p == [PATH.0, PATH.1, PATH.2])
            .count()
    }

    #[test]
    fn png_draws_a_path_traced_leftwards_as_a_line_not_dots() {
        let rightwards = path_pixels_of_line(0.0, 150.0);
        let leftwards = path_pixels_of_line(150.0, 0.0);
        assert!(rightwards > 500, "{rightwards} path pixels");
        assert!(
            leftwards.abs_diff(rightwards) <= rightwards / 50,
            "leftwards {leftwards} path pixels, rightwards {rightwards}"
        );
    }
}
