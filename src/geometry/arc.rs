//! Circle geometry of G2/G3 blocks: centre from I/J/K or R, consistency check, swept angle,
//! and the arc's extent (for the software limits).
//!
//! A circle must be a real one: its centre inside the data format (±214,748.3647 mm, as
//! ISG's 0.1 µm positions in 32 bits; 20020 for I/J/K, 20054 for a centre computed from R),
//! a full circle only from I/J/K (20034), and the swept angle of an R arc computed from the
//! chord, not from two nearly equal `atan2` angles — so a huge radius can neither give NaN
//! positions nor round a short arc into a full circle of that radius.

use std::f64::consts::{PI, TAU};

use super::SoftLimits;
use crate::lang::codes::{
    ARC_CENTER_RANGE, ARC_FULL_CIRCLE_BY_RADIUS, ARC_INCONSISTENT, ARC_RADIUS_RANGE, MAX_COORD_MM,
};
use crate::queue::{Move, MoveKind, Plane};
use crate::vocab::axis::{Position, MAX_AXES};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ArcError {
    /// Start and end radius differ by more than the tolerance.
    #[error("circle not consistent: start radius {r_start_mm} mm, end radius {r_end_mm} mm")]
    Inconsistent { r_start_mm: f64, r_end_mm: f64 },
    /// R smaller than half the chord.
    #[error("circle radius {r_mm} mm smaller than half the chord ({chord_mm} mm)")]
    RadiusTooSmall { r_mm: f64, chord_mm: f64 },
    /// Neither centre nor radius, or a zero radius.
    #[error("circle without centre: no I/J/K or R, or a radius of zero")]
    NoCenter,
    /// R programmed with the end point on the start point: the centre is undetermined.
    #[error("full circle programmed with R: program it with I/J/K")]
    FullCircleByRadius,
    /// The centre lies outside the data format (`from_radius`: computed from R).
    #[error("circle centre {coord_mm} mm outside the data format ±{MAX_COORD_MM} mm")]
    CenterOutOfRange { coord_mm: f64, from_radius: bool },
}

impl ArcError {
    /// The number reported: 20020 / 20054 / 20034 (TF5200 diagnosis list), 900130 (ours)
    /// for an inconsistent circle.
    pub fn code(&self) -> u32 {
        match self {
            ArcError::Inconsistent { .. }
            | ArcError::RadiusTooSmall { .. }
            | ArcError::NoCenter => ARC_INCONSISTENT,
            ArcError::FullCircleByRadius => ARC_FULL_CIRCLE_BY_RADIUS,
            ArcError::CenterOutOfRange {
                from_radius: false, ..
            } => ARC_CENTER_RANGE,
            ArcError::CenterOutOfRange {
                from_radius: true, ..
            } => ARC_RADIUS_RANGE,
        }
    }
}

/// What a G2/G3 block programs besides its end point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcSpec {
    pub plane: Plane,
    /// Centre offsets from the start point per axis X Y Z (I J K); only the two in the
    /// working plane count.
    pub ijk: [Option<f64>; 3],
    /// R > 0: the arc of at most 180°, R < 0: the longer one (ISG/DIN convention).
    pub radius: Option<f64>,
    /// G2.
    pub cw: bool,
}

/// Shortest chord an R arc may have, mm: below the control's 0.1 µm resolution by far, the
/// end point is the start point and the circle undetermined (20034).
const MIN_CHORD_MM: f64 = 1e-9;

/// Build an arc move from `start` to `end`.
pub fn arc_move(
    spec: &ArcSpec,
    start: Position,
    end: Position,
    feed_mm_per_min: f64,
    tolerance_mm: f64,
) -> Result<Move, ArcError> {
    let ArcSpec {
        plane,
        ijk,
        radius: r,
        cw,
    } = *spec;
    let (a, b, _) = plane.axes();
    let (sa, sb, ea, eb) = (start[a], start[b], end[a], end[b]);
    let by_radius = !(ijk[a].is_some() || ijk[b].is_some());
    let center = if !by_radius {
        [sa + ijk[a].unwrap_or(0.0), sb + ijk[b].unwrap_or(0.0)]
    } else if let Some(r) = r {
        center_from_radius(sa, sb, ea, eb, r, cw, tolerance_mm)?
    } else {
        return Err(ArcError::NoCenter);
    };
    for c in center {
        // NaN is refused too: it is not finite.
        if !c.is_finite() || c.abs() > MAX_COORD_MM {
            return Err(ArcError::CenterOutOfRange {
                coord_mm: c,
                from_radius: by_radius,
            });
        }
    }
    let r0 = (sa - center[0]).hypot(sb - center[1]);
    let r1 = (ea - center[0]).hypot(eb - center[1]);
    if r0 <= f64::EPSILON {
        return Err(ArcError::NoCenter);
    }
    if (r0 - r1).abs() > tolerance_mm {
        return Err(ArcError::Inconsistent {
            r_start_mm: r0,
            r_end_mm: r1,
        });
    }
    let sweep = match r {
        // From the chord: exact however large R is against it (two `atan2` angles of a
        // long radius differ by less than their rounding).
        Some(r) if by_radius => {
            let half = (ea - sa).hypot(eb - sb) / 2.0;
            let short = 2.0 * (half / r.abs()).min(1.0).asin();
            if r < 0.0 {
                TAU - short
            } else {
                short
            }
        }
        _ => {
            let a0 = (sb - center[1]).atan2(sa - center[0]);
            let a1 = (eb - center[1]).atan2(ea - center[0]);
            let sweep = if cw { a0 - a1 } else { a1 - a0 }.rem_euclid(TAU);
            // Same start and end point: a full circle (only reachable with I/J/K).
            if sweep <= 1e-12 {
                TAU
            } else {
                sweep
            }
        }
    };
    Ok(Move {
        kind: MoveKind::Arc {
            plane,
            center,
            radius_mm: r0,
            cw,
            sweep_rad: sweep,
        },
        start,
        end,
        feed_mm_per_min,
        path: Default::default(),
    })
}

fn center_from_radius(
    sa: f64,
    sb: f64,
    ea: f64,
    eb: f64,
    r: f64,
    cw: bool,
    tol: f64,
) -> Result<[f64; 2], ArcError> {
    let (dx, dy) = (ea - sa, eb - sb);
    let chord = dx.hypot(dy);
    let ra = r.abs();
    if ra <= f64::EPSILON {
        return Err(ArcError::NoCenter);
    }
    if chord <= MIN_CHORD_MM {
        return Err(ArcError::FullCircleByRadius);
    }
    let half = chord / 2.0;
    let h2 = ra * ra - half * half;
    if h2 < 0.0 && half - ra > tol {
        return Err(ArcError::RadiusTooSmall {
            r_mm: ra,
            chord_mm: chord,
        });
    }
    let h = h2.max(0.0).sqrt();
    let (mx, my) = (sa + dx / 2.0, sb + dy / 2.0);
    // Unit normal to the chord, to the left of the direction start → end.
    let (nx, ny) = (-dy / chord, dx / chord);
    // cw with the short arc: centre to the right of the chord; ccw: to the left.
    // A negative R (long arc) puts it on the other side.
    let left = !cw ^ (r < 0.0);
    let s = if left { h } else { -h };
    Ok([mx + nx * s, my + ny * s])
}

/// The smallest and largest value each axis takes along `mv`: the end points, and for an
/// arc the circle's extreme points in its plane that lie within the swept angle (the axis
/// normal to the plane and any other axis move linearly).
pub(crate) fn extent(mv: &Move) -> (Position, Position) {
    let mut lo = [0.0; MAX_AXES];
    let mut hi = [0.0; MAX_AXES];
    for i in 0..MAX_AXES {
        lo[i] = mv.start[i].min(mv.end[i]);
        hi[i] = mv.start[i].max(mv.end[i]);
    }
    if let Some(c) = mv.arc() {
        // The four quadrant points (angle, axis, value), passed when within the sweep.
        let quadrants = [
            (0.0, c.a, c.center[0] + c.radius_mm),
            (PI / 2.0, c.b, c.center[1] + c.radius_mm),
            (PI, c.a, c.center[0] - c.radius_mm),
            (1.5 * PI, c.b, c.center[1] - c.radius_mm),
        ];
        for (angle, axis, value) in quadrants {
            if (c.dir * (angle - c.start_rad)).rem_euclid(TAU) <= c.sweep_rad {
                lo[axis] = lo[axis].min(value);
                hi[axis] = hi[axis].max(value);
            }
        }
    }
    (lo, hi)
}

/// How far a computed position may pass a software limit by rounding alone, mm: an arc's
/// quadrant point computed as centre + radius may lie 1e-13 mm beyond an end point exactly
/// on the limit, which is allowed (moving *to* a limit is). Far below the 0.1 µm resolution.
pub(crate) const SOFT_LIMIT_SLACK_MM: f64 = 1e-6;

/// The first axis `mv` takes outside its software limits (21897), if any.
///
/// An axis that starts outside its limits (after a reset there, or with limits changed) may
/// move back inside: the bound on that side is its start, so it may not go further out but
/// may return — otherwise such an axis could never move again.
pub(crate) fn outside_limits(
    mv: &Move,
    limits: &[SoftLimits; MAX_AXES],
    enabled: &[bool; MAX_AXES],
) -> Option<LimitBreach> {
    let (lo, hi) = extent(mv);
    for (i, l) in limits.iter().enumerate() {
        if !enabled[i] {
            continue;
        }
        let min_mm = l.min_mm.min(mv.start[i]);
        let max_mm = l.max_mm.max(mv.start[i]);
        let (value_mm, below) = if lo[i] < min_mm - SOFT_LIMIT_SLACK_MM {
            (lo[i], true)
        } else if hi[i] > max_mm + SOFT_LIMIT_SLACK_MM {
            (hi[i], false)
        } else {
            continue;
        };
        return Some(LimitBreach {
            axis: i,
            value_mm,
            below,
            at_end: value_mm == mv.end[i],
            limits: *l,
        });
    }
    None
}

/// Where a move leaves an axis' software limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LimitBreach {
    /// Index into `AXIS_LETTERS`.
    pub axis: usize,
    /// The farthest value outside, mm.
    pub(crate) value_mm: f64,
    /// Below the lower limit (else above the upper).
    pub below: bool,
    /// The value is the move's end point (else a point on the way: an arc's extent).
    pub at_end: bool,
    pub limits: SoftLimits,
}

impl LimitBreach {
    /// The 21897 text: `path` names what reaches the value ("end point", "arc reaches",
    /// "compensated path reaches").
    pub fn message(&self, path: &str) -> String {
        format!(
            "axis {} {path} {} mm, {} software limit (limits {} to {} mm)",
            char::from(crate::vocab::axis::AXIS_LETTERS[self.axis]),
            self.value_mm,
            if self.below {
                "below the lower"
            } else {
                "above the upper"
            },
            self.limits.min_mm,
            self.limits.max_mm
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        super::arc_move(
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

    fn p(x: f64, y: f64) -> Position {
        [x, y, 0.0, 0.0, 0.0, 0.0]
    }

    #[test]
    fn quarter_circle_by_ijk_and_by_r_agree() {
        let a = arc_move(
            Plane::Xy,
            p(10.0, 0.0),
            p(0.0, 10.0),
            [Some(-10.0), Some(0.0), None],
            None,
            false,
            100.0,
            0.01,
        )
        .unwrap();
        let b = arc_move(
            Plane::Xy,
            p(10.0, 0.0),
            p(0.0, 10.0),
            [None; 3],
            Some(10.0),
            false,
            100.0,
            0.01,
        )
        .unwrap();
        for m in [a, b] {
            let MoveKind::Arc {
                center, sweep_rad, ..
            } = m.kind
            else {
                panic!()
            };
            assert!(
                center[0].abs() < 1e-9 && center[1].abs() < 1e-9,
                "{center:?}"
            );
            assert!((sweep_rad - PI / 2.0).abs() < 1e-9);
            assert!((m.length_mm() - 5.0 * PI).abs() < 1e-9);
            let mid = m.point_at(0.5);
            assert!((mid[0] - 10.0 * (PI / 4.0).cos()).abs() < 1e-9);
        }
    }

    #[test]
    fn negative_r_takes_the_long_way() {
        let m = arc_move(
            Plane::Xy,
            p(10.0, 0.0),
            p(0.0, 10.0),
            [None; 3],
            Some(-10.0),
            false,
            100.0,
            0.01,
        )
        .unwrap();
        let MoveKind::Arc { sweep_rad, .. } = m.kind else {
            panic!()
        };
        assert!((sweep_rad - 1.5 * PI).abs() < 1e-9);
    }

    #[test]
    fn inconsistent_centre_is_refused() {
        let e = arc_move(
            Plane::Xy,
            p(10.0, 0.0),
            p(0.0, 10.5),
            [Some(-10.0), Some(0.0), None],
            None,
            true,
            100.0,
            0.01,
        );
        assert!(matches!(e, Err(ArcError::Inconsistent { .. })));
    }

    #[test]
    fn full_circle_and_end_point_exact() {
        let m = arc_move(
            Plane::Xy,
            p(10.0, 0.0),
            p(10.0, 0.0),
            [Some(-10.0), Some(0.0), None],
            None,
            true,
            100.0,
            0.01,
        )
        .unwrap();
        let MoveKind::Arc { sweep_rad, .. } = m.kind else {
            panic!()
        };
        assert!((sweep_rad - 2.0 * PI).abs() < 1e-12);
        assert_eq!(m.point_at(1.0), p(10.0, 0.0));
    }

    #[test]
    fn a_huge_radius_is_refused_not_nan() {
        // `G02 X10 Y0 R1e300` from the origin: the centre is beyond any machine.
        let e = arc_move(
            Plane::Xy,
            p(0.0, 0.0),
            p(10.0, 0.0),
            [None; 3],
            Some(1e300),
            true,
            100.0,
            0.01,
        )
        .unwrap_err();
        assert_eq!(e.code(), ARC_RADIUS_RANGE);
        // `I1000000000000000000`: a circle of 1e18 mm.
        let e = arc_move(
            Plane::Xy,
            p(0.0, 0.0),
            p(10.0, 0.0),
            [Some(1e18), None, None],
            None,
            true,
            100.0,
            0.01,
        )
        .unwrap_err();
        assert_eq!(e.code(), ARC_CENTER_RANGE);
    }

    #[test]
    fn a_long_radius_over_a_short_chord_stays_a_short_arc() {
        // 2e5 mm radius over a 1 µm chord: the two atan2 angles are equal in f64, which
        // once made this a full circle of 1.3e6 mm.
        let m = arc_move(
            Plane::Xy,
            p(0.0, 0.0),
            p(0.001, 0.0),
            [None; 3],
            Some(200_000.0),
            true,
            100.0,
            0.01,
        )
        .unwrap();
        assert!(m.length_mm() < 0.0011, "{}", m.length_mm());
        let e = arc_move(
            Plane::Xy,
            p(5.0, 5.0),
            p(5.0, 5.0),
            [None; 3],
            Some(10.0),
            true,
            100.0,
            0.01,
        )
        .unwrap_err();
        assert_eq!(e.code(), ARC_FULL_CIRCLE_BY_RADIUS);
    }

    #[test]
    fn extent_holds_the_quadrant_points_passed() {
        // Half circle ccw from (10, 0) around the origin to (-10, 0): passes (0, 10).
        let m = arc_move(
            Plane::Xy,
            p(10.0, 0.0),
            p(-10.0, 0.0),
            [Some(-10.0), Some(0.0), None],
            None,
            false,
            100.0,
            0.01,
        )
        .unwrap();
        let (lo, hi) = extent(&m);
        assert_eq!((lo[0], hi[0]), (-10.0, 10.0));
        assert!(
            (hi[1] - 10.0).abs() < 1e-12 && lo[1] == 0.0,
            "{lo:?} {hi:?}"
        );
        // The same half clockwise passes (0, -10) instead.
        let m = arc_move(
            Plane::Xy,
            p(10.0, 0.0),
            p(-10.0, 0.0),
            [Some(-10.0), Some(0.0), None],
            None,
            true,
            100.0,
            0.01,
        )
        .unwrap();
        let (lo, hi) = extent(&m);
        assert!(
            (lo[1] + 10.0).abs() < 1e-12 && hi[1] == 0.0,
            "{lo:?} {hi:?}"
        );
        // A full circle spans its whole box.
        let m = arc_move(
            Plane::Xy,
            p(10.0, 0.0),
            p(10.0, 0.0),
            [Some(-10.0), Some(0.0), None],
            None,
            true,
            100.0,
            0.01,
        )
        .unwrap();
        let (lo, hi) = extent(&m);
        assert!((lo[0] + 10.0).abs() < 1e-12 && (hi[1] - 10.0).abs() < 1e-12);
        assert!((lo[1] + 10.0).abs() < 1e-12 && hi[0] == 10.0);
    }
}
