//! The machine's pace on the shipped settings (`params/`): the R50 circle as one arc and as
//! 36 / 360 / 3,600 chords, the 100 mm square with and without polynomial contouring — times,
//! corner speeds, the deviation from the programmed corner, and every axis' velocity and
//! acceleration on every tick within its limit.

use std::path::Path;
use std::sync::Arc;

mod common;
use common::limit_check::{LimitCheck, DEFAULT_EPS};
use ncchannel::decoder::arc::{arc_move, ArcSpec};
use ncchannel::motion::contour::DEFAULT_PATH_DEV_MM;
use ncchannel::motion::{AxisLimits, Motion, MotionNote, PlannerSettings};
use ncchannel::queue::{
    Action, BlockInfo, BlockQueue, Move, MoveKind, PathMode, Plane, Position, QueuedBlock,
};

const DT: f64 = 0.001;

/// Axis limits and planner settings of the shipped start-up list.
fn shipped() -> (Vec<AxisLimits>, PlannerSettings) {
    let config = ncchannel::params::load(Path::new("params/startup.lis")).unwrap();
    let s = ncchannel::setup::channel_settings(&config, &config.channels[0]).unwrap();
    (s.axes, s.planner)
}

fn block(line: u32, action: Action) -> QueuedBlock {
    QueuedBlock {
        info: BlockInfo {
            prog: Arc::from("t.nc"),
            line,
            offset: 0,
            counter: line as u64,
            n: None,
            text: None,
            stream: false,
        },
        action,
        silent: false,
    }
}

fn p(x: f64, y: f64) -> Position {
    [x, y, 0.0, 0.0, 0.0, 0.0]
}

fn line(start: Position, end: Position, feed: f64, path: PathMode) -> Action {
    Action::Move(Move {
        kind: MoveKind::Line,
        start,
        end,
        feed_mm_per_min: feed,
        path,
    })
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
        m.step(DT, q, &mut notes);
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
    let start = p(50.0, 0.0);
    if n == 0 {
        let spec = ArcSpec {
            plane: Plane::Xy,
            ijk: [Some(-50.0), Some(0.0), None],
            radius: None,
            cw: false,
        };
        let mv = arc_move(&spec, start, start, 6000.0, 1e-6).unwrap();
        q.push(block(1, Action::Move(mv)));
    } else {
        let mut at = start;
        for k in 1..=n {
            let phi = std::f64::consts::TAU * k as f64 / n as f64;
            let to = if k == n {
                start
            } else {
                p(50.0 * phi.cos(), 50.0 * phi.sin())
            };
            q.push(block(k as u32, line(at, to, 6000.0, path)));
            at = to;
        }
    }
    q.push(block(n as u32 + 1, Action::End { m: 30 }));
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
    // A tangent arc of radius 0.1207 mm passed at 80 % of a = 2000 mm/s² centripetal.
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
