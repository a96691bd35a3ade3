//! Motion driven directly: blocks into a `BlockQueue`, `Motion::step` per tick, positions and
//! notes observed — planner release rules, the trapezoid timing, exact end points, hold,
//! override, and the axis limits on every tick of a long random program.

use crate::support::queued::block;
use crate::support::random_path::{self, Rng};

use crate::support::limit_check::{LimitCheck, DEFAULT_EPS};
use ncchannel::vocab::axis::Position;
use ncchannel::vocab::flush::FlushKind;
use ncchannel::vocab::techno::NoUnits;
use ncchannel::JUNCTION_ACCEL_SHARE;
use ncchannel::{Action, BlockQueue, Move, MoveKind, PathMode, Plane};
use ncchannel::{ArcError, ArcSpec};
use ncchannel::{AxisLimits, Motion, MotionNote, PlannerSettings};

/// The positional form reads best in these tables of cases.
#[allow(clippy::too_many_arguments)]
fn arc_move(
    plane: Plane,
    start: Position,
    end: Position,
    ijk: [Option<f64>; 3],
    radius: Option<f64>,
    cw: bool,
    feed: f64,
    tol: f64,
) -> Result<Move, ArcError> {
    ncchannel::arc_move(
        &ArcSpec {
            plane,
            ijk,
            radius,
            cw,
        },
        start,
        end,
        feed,
        tol,
    )
}

const DT: f64 = 0.001;

fn axes(vmax_mm_per_min: f64, accel: f64) -> Vec<AxisLimits> {
    (0..3)
        .map(|index| AxisLimits {
            index,
            max_velocity_mm_per_min: vmax_mm_per_min,
            max_accel_mm_per_s2: accel,
            max_jerk_mm_per_s3: None,
            rapid_mm_per_min: vmax_mm_per_min,
            min_mm: -1000.0,
            max_mm: 1000.0,
        })
        .collect()
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

fn p(x: f64, y: f64, z: f64) -> Position {
    [x, y, z, 0.0, 0.0, 0.0]
}

/// Step until the program end (or `max` ticks); returns (tick, note) pairs and positions.
fn run(
    m: &mut Motion,
    q: &mut BlockQueue,
    max: usize,
) -> (Vec<(usize, MotionNote)>, Vec<Position>) {
    let mut notes = Vec::new();
    let mut all = Vec::new();
    let mut positions = Vec::new();
    for k in 1..=max {
        m.step(DT, q, &mut notes, &NoUnits);
        positions.push(m.position());
        let ended = notes.iter().any(|n| matches!(n, MotionNote::End { .. }));
        all.extend(notes.drain(..).map(|n| (k, n)));
        if ended {
            break;
        }
    }
    (all, positions)
}

fn started_lines(notes: &[(usize, MotionNote)]) -> Vec<(usize, u32)> {
    notes
        .iter()
        .filter_map(|(k, n)| match n {
            MotionNote::Started(i) => Some((*k, i.line)),
            _ => None,
        })
        .collect()
}

/// Trapezoid time of one block: from `v_in` to `v_out` with cruise `vc` and acceleration `a`.
fn trapezoid_s(len: f64, vc: f64, a: f64, v_in: f64, v_out: f64) -> f64 {
    let d_up = (vc * vc - v_in * v_in) / (2.0 * a);
    let d_down = (vc * vc - v_out * v_out) / (2.0 * a);
    assert!(
        d_up + d_down <= len,
        "this helper is for blocks that reach cruise"
    );
    (vc - v_in) / a + (vc - v_out) / a + (len - d_up - d_down) / vc
}

#[test]
fn square_at_f1000_reaches_each_corner_when_the_trapezoid_says() {
    let a_axis = 2000.0;
    let mut m = Motion::new(axes(30000.0, a_axis));
    let mut q = BlockQueue::new(64);
    let corners = [
        p(0.0, 0.0, 0.0),
        p(10.0, 0.0, 0.0),
        p(10.0, 10.0, 0.0),
        p(0.0, 10.0, 0.0),
        p(0.0, 0.0, 0.0),
    ];
    for i in 0..4 {
        q.push(block(
            i as u32 + 1,
            line(corners[i], corners[i + 1], 1000.0),
        ));
    }
    q.push(block(5, Action::End { m: 30 }));
    let (notes, positions) = run(&mut m, &mut q, 10_000);

    // The documented rules: path acceleration = (1 − share)·a on an axis-parallel line; a 90°
    // corner jumps each axis' direction by 1, so v ≤ share·a·dt.
    let a = (1.0 - JUNCTION_ACCEL_SHARE) * a_axis;
    let vc = 1000.0 / 60.0;
    let vj = JUNCTION_ACCEL_SHARE * a_axis * DT;
    let seg = [
        trapezoid_s(10.0, vc, a, 0.0, vj),
        trapezoid_s(10.0, vc, a, vj, vj),
        trapezoid_s(10.0, vc, a, vj, vj),
        trapezoid_s(10.0, vc, a, vj, 0.0),
    ];
    let starts = started_lines(&notes);
    assert_eq!(
        starts.iter().map(|s| s.1).collect::<Vec<_>>(),
        vec![1, 2, 3, 4, 5]
    );
    let mut t_pred = 0.0;
    for (i, d) in seg.iter().enumerate() {
        t_pred += d;
        // Block i+2 starts in the tick in which block i+1 reached its corner.
        let tick = starts[i + 1].0 as f64;
        let t_end_of_tick = tick * DT;
        assert!(
            t_end_of_tick >= t_pred - 1e-9 && t_end_of_tick - t_pred < DT + 1e-9,
            "corner {} predicted at {t_pred:.6} s, reached in the tick ending {t_end_of_tick:.6} s",
            i + 1
        );
    }
    // Exactly at the programmed end point, and every tick on the square's edges.
    assert_eq!(m.position(), corners[4]);
    for q in &positions {
        let on_x_edge = (q[1].abs() < 1e-9 || (q[1] - 10.0).abs() < 1e-9)
            && (-1e-9..=10.0 + 1e-9).contains(&q[0]);
        let on_y_edge = (q[0].abs() < 1e-9 || (q[0] - 10.0).abs() < 1e-9)
            && (-1e-9..=10.0 + 1e-9).contains(&q[1]);
        assert!(on_x_edge || on_y_edge, "{q:?} is off the square");
    }
}

#[test]
fn arc_ends_exactly_at_its_end_point_and_stays_on_the_circle() {
    for plane in [Plane::Xy, Plane::Zx, Plane::Yz] {
        let (a, b, n) = plane.axes();
        let mut start = [0.0; 6];
        let mut end = [0.0; 6];
        start[a] = 10.0;
        end[a] = -10.0 / 2f64.sqrt();
        end[b] = 10.0 / 2f64.sqrt();
        end[n] = 3.0; // helix
        let mut ijk = [None; 3];
        ijk[a] = Some(-10.0);
        ijk[b] = Some(0.0);
        let mv = arc_move(plane, start, end, ijk, None, false, 3000.0, 0.01).unwrap();
        let mut m = Motion::new(axes(30000.0, 2000.0));
        m.set_position(start);
        let mut q = BlockQueue::new(8);
        q.push(block(1, Action::Move(Box::new(mv))));
        q.push(block(2, Action::End { m: 30 }));
        let (_, positions) = run(&mut m, &mut q, 100_000);
        assert_eq!(m.position(), end, "{plane:?}");
        for q in &positions {
            let r = q[a].hypot(q[b]);
            assert!((r - 10.0).abs() < 1e-9, "{plane:?}: radius {r}");
            assert!((0.0..=3.0 + 1e-12).contains(&q[n]));
        }
    }
}

#[test]
fn inconsistent_ijk_beyond_the_tolerance_is_refused() {
    let start = p(10.0, 0.0, 0.0);
    let end = p(0.0, 10.05, 0.0);
    let r = arc_move(
        Plane::Xy,
        start,
        end,
        [Some(-10.0), Some(0.0), None],
        None,
        false,
        1000.0,
        0.01,
    );
    assert!(r.is_err());
    let ok = arc_move(
        Plane::Xy,
        start,
        p(0.0, 10.005, 0.0),
        [Some(-10.0), Some(0.0), None],
        None,
        false,
        1000.0,
        0.01,
    );
    assert!(ok.is_ok());
}

#[test]
fn blocks_are_held_until_the_window_is_full_then_run_without_stopping() {
    let mut m = Motion::with_planner(
        axes(30000.0, 2000.0),
        PlannerSettings {
            lookahead_blocks: 4,
            ..PlannerSettings::default()
        },
    );
    let mut q = BlockQueue::new(64);
    let mut notes = Vec::new();
    let mut at = p(0.0, 0.0, 0.0);
    let mut push = |q: &mut BlockQueue, n: u32| {
        let to = p(at[0] + 5.0, 0.0, 0.0);
        q.push(block(n, line(at, to, 6000.0)));
        at = to;
    };
    for n in 1..=3 {
        push(&mut q, n);
    }
    for _ in 0..50 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
    }
    // Three of four: held, nothing runs, and motion says it waits for data.
    assert!(notes.is_empty());
    assert_eq!(m.position(), p(0.0, 0.0, 0.0));
    assert_eq!(m.held_blocks(), 3);
    assert!(m.waiting_for_data());
    assert!(!m.idle());
    // The fourth fills the window: all four run.
    push(&mut q, 4);
    m.step(DT, &mut q, &mut notes, &NoUnits);
    assert_eq!(m.held_blocks(), 0);
    assert!(m.position()[0] > 0.0);
    // Feed one block per tick while they run: the window stays full, the motion never stops.
    let mut n = 5;
    let mut min_v_after_start = f64::INFINITY;
    for _ in 0..300 {
        if q.is_empty() && n <= 40 {
            push(&mut q, n);
            n += 1;
        }
        m.step(DT, &mut q, &mut notes, &NoUnits);
        if m.position()[0] > 1.0 && m.position()[0] < 150.0 {
            min_v_after_start = min_v_after_start.min(m.velocity_mm_per_s());
        }
    }
    assert!(min_v_after_start > 50.0, "slowed to {min_v_after_start}");
    let lines: Vec<u32> = notes
        .iter()
        .filter_map(|n| match n {
            MotionNote::Started(i) => Some(i.line),
            _ => None,
        })
        .collect();
    assert_eq!(lines, (1..lines.len() as u32 + 1).collect::<Vec<_>>());
}

#[test]
fn flush_continue_releases_and_the_next_block_in_time_continues_without_stop() {
    for (late, expect_stop) in [(false, false), (true, true)] {
        let mut m = Motion::new(axes(30000.0, 2000.0));
        let mut q = BlockQueue::new(64);
        let mut notes = Vec::new();
        q.push(block(1, line(p(0.0, 0.0, 0.0), p(10.0, 0.0, 0.0), 1000.0)));
        q.push(block(2, Action::Flush(FlushKind::Continue)));
        let arrive_tick = if late { 900 } else { 300 };
        let mut stopped_between = false;
        for k in 1..=2000 {
            if k == arrive_tick {
                q.push(block(3, line(p(10.0, 0.0, 0.0), p(20.0, 0.0, 0.0), 1000.0)));
                q.push(block(4, Action::End { m: 30 }));
            }
            m.step(DT, &mut q, &mut notes, &NoUnits);
            let x = m.position()[0];
            if x > 1.0 && x < 19.0 && m.velocity_mm_per_s() == 0.0 {
                stopped_between = true;
            }
        }
        assert_eq!(stopped_between, expect_stop, "late = {late}");
        assert_eq!(m.position(), p(20.0, 0.0, 0.0));
        assert!(notes.contains(&MotionNote::Flush(FlushKind::Continue)));
    }
}

#[test]
fn plain_flush_stops_at_the_last_block_even_with_the_next_in_time() {
    let mut m = Motion::new(axes(30000.0, 2000.0));
    let mut q = BlockQueue::new(64);
    let mut notes = Vec::new();
    q.push(block(1, line(p(0.0, 0.0, 0.0), p(10.0, 0.0, 0.0), 1000.0)));
    q.push(block(2, Action::Flush(FlushKind::Stop)));
    q.push(block(3, line(p(10.0, 0.0, 0.0), p(20.0, 0.0, 0.0), 1000.0)));
    q.push(block(4, Action::End { m: 30 }));
    // The stop falls inside a tick; the tick-end velocities around it are at most a·dt.
    let mut v_min_near_10 = f64::INFINITY;
    for _ in 0..3000 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
        let x = m.position()[0];
        if (9.9..=10.1).contains(&x) {
            v_min_near_10 = v_min_near_10.min(m.velocity_mm_per_s());
        }
    }
    assert!(v_min_near_10 <= 1500.0 * DT + 1e-9, "{v_min_near_10}");
    assert_eq!(m.position()[0], 20.0);
}

#[test]
fn dwell_stops_and_waits_and_m_functions_do_not_stop() {
    let mut m = Motion::new(axes(30000.0, 2000.0));
    let mut q = BlockQueue::new(64);
    q.push(block(1, line(p(0.0, 0.0, 0.0), p(10.0, 0.0, 0.0), 3000.0)));
    q.push(block(2, Action::None)); // an M function between two collinear moves
    q.push(block(3, line(p(10.0, 0.0, 0.0), p(20.0, 0.0, 0.0), 3000.0)));
    q.push(block(4, Action::Dwell { seconds: 0.5 }));
    q.push(block(5, line(p(20.0, 0.0, 0.0), p(30.0, 0.0, 0.0), 3000.0)));
    q.push(block(6, Action::End { m: 30 }));
    let mut notes = Vec::new();
    let mut v_at_10 = None;
    let mut ticks_at_20 = 0;
    for _ in 0..5000 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
        let x = m.position()[0];
        if (x - 10.0).abs() < 0.06 && v_at_10.is_none() {
            v_at_10 = Some(m.velocity_mm_per_s());
        }
        if x == 20.0 {
            ticks_at_20 += 1;
            assert_eq!(m.velocity_mm_per_s(), 0.0);
        }
    }
    assert!(v_at_10.unwrap() > 49.0, "{v_at_10:?}");
    assert!((500..=502).contains(&ticks_at_20), "{ticks_at_20}");
    assert_eq!(m.position()[0], 30.0);
    let order: Vec<u32> = notes
        .iter()
        .filter_map(|n| match n {
            MotionNote::Started(i) => Some(i.line),
            _ => None,
        })
        .collect();
    assert_eq!(order, vec![1, 2, 3, 4, 5, 6]);
}

#[test]
fn hold_brakes_on_the_path_and_resume_reaches_the_end() {
    let a_axis = 2000.0;
    let mut m = Motion::new(axes(30000.0, a_axis));
    let mut q = BlockQueue::new(8);
    let end = p(100.0, 50.0, 0.0);
    q.push(block(1, line(p(0.0, 0.0, 0.0), end, 6000.0)));
    q.push(block(2, Action::End { m: 30 }));
    let mut notes = Vec::new();
    let mut check = LimitCheck::new(&axes(30000.0, a_axis), DT, DEFAULT_EPS);
    for _ in 0..300 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
        check.record(m.position());
    }
    assert!(m.velocity_mm_per_s() > 99.0);
    m.set_hold(true);
    let mut ticks = 0;
    while m.velocity_mm_per_s() > 0.0 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
        check.record(m.position());
        ticks += 1;
        assert!(ticks < 1000);
    }
    // A lone line (rest to rest, nothing to blend) brakes at the full axis acceleration
    // projected on the path, 2000 / cos(26.6°) = 2236 mm/s²: 100 mm/s in about 45 ms.
    assert!((43..=47).contains(&ticks), "{ticks}");
    let held_at = m.position();
    assert!((held_at[1] - held_at[0] / 2.0).abs() < 1e-9, "on the path");
    for _ in 0..100 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
    }
    assert_eq!(m.position(), held_at);
    assert!(!m.waiting_for_data(), "a hold is not a lack of data");
    m.set_hold(false);
    for _ in 0..5000 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
        check.record(m.position());
    }
    assert_eq!(m.position(), end);
    check.verdict().unwrap();
}

#[test]
fn override_scales_the_feed_and_zero_stops_on_the_path() {
    let mut m = Motion::new(axes(30000.0, 2000.0));
    let mut q = BlockQueue::new(8);
    q.push(block(1, line(p(0.0, 0.0, 0.0), p(500.0, 0.0, 0.0), 6000.0)));
    q.push(block(2, Action::End { m: 30 }));
    let mut notes = Vec::new();
    for _ in 0..500 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
    }
    assert!((m.velocity_mm_per_s() - 100.0).abs() < 1e-9);
    m.set_override(50.0);
    for _ in 0..500 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
    }
    assert!((m.velocity_mm_per_s() - 50.0).abs() < 1e-9);
    m.set_override(200.0);
    for _ in 0..500 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
    }
    assert!((m.velocity_mm_per_s() - 200.0).abs() < 1e-9);
    m.set_override(0.0);
    for _ in 0..500 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
    }
    assert_eq!(m.velocity_mm_per_s(), 0.0);
    let x = m.position()[0];
    m.step(DT, &mut q, &mut notes, &NoUnits);
    assert_eq!(m.position()[0], x);
    assert!(!m.waiting_for_data(), "override 0 is not a lack of data");
}

#[test]
fn override_above_100_never_exceeds_the_axis_limit() {
    let mut m = Motion::new(axes(6000.0, 2000.0));
    let mut q = BlockQueue::new(8);
    q.push(block(1, line(p(0.0, 0.0, 0.0), p(500.0, 0.0, 0.0), 6000.0)));
    q.push(block(2, Action::End { m: 30 }));
    m.set_override(200.0);
    let mut notes = Vec::new();
    for _ in 0..1000 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
    }
    assert!((m.velocity_mm_per_s() - 100.0).abs() < 1e-9);
}

#[test]
fn reset_stops_at_once_and_forgets_the_window() {
    let mut m = Motion::new(axes(30000.0, 2000.0));
    let mut q = BlockQueue::new(8);
    q.push(block(1, line(p(0.0, 0.0, 0.0), p(500.0, 0.0, 0.0), 6000.0)));
    q.push(block(2, Action::End { m: 30 }));
    let mut notes = Vec::new();
    for _ in 0..100 {
        m.step(DT, &mut q, &mut notes, &NoUnits);
    }
    let x = m.position()[0];
    m.reset();
    assert_eq!(m.velocity_mm_per_s(), 0.0);
    assert!(m.idle());
    m.step(DT, &mut q, &mut notes, &NoUnits);
    assert_eq!(m.position()[0], x);
}

/// Different limits per axis, so the projections matter.
fn mixed_limits() -> Vec<AxisLimits> {
    vec![
        AxisLimits {
            index: 0,
            max_velocity_mm_per_min: 12000.0,
            max_accel_mm_per_s2: 1500.0,
            max_jerk_mm_per_s3: None,
            rapid_mm_per_min: 12000.0,
            min_mm: -1e6,
            max_mm: 1e6,
        },
        AxisLimits {
            index: 1,
            max_velocity_mm_per_min: 9000.0,
            max_accel_mm_per_s2: 1000.0,
            max_jerk_mm_per_s3: None,
            rapid_mm_per_min: 8000.0,
            min_mm: -1e6,
            max_mm: 1e6,
        },
        AxisLimits {
            index: 2,
            max_velocity_mm_per_min: 6000.0,
            max_accel_mm_per_s2: 600.0,
            max_jerk_mm_per_s3: None,
            rapid_mm_per_min: 6000.0,
            min_mm: -1e6,
            max_mm: 1e6,
        },
    ]
}

#[test]
fn velocity_and_acceleration_stay_within_the_axis_limits_on_every_tick() {
    let limits = mixed_limits();
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut m = Motion::with_planner(
        limits.clone(),
        PlannerSettings {
            lookahead_blocks: 16,
            ..PlannerSettings::default()
        },
    );
    let mut q = BlockQueue::new(1_000_000);
    let mut at = p(0.0, 0.0, 0.0);
    for n in 0..1500u32 {
        let kind = rng.next();
        let feed = rng.range(100.0, 15000.0);
        let action = if kind < 0.1 {
            let mv = random_path::rapid(&mut rng, at);
            at = mv.end;
            Action::Move(Box::new(mv))
        } else if kind < 0.55 {
            // Short and long lines, some nearly collinear chains of tiny segments.
            let mv = random_path::line(&mut rng, at, feed);
            at = mv.end;
            Action::Move(Box::new(mv))
        } else if kind < 0.9 {
            let mv = random_path::arc(&mut rng, at, feed);
            at = mv.end;
            Action::Move(Box::new(mv))
        } else if kind < 0.95 {
            Action::None
        } else {
            Action::Dwell {
                seconds: rng.range(0.0, 0.02),
            }
        };
        q.push(block(n + 1, action));
    }
    q.push(block(9999, Action::End { m: 30 }));
    let mut check = LimitCheck::new(&limits, DT, DEFAULT_EPS);
    check.record(m.position());
    let mut notes = Vec::new();
    let mut ended = false;
    let mut ticks = 0u64;
    while !ended && ticks < 5_000_000 {
        ticks += 1;
        // Override changes and a hold in the middle are part of the program's life.
        match ticks {
            20_000 => m.set_override(60.0),
            30_000 => m.set_override(150.0),
            40_000 => m.set_hold(true),
            40_500 => m.set_hold(false),
            50_000 => m.set_override(100.0),
            _ => {}
        }
        m.step(DT, &mut q, &mut notes, &NoUnits);
        check.record(m.position());
        ended = notes.iter().any(|n| matches!(n, MotionNote::End { .. }));
        notes.clear();
    }
    assert!(ended, "program did not end in {ticks} ticks");
    assert_eq!(
        m.position(),
        at,
        "ends exactly at the last programmed point"
    );
    check.verdict().unwrap();
    // The check is not vacuous: the motion came close to the limits somewhere.
    let best_v = check
        .worst_velocity
        .iter()
        .map(|w| w.ratio)
        .fold(0.0, f64::max);
    let best_a = check
        .worst_accel
        .iter()
        .map(|w| w.ratio)
        .fold(0.0, f64::max);
    assert!(best_v > 0.9 && best_a > 0.7, "v {best_v}, a {best_a}");
}
