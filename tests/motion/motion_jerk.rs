//! Jerk limits and the corner filter, driven directly: blocks into a `BlockQueue`,
//! `Motion::step` per tick, the axes' positions checked by finite differences — every axis'
//! velocity, acceleration and jerk on every tick of random programs, the rest-to-rest time,
//! polylines against the true arc, the memory effect's non-motion blocks.

use crate::support::queued::{block, r50_circle};
use crate::support::random_path::{self, Rng};

use crate::support::limit_check::{LimitCheck, FILTERED_EPS};
use ncchannel::vocab::axis::Position;
use ncchannel::vocab::techno::NoUnits;
use ncchannel::{Action, BlockQueue, CompSide, Move, MoveKind, PathMode, SplineKind};
use ncchannel::{AxisLimits, Motion, MotionNote, PlannerSettings};

const DT: f64 = 0.001;

fn axes(vmax: f64, accel: f64, jerk: Option<f64>) -> Vec<AxisLimits> {
    (0..3)
        .map(|index| AxisLimits {
            index,
            max_velocity_mm_per_min: vmax,
            max_accel_mm_per_s2: accel,
            max_jerk_mm_per_s3: jerk,
            rapid_mm_per_min: vmax,
            min_mm: -1e6,
            max_mm: 1e6,
        })
        .collect()
}

fn settings(lookahead: usize, corner_ms: f64) -> PlannerSettings {
    PlannerSettings {
        lookahead_blocks: lookahead,
        corner_smoothing_s: corner_ms / 1000.0,
    }
}

fn p(x: f64, y: f64, z: f64) -> Position {
    [x, y, z, 0.0, 0.0, 0.0]
}

fn line(start: Position, end: Position, feed: f64) -> Action {
    Action::Move(Box::new(Move {
        kind: MoveKind::Line,
        start,
        end,
        feed_mm_per_min: feed,
        path: PathMode::default(),
    }))
}

/// Run until the program end; every tick's position into `check` (if any). Returns the ticks
/// until the end note and the positions.
fn run_to_end(
    m: &mut Motion,
    q: &mut BlockQueue,
    mut check: Option<&mut LimitCheck>,
    max_ticks: usize,
) -> (usize, Vec<Position>) {
    let mut notes = Vec::new();
    let mut positions = Vec::new();
    if let Some(c) = check.as_deref_mut() {
        c.record(m.position());
    }
    for k in 1..=max_ticks {
        m.step(DT, q, &mut notes, &NoUnits);
        positions.push(m.position());
        if let Some(c) = check.as_deref_mut() {
            c.record(m.position());
        }
        if let Some(MotionNote::Error { code, msg, .. }) =
            notes.iter().find(|n| matches!(n, MotionNote::Error { .. }))
        {
            panic!("motion error {code}: {msg}");
        }
        if notes.iter().any(|n| matches!(n, MotionNote::End { .. })) {
            return (k, positions);
        }
        notes.clear();
    }
    panic!("no program end in {max_ticks} ticks");
}

/// The R50 circle at F6000 as `n` chords (n = 0: the true arc), then M30; seconds to the end.
fn circle_time_s(n: usize, axes: &[AxisLimits], s: PlannerSettings) -> f64 {
    let mut m = Motion::with_planner(axes.to_vec(), s);
    let mut q = BlockQueue::new(1_000_000);
    let start = r50_circle(&mut q, n, PathMode::default());
    m.set_position(start);
    let (ticks, positions) = run_to_end(&mut m, &mut q, None, 200_000);
    assert_eq!(positions.last().copied(), Some(start));
    ticks as f64 * DT
}

#[test]
fn polylines_of_the_r50_circle_run_near_the_true_arc_time() {
    // A jerk-limited machine with the corner filter and a window long enough to brake in.
    let ax = axes(30000.0, 2000.0, Some(20_000.0));
    let s = settings(128, 50.0);
    let arc = circle_time_s(0, &ax, s);
    let t: Vec<f64> = [36, 360, 3600]
        .iter()
        .map(|&n| circle_time_s(n, &ax, s))
        .collect();
    println!("R50 at F6000: arc {arc:.3} s, 36/360/3600 chords {t:?} s");
    for (n, ti) in [36, 360, 3600].iter().zip(&t) {
        assert!(
            (ti - arc).abs() <= 0.1 * arc,
            "{n} chords: {ti} s against the arc's {arc} s"
        );
    }
    for w in t.windows(2) {
        assert!(w[1] <= 1.05 * w[0], "more chords slower: {t:?}");
    }
}

/// The time-optimal rest-to-rest profile for a path of `l` mm with velocity, acceleration and
/// jerk limits `v`, `a`, `j` (j infinite: no jerk limit), s. The textbook cases: both limits
/// reached (jerk phases a/j), only the acceleration (no cruise), only the velocity (peak
/// acceleration √(v·j)), neither (four jerk phases of ∛(l/2j)).
fn optimum_s(l: f64, v: f64, a: f64, j: f64) -> f64 {
    if !j.is_finite() {
        return if l >= v * v / a {
            l / v + v / a
        } else {
            2.0 * (l / a).sqrt()
        };
    }
    let neither = 4.0 * (l / (2.0 * j)).cbrt();
    if v * j >= a * a {
        if l >= v * (v / a + a / j) {
            l / v + v / a + a / j
        } else if l >= 2.0 * a * a * a / (j * j) {
            // l = u·(u/a + a/j) for the peak velocity u.
            let u = 0.5 * a * (-a / j + (a * a / (j * j) + 4.0 * l / a).sqrt());
            2.0 * (u / a + a / j)
        } else {
            neither
        }
    } else if l >= 2.0 * v * (v / j).sqrt() {
        l / v + 2.0 * (v / j).sqrt()
    } else {
        neither
    }
}

/// One straight move from rest to rest (then M30), limits checked every tick: the tick in
/// which the axes first stand at the end point, s.
fn rest_to_rest_s(limits: &[AxisLimits], to: Position, feed: f64) -> f64 {
    let mut m = Motion::with_planner(limits.to_vec(), settings(32, 0.0));
    let mut q = BlockQueue::new(16);
    q.push(block(1, line(p(0.0, 0.0, 0.0), to, feed)));
    q.push(block(2, Action::End { m: 30 }));
    let mut check = LimitCheck::new(limits, DT, FILTERED_EPS);
    let (_, positions) = run_to_end(&mut m, &mut q, Some(&mut check), 100_000);
    if let Err(e) = check.verdict() {
        panic!("{to:?} at F{feed}: {e}");
    }
    assert_eq!(positions.last().copied(), Some(to));
    let k = positions.iter().position(|q| *q == to).unwrap();
    assert!(positions[k..].iter().all(|q| *q == to), "stays at the end");
    (k + 1) as f64 * DT
}

#[test]
fn rest_to_rest_moves_take_the_jerk_limited_optimum_within_one_tick() {
    // (length mm, feed mm/min, acceleration, jerk): the 100 mm at F6000 (only the
    // velocity limit is reached), both limits, only the acceleration limit, neither, and the
    // same move without a jerk limit (the trapezoid at the full acceleration).
    let cases = [
        (100.0, 6000.0, 2000.0, Some(20_000.0)),
        (100.0, 15000.0, 2000.0, Some(20_000.0)),
        (100.0, 30000.0, 2000.0, Some(20_000.0)),
        (10.0, 30000.0, 2000.0, Some(20_000.0)),
        (100.0, 6000.0, 2000.0, None),
        (1.0, 6000.0, 2000.0, None),
    ];
    for (len, feed, a, j) in cases {
        let ax = axes(30000.0, a, j);
        let t = rest_to_rest_s(&ax, p(len, 0.0, 0.0), feed);
        let opt = optimum_s(len, feed / 60.0, a, j.unwrap_or(f64::INFINITY));
        println!("{len} mm at F{feed}, a {a}, j {j:?}: {t:.3} s, optimum {opt:.4} s");
        assert!(
            (t - opt).abs() <= DT + 1e-9,
            "{len} mm at F{feed}, j {j:?}: {t} s against the optimum {opt} s"
        );
    }
    // A diagonal over axes with different limits: the path limits are the axes' projected.
    let mut ax = axes(12000.0, 1500.0, Some(30_000.0));
    ax[1].max_velocity_mm_per_min = 9000.0;
    ax[1].max_accel_mm_per_s2 = 1000.0;
    ax[1].max_jerk_mm_per_s3 = Some(8000.0);
    let (dx, dy) = (80.0_f64, 60.0_f64);
    let l = dx.hypot(dy);
    let (tx, ty) = (dx / l, dy / l);
    let v = (15000.0 / 60.0_f64).min(200.0 / tx).min(150.0 / ty);
    let a = (1500.0 / tx).min(1000.0 / ty);
    let j = (30_000.0 / tx).min(8000.0 / ty);
    let t = rest_to_rest_s(&ax, p(dx, dy, 0.0), 15000.0);
    let opt = optimum_s(l, v, a, j);
    println!("diagonal: {t:.3} s, optimum {opt:.4} s");
    assert!(
        (t - opt).abs() <= DT + 1e-9,
        "diagonal: {t} s against {opt} s"
    );
}

#[test]
fn a_lone_move_keeps_its_limits_through_holds_and_override_changes() {
    let ax = axes(30000.0, 2000.0, Some(20_000.0));
    for (len, feed) in [(300.0, 12000.0), (40.0, 30000.0)] {
        for hold_at in [30usize, 80, 150, 400] {
            let mut m = Motion::with_planner(ax.clone(), settings(32, 0.0));
            let mut q = BlockQueue::new(16);
            let end = p(len, 0.0, 0.0);
            q.push(block(1, line(p(0.0, 0.0, 0.0), end, feed)));
            q.push(block(2, Action::End { m: 30 }));
            let mut check = LimitCheck::new(&ax, DT, FILTERED_EPS);
            check.record(m.position());
            let mut notes = Vec::new();
            let mut ended = false;
            for k in 0..100_000usize {
                match k {
                    _ if k == hold_at => m.set_hold(true),
                    _ if k == hold_at + 120 => m.set_hold(false),
                    _ if k == hold_at + 200 => m.set_override(40.0),
                    _ if k == hold_at + 260 => m.set_override(150.0),
                    _ if k == hold_at + 300 => m.set_override(100.0),
                    _ => {}
                }
                m.step(DT, &mut q, &mut notes, &NoUnits);
                check.record(m.position());
                if notes.iter().any(|n| matches!(n, MotionNote::End { .. })) {
                    ended = true;
                    break;
                }
                notes.clear();
            }
            assert!(ended);
            assert_eq!(m.position(), end);
            if let Err(e) = check.verdict() {
                panic!("{len} mm at F{feed}, hold at tick {hold_at}: {e}");
            }
        }
    }
}

/// Half the lines with G261 (a deviation of 0.01 … 0.5 mm).
fn contoured(a: Action, rng: &mut Rng) -> Action {
    match a {
        Action::Move(mut mv) if rng.next() < 0.5 => {
            mv.path.contour_dev_mm = Some(rng.range(0.01, 0.5));
            Action::Move(mv)
        }
        a => a,
    }
}

/// A random program: rapids, lines (long, short, CAM polylines: a third of them splines, half
/// of the rest contoured), squares with tool radius compensation, arcs and helices in all
/// planes, dwells, M30. Returns the end point.
fn random_program(rng: &mut Rng, q: &mut BlockQueue, blocks: u32) -> Position {
    let mut at = p(0.0, 0.0, 0.0);
    let mut n = 0u32;
    while n < blocks {
        n += 1;
        let kind = rng.next();
        let feed = rng.range(100.0, 15000.0);
        if kind < 0.1 {
            let mv = random_path::rapid(rng, at);
            at = mv.end;
            q.push(block(n, Action::Move(Box::new(mv))));
        } else if kind < 0.4 {
            let mv = random_path::line(rng, at, feed);
            at = mv.end;
            q.push(block(n, contoured(Action::Move(Box::new(mv)), rng)));
        } else if kind < 0.6 {
            // A CAM polyline: 20..200 chords of a circle, radius 5..60 mm.
            let chords = (rng.range(20.0, 200.0)) as usize;
            let r = rng.range(5.0, 60.0);
            let phi0 = rng.range(0.0, 6.3);
            let sweep = rng.range(0.5, 6.0);
            let c = [at[0] - r * phi0.cos(), at[1] - r * phi0.sin()];
            // A third of the polylines as a spline (G151), of either type.
            let spline = match rng.next() {
                x if x < 0.17 => Some(SplineKind::Akima),
                x if x < 0.34 => Some(SplineKind::BSpline),
                _ => None,
            };
            for k in 1..=chords {
                let phi = phi0 + sweep * k as f64 / chords as f64;
                let to = p(c[0] + r * phi.cos(), c[1] + r * phi.sin(), at[2]);
                let a = match (spline, line(at, to, feed)) {
                    (Some(kind), Action::Move(mut mv)) => {
                        mv.path.spline = Some(kind);
                        Action::Move(mv)
                    }
                    (_, a) => contoured(a, rng),
                };
                q.push(block(n, a));
                at = to;
            }
        } else if kind < 0.66 {
            // A square with tool radius compensation (D1, radius 1 mm), G41 or G42, then G40.
            let side = if rng.next() < 0.5 {
                CompSide::Left
            } else {
                CompSide::Right
            };
            let l = rng.range(5.0, 30.0);
            let th = rng.range(0.0, 6.3);
            let (c, s) = (th.cos(), th.sin());
            let corners = [(0.0, 0.0), (l, 0.0), (l, l), (0.0, l), (0.0, 0.0)];
            let base = p(at[0] + 3.0, at[1] + 3.0, at[2]);
            let pts: Vec<Position> = corners
                .iter()
                .map(|(x, y)| p(base[0] + c * x - s * y, base[1] + s * x + c * y, base[2]))
                .collect();
            let comp = PathMode {
                comp: side,
                tool_offset: 1,
                ..PathMode::default()
            };
            let mut from = at;
            for to in &pts {
                q.push(block(
                    n,
                    Action::Move(Box::new(Move {
                        kind: MoveKind::Line,
                        start: from,
                        end: *to,
                        feed_mm_per_min: feed,
                        path: comp,
                    })),
                ));
                from = *to;
            }
            let off = p(from[0] - 3.0, from[1] - 3.0, from[2]);
            q.push(block(n, line(from, off, feed)));
            at = off;
        } else if kind < 0.95 {
            let mv = random_path::arc(rng, at, feed);
            at = mv.end;
            q.push(block(n, Action::Move(Box::new(mv))));
        } else {
            q.push(block(
                n,
                Action::Dwell {
                    seconds: rng.range(0.0, 0.05),
                },
            ));
        }
    }
    q.push(block(n + 1, Action::End { m: 30 }));
    at
}

fn limits_hold_on_random_programs(jerk: Option<f64>, corner_ms: f64, seed: u64) {
    // Different limits per axis, so the projections matter.
    let mut limits = axes(12000.0, 1500.0, jerk.map(|j| j * 1.5));
    limits[1].max_velocity_mm_per_min = 9000.0;
    limits[1].max_accel_mm_per_s2 = 1000.0;
    limits[1].max_jerk_mm_per_s3 = jerk;
    limits[1].rapid_mm_per_min = 8000.0;
    limits[2].max_velocity_mm_per_min = 6000.0;
    limits[2].max_accel_mm_per_s2 = 600.0;
    limits[2].max_jerk_mm_per_s3 = jerk.map(|j| j * 0.5);
    limits[2].rapid_mm_per_min = 6000.0;
    let mut rng = Rng(seed);
    let mut m = Motion::with_planner(limits.clone(), settings(24, corner_ms));
    m.set_tool_radii(vec![(1, 1.0)]);
    let mut q = BlockQueue::new(1_000_000);
    let end = random_program(&mut rng, &mut q, 300);
    let mut check = LimitCheck::new(&limits, DT, FILTERED_EPS);
    let (_, positions) = run_to_end(&mut m, &mut q, Some(&mut check), 5_000_000);
    // The end point exactly, no residue of the filter.
    assert_eq!(positions.last().copied(), Some(end));
    if let Err(e) = check.verdict() {
        panic!("jerk {jerk:?}, corner {corner_ms} ms, seed {seed}: {e}");
    }
}

#[test]
fn every_axis_keeps_velocity_acceleration_and_jerk_on_every_tick() {
    for seed in [0x9E37_79B9_7F4A_7C15, 0x1234_5678_9ABC_DEF1, 77] {
        limits_hold_on_random_programs(Some(20_000.0), 30.0, seed);
        limits_hold_on_random_programs(Some(50_000.0), 0.0, seed);
    }
}

#[test]
fn corner_filter_alone_keeps_velocity_and_acceleration_on_every_tick() {
    for seed in [5, 0xDEAD_BEEF] {
        limits_hold_on_random_programs(None, 50.0, seed);
    }
}
