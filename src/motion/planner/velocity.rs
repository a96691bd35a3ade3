//! The velocity plan: each motion block's nominal velocity, velocity limit and path
//! acceleration, and the backward pass that gives every released block its exit velocity.
//!
//! Every released motion block gets a nominal velocity (programmed feed, G0 at the axes'
//! rapid rates, lowered so no axis exceeds its maximum velocity; arcs also so the centripetal
//! acceleration stays within the axes' limit), a path acceleration (the axis limits projected
//! on the path direction) and an entry velocity limit at its junction with the previous block
//! (planner/junction.rs). A backward pass from the last released block, which always ends at
//! rest, gives every block the highest exit velocity from which everything after it can still
//! brake in time: so a feed that starves is safe, and a block released before the deceleration
//! point lifts the plan without a stop.

use crate::queue::{Move, MoveKind};
use crate::vocab::axis::MAX_AXES;

use super::super::interpolator::tangent;
use super::axes::{AxisTable, JUNCTION_ACCEL_SHARE};
use super::entry::{EntryKind, Segment};
use super::window::Window;

/// Share of the profile acceleration an arc may use for its centripetal acceleration; the
/// tangential ramp gets √(1 − share²) of it, so both together stay within the limit.
const ARC_CENTRIPETAL_SHARE: f64 = 0.5;

/// Backward pass over the released blocks: the last one ends at rest; each block's exit is
/// the next block's admissible entry velocity (`corner_s`: the corner filter's window, s).
///
/// Blocks released before the last plan whose inputs are unchanged stop the pass early: the
/// first of them (from the back) whose exit comes out as before enters as before, and so does
/// everything ahead of it. A window that releases one block at a time then replans a few
/// blocks, not all of them.
pub(super) fn plan(window: &mut Window, corner_s: f64, override_pct: f64, dt_s: f64) {
    let plan_for = [corner_s.to_bits(), override_pct.to_bits(), dt_s.to_bits()];
    let fresh = window.plan_fresh(plan_for);
    let mut next_entry = 0.0_f64;
    let mut stop = true;
    for (i, e) in window.released_mut().enumerate().rev() {
        match &mut e.kind {
            EntryKind::Move(seg) => {
                let exit = if stop { 0.0 } else { next_entry };
                if i < fresh && exit.to_bits() == seg.exit_mm_per_s.to_bits() {
                    break;
                }
                seg.exit_mm_per_s = exit;
                let entry_limit = match seg.junction {
                    None => 0.0,
                    Some(j) => {
                        let prev_cruise = (j.prev_programmed_mm_per_s * override_pct / 100.0)
                            .min(j.prev_limit_mm_per_s);
                        let cruise = seg.cruise_mm_per_s(override_pct);
                        j.limit_mm_per_s(dt_s)
                            .max(j.smoothed_limit_mm_per_s(
                                corner_s,
                                prev_cruise,
                                seg.length_mm,
                                cruise,
                            ))
                            .min(prev_cruise)
                            .min(cruise)
                    }
                };
                let reachable = (seg.exit_mm_per_s * seg.exit_mm_per_s
                    + 2.0 * seg.accel_mm_per_s2 * seg.length_mm)
                    .sqrt();
                next_entry = entry_limit.min(reachable).max(0.0);
                stop = false;
            }
            k if k.is_barrier() => stop = true,
            _ => {}
        }
    }
    window.planned(plan_for);
}

/// A motion block's nominal velocity, velocity limit, path acceleration and (not yet linked)
/// junction.
pub(super) fn segment(axes: &AxisTable, mv: Move) -> Segment {
    let length_mm = mv.length_mm();
    let t0 = tangent(&mv, length_mm, false);
    // Largest share of the path velocity each axis takes anywhere on the block.
    let mut share = [0.0; MAX_AXES];
    for (i, s) in share.iter_mut().enumerate() {
        *s = t0[i].abs();
    }
    let mut curvature = 0.0;
    if let MoveKind::Arc {
        plane,
        radius_mm,
        sweep_rad,
        ..
    } = mv.kind
    {
        let (a, b, _) = plane.axes();
        if length_mm > 0.0 {
            // The circle part's share: on a full turn each plane axis takes all of it.
            let k = radius_mm * sweep_rad / length_mm;
            share[a] = k;
            share[b] = k;
            if radius_mm > 0.0 {
                curvature = k * k / radius_mm;
            }
        }
    }
    let mut limit = f64::INFINITY;
    let mut full = f64::INFINITY;
    let mut rapid = f64::INFINITY;
    let mut min_accel = f64::INFINITY;
    for (i, s) in share.iter().enumerate() {
        if *s <= 1e-12 {
            continue;
        }
        let Some(ax) = axes.get(i) else { continue };
        let vmax = ax.max_velocity_mm_per_min.max(1e-6) / 60.0;
        let amax = ax.max_accel_mm_per_s2.max(1e-6);
        limit = limit.min(vmax / s);
        rapid = rapid.min(ax.rapid_mm_per_min.max(1e-6) / 60.0 / s);
        full = full.min(amax / s);
        min_accel = min_accel.min(amax);
    }
    let mut accel = full * (1.0 - JUNCTION_ACCEL_SHARE);
    if curvature > 0.0 && min_accel.is_finite() {
        // Centripetal v²·κ ≤ share·a; the tangential ramp gets the rest of the vector.
        let reserve_accel = min_accel * (1.0 - JUNCTION_ACCEL_SHARE);
        limit = limit.min((ARC_CENTRIPETAL_SHARE * reserve_accel / curvature).sqrt());
        let tangential = (1.0 - ARC_CENTRIPETAL_SHARE * ARC_CENTRIPETAL_SHARE).sqrt();
        accel = accel.min(tangential * reserve_accel);
    }
    if !limit.is_finite() {
        // No configured axis moves (zero length, or an axis without limits): nothing to
        // limit, the block ends at once or moves at its feed.
        limit = f64::MAX;
    }
    if !accel.is_finite() {
        accel = f64::MAX;
    }
    if !full.is_finite() {
        full = f64::MAX;
    }
    let programmed = match mv.kind {
        MoveKind::Rapid => rapid.min(limit),
        _ => mv.feed_mm_per_min.max(0.0) / 60.0,
    };
    Segment {
        mv,
        length_mm,
        programmed_mm_per_s: programmed,
        limit_mm_per_s: limit,
        accel_mm_per_s2: accel,
        full_accel_mm_per_s2: full,
        end_claim_mm_per_s2: axes.reserve(),
        junction: None,
        exit_mm_per_s: 0.0,
    }
}

/// Path acceleration and jerk limits of a straight move with every axis' full
/// acceleration (no junction reserve: a lone line has no junction), mm/s², mm/s³
/// (infinite: no jerk limit on any moving axis).
pub(super) fn line_limits(axes: &AxisTable, seg: &Segment) -> (f64, f64) {
    let accel = seg.full_accel_mm_per_s2;
    let t = tangent(&seg.mv, seg.length_mm, false);
    let mut jerk = f64::INFINITY;
    for (i, ti) in t.iter().enumerate() {
        let s = ti.abs();
        if s <= 1e-12 {
            continue;
        }
        let Some(j) = axes
            .get(i)
            .and_then(|ax| ax.max_jerk_mm_per_s3)
            .filter(|j| j.is_finite() && *j > 0.0)
        else {
            continue;
        };
        jerk = jerk.min(j / s);
    }
    (accel, jerk)
}
