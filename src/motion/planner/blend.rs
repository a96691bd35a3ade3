//! Contour blends (G261 / G61 corner rounding): the arc that replaces a corner between the
//! window's last motion block and the next one, and the dynamics it is passed with.

use crate::queue::Move;

use super::super::contour;
use super::axes::AxisTable;
use super::entry::Segment;
use super::window::Window;

/// Share of the axes' full acceleration a contour blend may use for its centripetal
/// acceleration; its tangential ramp gets √(1 − share²) of it.
const BLEND_CENTRIPETAL_SHARE: f64 = 0.8;
/// Share of the smallest moving axis' acceleration a contour blend uses in all: sampled once
/// per cycle, a curve under centripetal and tangential acceleration at once shows slightly
/// more than the vector's length (0.07 % measured at the full length).
const BLEND_ACCEL_SHARE: f64 = 0.95;

/// A contour blend is passed at what the axes allow: of the smallest moving axis' full
/// acceleration, what passing at feed takes for the centripetal part (at most
/// [`BLEND_CENTRIPETAL_SHARE`]), the rest of the vector for the tangential ramp (a programmed arc keeps the junction reserve and the
/// even split: it may be long and start or end at a corner). A blend is tangent to both
/// lines, so it needs no reserve of its own.
pub(super) fn blend_dynamics(axes: &AxisTable, seg: &mut Segment) {
    let Some(c) = seg.mv.arc() else { return };
    let min_accel = [c.a, c.b]
        .iter()
        .filter_map(|&i| axes.get(i))
        .map(|ax| BLEND_ACCEL_SHARE * ax.max_accel_mm_per_s2.max(1e-6))
        .fold(f64::INFINITY, f64::min);
    if !(min_accel.is_finite() && c.radius_mm > 0.0) {
        return;
    }
    let vmax = [c.a, c.b]
        .iter()
        .filter_map(|&i| axes.get(i))
        .map(|ax| ax.max_velocity_mm_per_min.max(1e-6) / 60.0)
        .fold(f64::INFINITY, f64::min);
    // The centripetal share passing at feed takes (a blend of a nearly straight corner
    // needs almost none and leaves the ramp nearly all), at most the constant.
    let feed = seg.programmed_mm_per_s.min(vmax);
    let share = (feed * feed / (c.radius_mm * min_accel)).min(BLEND_CENTRIPETAL_SHARE);
    let v = (share * min_accel * c.radius_mm).sqrt();
    seg.limit_mm_per_s = v.min(vmax);
    seg.accel_mm_per_s2 = (1.0 - share * share).sqrt() * min_accel;
}

/// Contouring: if the last motion block in the window ends in a corner it should blend
/// (G261 / G61), shorten it and `next` and return the blend arc (see [`contour`]).
/// The window's front is not changed once it executes (`front_busy`).
pub(super) fn blend_corner(window: &mut Window, next: &mut Move, front_busy: bool) -> Option<Move> {
    let at = window.last_move_unflushed();
    let i = at.filter(|&i| i > 0 || !front_busy)?;
    let prev = window.segment_mut(i)?;
    let dev = prev.mv.path.contour_dev_mm?;
    let (p1, arc, p2) = contour::blend(&prev.mv, next, dev)?;
    prev.mv.end = p1;
    prev.length_mm = prev.mv.length_mm();
    if let Some(j) = prev.junction.as_mut() {
        j.short_mm = j.short_mm.min(prev.length_mm);
    }
    next.start = p2;
    window.mark_dirty();
    Some(arc)
}
