//! Circle geometry of G2/G3 blocks: centre from I/J/K or R, consistency check, swept angle.

use std::f64::consts::TAU;

use crate::queue::{Move, MoveKind, Plane, Position};

/// Largest circle radius accepted, mm (1 km): beyond any machine's travel, so a larger value
/// is a typing or post-processor error, and a circle of 1e18 mm would never end.
pub const MAX_ARC_RADIUS_MM: f64 = 1.0e6;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ArcError {
    /// Start and end radius differ by more than the tolerance.
    #[error("start radius {r_start_mm} mm and end radius {r_end_mm} mm differ")]
    Inconsistent { r_start_mm: f64, r_end_mm: f64 },
    /// R smaller than half the chord.
    #[error("R {r_mm} mm is smaller than half the chord of {chord_mm} mm")]
    RadiusTooSmall { r_mm: f64, chord_mm: f64 },
    /// Neither centre nor radius, or a zero radius.
    #[error("no centre (I/J/K) or radius (R), or a zero radius")]
    NoCenter,
    /// A centre or radius no real circle has: not finite, or larger than
    /// [`MAX_ARC_RADIUS_MM`].
    #[error("radius {r_mm} mm is not a circle a machine can run (at most 1000000 mm)")]
    TooLarge { r_mm: f64 },
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
    let too_large = |v: f64| !v.is_finite() || v.abs() > MAX_ARC_RADIUS_MM;
    if let Some(v) = [ijk[a], ijk[b], r]
        .into_iter()
        .flatten()
        .find(|&v| too_large(v))
    {
        return Err(ArcError::TooLarge { r_mm: v.abs() });
    }
    let center = if ijk[a].is_some() || ijk[b].is_some() {
        [sa + ijk[a].unwrap_or(0.0), sb + ijk[b].unwrap_or(0.0)]
    } else if let Some(r) = r {
        center_from_radius(sa, sb, ea, eb, r, cw, tolerance_mm)?
    } else {
        return Err(ArcError::NoCenter);
    };
    let r0 = (sa - center[0]).hypot(sb - center[1]);
    let r1 = (ea - center[0]).hypot(eb - center[1]);
    if r0 <= f64::EPSILON {
        return Err(ArcError::NoCenter);
    }
    if too_large(r0) {
        return Err(ArcError::TooLarge { r_mm: r0 });
    }
    if (r0 - r1).abs() > tolerance_mm {
        return Err(ArcError::Inconsistent {
            r_start_mm: r0,
            r_end_mm: r1,
        });
    }
    let a0 = (sb - center[1]).atan2(sa - center[0]);
    let a1 = (eb - center[1]).atan2(ea - center[0]);
    let mut sweep = if cw { a0 - a1 } else { a1 - a0 };
    sweep = sweep.rem_euclid(TAU);
    // Same start and end point: a full circle (only reachable with I/J/K).
    if sweep <= 1e-12 {
        sweep = TAU;
    }
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
    if chord <= f64::EPSILON || ra <= f64::EPSILON {
        return Err(ArcError::NoCenter);
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

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
}
