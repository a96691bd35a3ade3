//! Contouring: the corner between two straight blocks replaced by a circular arc tangent to
//! both, whose middle lies at most the permitted deviation from the programmed corner — the
//! kernel's G261/G61 with `#CONTOUR MODE [DEV PATH_DEV=…]` (ISG programming manual, "Contouring
//! mode"; the bracket syntax as written by CAM post-processors, e.g. `#CONTOUR MODE [DEV
//! PATH_DEV=2 CONST_VEL=1]`).
//!
//! Why an arc. The path stays tangent-continuous, so the corner costs no velocity jump; the
//! arc's centripetal acceleration v²/r bounds the speed through it like any programmed arc,
//! and the axis filter (if on) turns the step in curvature into a jerk-limited ramp. The arc
//! of a corner with direction change θ and deviation δ has radius r = δ·cos(θ/2)/(1 − cos(θ/2))
//! and cuts d = r·tan(θ/2) off both blocks; d is capped at half the next block and half of what
//! the previous block has left, so blends never overlap and no line shrinks to nothing (the
//! radius, and with it the deviation, shrinks instead).

use crate::queue::{Move, MoveKind, Plane};
use crate::vocab::axis::{Position, MAX_AXES};

/// Corners turning less than this are left alone (collinear within rounding), rad.
const MIN_TURN_RAD: f64 = 1e-7;
/// Corners turning more than π minus this (a reversal) are left sharp, rad.
const MAX_TURN_MARGIN_RAD: f64 = 1e-3;

/// The blend of the corner between lines `prev` (ending at the corner) and `next` (starting
/// there), or `None` when the corner stays sharp (not two lines, not in one of the planes
/// G17/G18/G19, collinear, a reversal, zero deviation, or nothing left to cut).
///
/// Returns the new end of `prev`, the arc, and the new start of `next`.
pub(crate) fn blend(prev: &Move, next: &Move, dev_mm: f64) -> Option<(Position, Move, Position)> {
    if !(matches!(prev.kind, MoveKind::Line) && matches!(next.kind, MoveKind::Line)) {
        return None;
    }
    if !(dev_mm.is_finite() && dev_mm > 0.0) {
        return None;
    }
    let corner = prev.end;
    let plane = plane_of(prev, next)?;
    let (a, b, _) = plane.axes();
    let d1 = [prev.end[a] - prev.start[a], prev.end[b] - prev.start[b]];
    let d2 = [next.end[a] - next.start[a], next.end[b] - next.start[b]];
    let (l1, l2) = (d1[0].hypot(d1[1]), d2[0].hypot(d2[1]));
    if l1 <= 0.0 || l2 <= 0.0 {
        return None;
    }
    let u1 = [d1[0] / l1, d1[1] / l1];
    let u2 = [d2[0] / l2, d2[1] / l2];
    let cross = u1[0] * u2[1] - u1[1] * u2[0];
    let dot = (u1[0] * u2[0] + u1[1] * u2[1]).clamp(-1.0, 1.0);
    let turn = cross.atan2(dot).abs();
    if !(MIN_TURN_RAD..std::f64::consts::PI - MAX_TURN_MARGIN_RAD).contains(&turn) {
        return None;
    }
    let half = 0.5 * turn;
    let mut r = dev_mm * half.cos() / (1.0 - half.cos());
    let mut cut = r * half.tan();
    // Half of each block at most, and half of what an earlier blend left of `prev`: no blend
    // eats a block (a line of nearly no length has no usable direction).
    let max_cut = 0.5 * l2.min(l1);
    if cut > max_cut {
        cut = max_cut;
        r = cut / half.tan();
    }
    if !(cut > 1e-9 && r > 1e-9) {
        return None;
    }
    let mut p1 = corner;
    p1[a] -= u1[0] * cut;
    p1[b] -= u1[1] * cut;
    let mut p2 = corner;
    p2[a] += u2[0] * cut;
    p2[b] += u2[1] * cut;
    // Centre: from p1 along the normal towards the inside of the turn.
    let ccw = cross > 0.0;
    let n = if ccw {
        [-u1[1], u1[0]]
    } else {
        [u1[1], -u1[0]]
    };
    let center = [p1[a] + n[0] * r, p1[b] + n[1] * r];
    let arc = Move {
        kind: MoveKind::Arc {
            plane,
            center,
            radius_mm: r,
            cw: !ccw,
            sweep_rad: turn,
        },
        start: p1,
        end: p2,
        feed_mm_per_min: next.feed_mm_per_min,
        path: next.path,
    };
    Some((p1, arc, p2))
}

/// The working plane both lines lie in (every other axis constant on both), G17 first.
fn plane_of(prev: &Move, next: &Move) -> Option<Plane> {
    [Plane::Xy, Plane::Zx, Plane::Yz].into_iter().find(|p| {
        let (a, b, _) = p.axes();
        (0..MAX_AXES)
            .filter(|&i| i != a && i != b)
            .all(|i| prev.start[i] == prev.end[i] && next.start[i] == next.end[i])
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::queue::PathMode;

    fn line(x0: f64, y0: f64, x1: f64, y1: f64) -> Move {
        Move {
            kind: MoveKind::Line,
            start: [x0, y0, 0.0, 0.0, 0.0, 0.0],
            end: [x1, y1, 0.0, 0.0, 0.0, 0.0],
            feed_mm_per_min: 3000.0,
            path: PathMode::default(),
        }
    }

    #[test]
    fn the_square_corner_blend_deviates_by_the_permitted_amount() {
        let (p1, arc, p2) = blend(
            &line(0.0, 0.0, 50.0, 0.0),
            &line(50.0, 0.0, 50.0, 50.0),
            0.05,
        )
        .unwrap();
        let mid = arc.point_at(0.5);
        let dev = (mid[0] - 50.0).hypot(mid[1]);
        assert!((dev - 0.05).abs() < 1e-12, "{dev}");
        assert!((p1[0] - (50.0 - (p2[1]))).abs() < 1e-12);
        let MoveKind::Arc { cw, radius_mm, .. } = arc.kind else {
            panic!()
        };
        assert!(!cw);
        assert!((radius_mm - 0.05 / (2f64.sqrt() - 1.0)).abs() < 1e-12);
    }
}
