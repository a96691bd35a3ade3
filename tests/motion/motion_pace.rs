//! The machine's pace on the shipped settings (`params/`): the R50 circle as one arc and as
//! 36 / 360 / 3,600 chords, the 100 mm square with and without polynomial contouring — times,
//! corner speeds, the deviation from the programmed corner, and every axis' velocity and
//! acceleration on every tick within its limit.

use std::path::Path;

use crate::support::limit_check::{LimitCheck, DEFAULT_EPS};
use crate::support::queued::{block, r50_circle};
use ncchannel::vocab::axis::Position;
use ncchannel::vocab::techno::NoUnits;
use ncchannel::DEFAULT_PATH_DEV_MM;
use ncchannel::{Action, BlockQueue, Move, MoveKind, PathMode};
use ncchannel::{AxisLimits, Motion, MotionNote, PlannerSettings};

const DT: f64 = 0.001;

/// Axis limits and planner settings of the shipped start-up list.
fn shipped() -> (Vec<AxisLimits>, PlannerSettings) {
    let config = ncchannel::params::load(Path::new("params/startup.lis")).unwrap();
    let s = ncchannel::channel_settings(&config, &config.channels[0]).unwrap();
    (s.axes, s.planner)
}

fn p(x: f64, y: f64) -> Position {
    [x, y, 0.0, 0.0, 0.0, 0.0]
}

fn line(start: Position, end: Position, feed: f64, path: PathMode) -> Action {
    Action::Move(Box::new(Move {
        kind: MoveKind::Line,
        start,
        end,
        feed_mm_per_min: feed,
        path,
    }))
}

/// What one run showed: seconds to the program end, every tick's position and path velocity.
struct Run {
    time_s: f64,
    positions: Vec<Position>,
    velocities: Vec<f64>,
    check: LimitCheck,
}

/// Run the queued program on the shipped settings to its end.
fn run(q: &mut BlockQueue, start: Position) -> Run {
    let (axes, settings) = shipped();
    let mut m = Motion::with_planner(axes.clone(), settings);
    m.set_position(start);
    let mut check = LimitCheck::new(&axes, DT, DEFAULT_EPS);
    check.record(start);
    let (mut positions, mut velocities) = (Vec::new(), Vec::new());
    let mut notes = Vec::new();
    for k in 1..=200_000 {
        m.step(DT, q, &mut notes, &NoUnits);
        positions.push(m.position());
        velocities.push(m.velocity_mm_per_s());
        check.record(m.position());
        assert!(
            !notes.iter().any(|n| matches!(n, MotionNote::Error { .. })),
            "{notes:?}"
        );
        if notes.iter().any(|n| matches!(n, MotionNote::End { .. })) {
            return Run {
                time_s: k as f64 * DT,
                positions,
                velocities,
                check,
            };
        }
        notes.clear();
    }
    panic!("no program end");
}

/// The R50 circle at F6000 from (50, 0): one G03 (n = 0) or n chords.
fn circle(n: usize) -> Run {
    circle_with(n, PathMode::default())
}

/// The same, the chords programmed with `path` (contouring).
fn circle_with(n: usize, path: PathMode) -> Run {
    let mut q = BlockQueue::new(1_000_000);
    let start = r50_circle(&mut q, n, path);
    let r = run(&mut q, start);
    assert_eq!(r.positions.last().copied(), Some(start));
    r
}

#[test]
fn chord_polylines_of_the_r50_circle_run_near_the_arc_on_shipped_settings() {
    let arc = circle(0);
    arc.check.verdict().unwrap();
    for n in [360, 3600] {
        let r = circle(n);
        println!(
            "R50 F6000 shipped: arc {:.3} s, {n} chords {:.3} s ({:.3}×)",
            arc.time_s,
            r.time_s,
            r.time_s / arc.time_s
        );
        assert!(r.time_s <= 1.1 * arc.time_s, "{n} chords: {} s", r.time_s);
        if let Err(e) = r.check.verdict() {
            panic!("{n} chords: {e}");
        }
    }
}

#[test]
fn a_one_degree_kink_is_passed_at_almost_full_feed() {
    // The 360-chord circle: every junction turns 1°; away from its start and end the axes
    // keep at least 90 % of F6000.
    let r = circle(360);
    let n = r.velocities.len();
    let slowest = r.velocities[n / 4..3 * n / 4]
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    println!("360 chords: slowest {slowest:.2} mm/s");
    assert!(slowest >= 90.0, "{slowest}");
}

/// The 100 mm square at F3000 from the origin, counter-clockwise; `dev` = contouring.
fn square(dev: Option<f64>) -> Run {
    let mut q = BlockQueue::new(1_000);
    let path = PathMode {
        contour_dev_mm: dev,
        ..PathMode::default()
    };
    let corners = [p(100.0, 0.0), p(100.0, 100.0), p(0.0, 100.0), p(0.0, 0.0)];
    let mut at = p(0.0, 0.0);
    for (k, c) in corners.iter().enumerate() {
        q.push(block(k as u32 + 1, line(at, *c, 3000.0, path)));
        at = *c;
    }
    q.push(block(5, Action::End { m: 30 }));
    run(&mut q, p(0.0, 0.0))
}

/// The slowest path velocity near each inner corner (within 2 mm of it), mm/s.
fn corner_speeds(r: &Run) -> Vec<f64> {
    [p(100.0, 0.0), p(100.0, 100.0), p(0.0, 100.0)]
        .iter()
        .map(|c| {
            r.positions
                .iter()
                .zip(&r.velocities)
                .filter(|(q, _)| (q[0] - c[0]).hypot(q[1] - c[1]) < 2.0)
                .map(|(_, v)| *v)
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

#[test]
fn the_square_stops_at_its_corners_without_contouring() {
    let r = square(None);
    let speeds = corner_speeds(&r);
    println!(
        "square without contouring: {:.3} s, corners {speeds:.3?} mm/s",
        r.time_s
    );
    // A stop within one cycle: no axis changes its velocity by more than aᵢ·dt = 2 mm/s.
    assert!(speeds.iter().all(|v| *v <= 2.0), "{speeds:?}");
    r.check.verdict().unwrap();
}

/// The deviation from the programmed corners: per inner corner, how close the path comes to
/// it, mm (the contour's middle lies this far from the corner).
fn corner_deviations_mm(r: &Run) -> Vec<f64> {
    [p(100.0, 0.0), p(100.0, 100.0), p(0.0, 100.0)]
        .iter()
        .map(|c| {
            r.positions
                .iter()
                .map(|q| (q[0] - c[0]).hypot(q[1] - c[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

#[test]
fn the_contoured_square_rounds_its_corners_within_the_default_deviation_at_speed() {
    let sharp = square(None);
    let r = square(Some(DEFAULT_PATH_DEV_MM));
    let speeds = corner_speeds(&r);
    let devs = corner_deviations_mm(&r);
    let dev = devs.iter().copied().fold(0.0, f64::max);
    println!(
        "square with G261 ({DEFAULT_PATH_DEV_MM} mm): {:.3} s (sharp {:.3} s), corners {speeds:.2?} mm/s, deviation {dev:.5} mm",
        r.time_s, sharp.time_s
    );
    // Every corner rounded by the default deviation: the path passes δ from the corner
    // (the ticks sample the curve every 14 µm, so the closest sample lies up to 1 µm further).
    assert!(
        devs.iter()
            .all(|d| (DEFAULT_PATH_DEV_MM..DEFAULT_PATH_DEV_MM + 1e-3).contains(d)),
        "{devs:?}"
    );
    // And nowhere farther than δ from the programmed sides.
    let off = r
        .positions
        .iter()
        .map(|q| q[0].min(100.0 - q[0]).min(q[1]).min(100.0 - q[1]).abs())
        .fold(0.0, f64::max);
    assert!(off <= DEFAULT_PATH_DEV_MM, "{off}");
    // A tangent arc of radius 0.1207 mm passed at 80 % of 95 % of a = 2000 mm/s²
    // centripetal: 13.5 mm/s.
    assert!(speeds.iter().all(|v| *v >= 13.0), "{speeds:?}");
    assert!(r.time_s < sharp.time_s);
    r.check.verdict().unwrap();
}

#[test]
fn coarse_chords_need_contouring_to_keep_the_pace() {
    // 36 chords turn 10° at each junction: at F6000 an axis' velocity would jump by 17 mm/s
    // in one cycle, 8.7 × what a = 2000 mm/s² allows, so without contouring the junctions
    // are slow. With G261 at its default deviation they are rounded and passed at speed.
    let arc = circle(0);
    let sharp = circle(36);
    let path = PathMode {
        contour_dev_mm: Some(DEFAULT_PATH_DEV_MM),
        ..PathMode::default()
    };
    let round = circle_with(36, path);
    println!(
        "36 chords: {:.3} s sharp, {:.3} s with G261 ({:.3}×), arc {:.3} s",
        sharp.time_s,
        round.time_s,
        round.time_s / arc.time_s,
        arc.time_s
    );
    assert!(round.time_s <= 1.1 * arc.time_s, "{}", round.time_s);
    sharp.check.verdict().unwrap();
    round.check.verdict().unwrap();
}

/// The slowest path velocity of two 40 mm lines at F6000 meeting at a kink of `deg`°, mm/s.
fn kink_speed(deg: f64) -> f64 {
    let mut q = BlockQueue::new(16);
    let th = deg.to_radians();
    let (a, b) = (p(0.0, 0.0), p(40.0, 0.0));
    let c = p(40.0 + 40.0 * th.cos(), 40.0 * th.sin());
    q.push(block(1, line(a, b, 6000.0, PathMode::default())));
    q.push(block(2, line(b, c, 6000.0, PathMode::default())));
    q.push(block(3, Action::End { m: 30 }));
    let r = run(&mut q, a);
    r.check.verdict().unwrap();
    // Between leaving the start and arriving at the end: the slowest moment is the kink.
    let first = r.velocities.iter().position(|v| *v > 99.0).unwrap();
    let last = r.velocities.iter().rposition(|v| *v > 99.0).unwrap();
    r.velocities[first..=last]
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn the_corner_speed_falls_with_the_kink_as_the_axes_allow() {
    // a = 2000 mm/s², dt = 1 ms: a 1° kink near feed, 5° and more by the jump rule, 90° a
    // stop. The rule's speed is monotone in the angle.
    let speeds: Vec<f64> = [0.5, 1.0, 2.0, 5.0, 10.0, 45.0, 90.0]
        .iter()
        .map(|&d| kink_speed(d))
        .collect();
    println!("kink 0.5/1/2/5/10/45/90°: {speeds:.2?} mm/s");
    assert!(speeds[0] >= 99.0 && speeds[1] >= 95.0, "{speeds:?}");
    assert!(speeds.windows(2).all(|w| w[1] <= w[0] + 1e-9), "{speeds:?}");
    assert!(speeds[6] <= 2.0, "{speeds:?}");
}

/// Regenerates the plots of docs/motion.md from runs on the shipped settings:
/// `cargo test --release --test motion -- --ignored motion_pace::docs_plots`.
#[test]
#[ignore = "writes docs/*.svg"]
fn docs_plots() {
    // The plots' text is laid out with the binary's embedded font (plotters' ab_glyph).
    ncchannel::report::picture::register_font();
    corner_speed_plot(Path::new("docs/corner_speed.svg"));
    contour_corner_plot(Path::new("docs/contour_corner.svg"));
}

fn corner_speed_plot(out: &Path) {
    use plotters::prelude::*;
    let angles: Vec<f64> = (0..=40)
        .map(|k| 0.1 * 900f64.powf(k as f64 / 40.0))
        .collect();
    let measured: Vec<(f64, f64)> = angles.iter().map(|&d| (d, kink_speed(d))).collect();
    // The fixed-reserve rule this replaced: v·|Δtᵢ| ≤ 0.25·a·dt on the worse axis.
    let reserve: Vec<(f64, f64)> = angles
        .iter()
        .map(|&d| {
            let th: f64 = d.to_radians();
            let jump = (1.0 - th.cos()).max(th.sin());
            (d, (0.25 * 2000.0 * DT / jump).min(100.0))
        })
        .collect();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 500)).into_drawing_area();
        root.fill(&WHITE).unwrap();
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Corner speed of two lines at F6000, shipped axes (a = 2000 mm/s², 1 ms cycle)",
                ("sans-serif", 18),
            )
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d((0.1f64..90f64).log_scale(), 0f64..110f64)
            .unwrap();
        chart
            .configure_mesh()
            .x_desc("direction change at the junction (°)")
            .y_desc("slowest path velocity (mm/s)")
            .draw()
            .unwrap();
        let blue = RGBColor(31, 95, 191);
        chart
            .draw_series(LineSeries::new(
                measured.iter().copied(),
                blue.stroke_width(2),
            ))
            .unwrap()
            .label("each axis' acceleration over the cycle (measured)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], blue));
        let grey = RGBColor(150, 150, 150);
        chart
            .draw_series(LineSeries::new(
                reserve.iter().copied(),
                grey.stroke_width(2),
            ))
            .unwrap()
            .label("the fixed 25 % reserve it replaced")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .unwrap();
        root.present().unwrap();
    }
    std::fs::write(out, svg).unwrap();
}

fn contour_corner_plot(out: &Path) {
    use plotters::prelude::*;
    let sharp = square(None);
    let round = square(Some(DEFAULT_PATH_DEV_MM));
    // Around the corner (100, 0), 1:1: a square window in mm on a square drawing area.
    let (x0, x1, y0, y1) = (99.55, 100.15, -0.15, 0.45);
    let near = |r: &Run| -> Vec<(f64, f64)> {
        r.positions
            .iter()
            .filter(|q| q[0] >= x0 && q[0] <= x1 && q[1] >= y0 && q[1] <= y1)
            .map(|q| (q[0], q[1]))
            .collect()
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1100, 560)).into_drawing_area();
        root.fill(&WHITE).unwrap();
        let (left, right) = root.split_horizontally(560);
        let build = |y1: f64| {
            ChartBuilder::on(&left)
                .caption("corner (100, 0) of the square, 1:1", ("sans-serif", 16))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(50)
                .build_cartesian_2d(x0..x1, y0..y1)
                .unwrap()
        };
        // 1:1: the Y range stretched to the plotting area's aspect (the same caption is
        // drawn twice, in the same place).
        let (w, h) = build(y1).plotting_area().dim_in_pixel();
        let mut chart = build(y0 + (x1 - x0) * f64::from(h) / f64::from(w));
        chart
            .configure_mesh()
            .x_desc("X (mm)")
            .y_desc("Y (mm)")
            .draw()
            .unwrap();
        let grey = RGBColor(150, 150, 150);
        chart
            .draw_series(LineSeries::new(near(&sharp), grey.stroke_width(2)))
            .unwrap()
            .label("programmed (G260: stops)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], grey));
        let blue = RGBColor(31, 95, 191);
        chart
            .draw_series(
                near(&round)
                    .into_iter()
                    .map(|q| Circle::new(q, 2, blue.filled())),
            )
            .unwrap()
            .label("G261, one dot per 1 ms cycle")
            .legend(move |(x, y)| Circle::new((x + 10, y), 3, blue.filled()));
        let red = RGBColor(214, 39, 40);
        let ring: Vec<(f64, f64)> = (0..=100)
            .map(|k| {
                let a = std::f64::consts::FRAC_PI_2 * (1.0 + k as f64 / 100.0);
                (
                    100.0 + DEFAULT_PATH_DEV_MM * a.cos(),
                    DEFAULT_PATH_DEV_MM * a.sin().abs(),
                )
            })
            .collect();
        chart
            .draw_series(LineSeries::new(ring, red.stroke_width(1)))
            .unwrap()
            .label("0.05 mm from the corner")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], red));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .unwrap();
        velocity_panel(&right, &[(&sharp, grey, "G260"), (&round, blue, "G261")]);
        root.present().unwrap();
    }
    std::fs::write(out, svg).unwrap();
}

/// The path velocity of `runs` over the square's first two sides.
fn velocity_panel(
    area: &plotters::drawing::DrawingArea<
        plotters::prelude::SVGBackend<'_>,
        plotters::coord::Shift,
    >,
    runs: &[(&Run, plotters::style::RGBColor, &str)],
) {
    use plotters::prelude::*;
    let t_end = 4.5;
    let mut v = ChartBuilder::on(area)
        .caption("path velocity, F3000", ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0f64..t_end, 0f64..55f64)
        .unwrap();
    v.configure_mesh()
        .x_desc("time (s)")
        .y_desc("v (mm/s)")
        .draw()
        .unwrap();
    for &(r, colour, name) in runs {
        let pts: Vec<(f64, f64)> = r
            .velocities
            .iter()
            .enumerate()
            .map(|(k, v)| ((k + 1) as f64 * DT, *v))
            .take_while(|(t, _)| *t <= t_end)
            .collect();
        v.draw_series(LineSeries::new(pts, colour.stroke_width(2)))
            .unwrap()
            .label(name)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
    }
    v.configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .unwrap();
}
