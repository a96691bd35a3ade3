//! The junction rule: the velocity limit at the corner between two motion blocks and the
//! acceleration each junction claims from the blocks on both sides (docs/motion.md "Corners").
//!
//! At a corner the direction jumps from t1 to t2 and each axis' velocity jumps by v·|t2ᵢ − t1ᵢ|
//! within one tick, on top of the tangential acceleration of the blocks on both sides. Each
//! axis' budget for the jump is what those blocks leave of aᵢ, so v ≤ budgetᵢ·dt / |Δtᵢ| keeps
//! the per-tick velocity change of every axis within aᵢ; when blocks are shorter than one
//! tick's travel several corners fall into one tick, so also v² ≤ budgetᵢ·L / |Δtᵢ| (L the
//! shorter of the two blocks), the polygon's own centripetal limit. Between two lines the
//! junction claims the budget passing it at feed takes, and the lines accelerate with the rest
//! (`JunctionRule::link`); next to an arc, for a corner that cannot be passed at feed, and with
//! a corner filter, the budget is [`JUNCTION_ACCEL_SHARE`] of aᵢ. Non-motion blocks between two
//! moves do not break the junction; a dwell, the program end, `#FLUSH` and `#FLUSH WAIT` do
//! (the motion stops there).

use crate::queue::{Move, MoveKind};
use crate::vocab::axis::MAX_AXES;

use super::super::interpolator::tangent;
use super::super::AxisLimits;
use super::axes::{AxisTable, JUNCTION_ACCEL_SHARE};
use super::entry::{Junction, Segment};
use super::window::Window;

/// Share of a junction's budget its velocity jumps may use: the rest covers the neighbouring
/// junctions when several fall into one cycle with unequal corners (the rule looks at the two
/// blocks on each side of a junction only).
const JUMP_MARGIN: f64 = 0.95;
/// Share of its acceleration a line keeps whatever its junctions claim: a junction that would
/// leave less is not passed at feed but with the fixed reserve.
const PROFILE_FLOOR: f64 = 0.2;

/// The junction rule's settings: the cycle the claims are sized for and the corner filter.
#[derive(Debug)]
pub(super) struct JunctionRule {
    /// Corner smoothing window, s (0 = off).
    corner_s: f64,
    /// Cycle time the junction claims are sized for, s.
    cycle_s: f64,
}

impl Junction {
    /// The junction's geometric velocity limit for tick length `dt_s`, mm/s.
    pub(super) fn limit_mm_per_s(&self, dt_s: f64) -> f64 {
        if self.k_s2_per_mm <= 0.0 {
            return f64::INFINITY;
        }
        (dt_s / self.k_s2_per_mm).min((self.short_mm / self.k_s2_per_mm).sqrt())
    }

    /// The limit when a corner filter of `window_s` spreads the velocity jump (0 = no filter).
    ///
    /// Each junction owns the time τ = min(window, time on the previous block, time on the
    /// next block) at the blocks' cruise velocities; owned times of successive junctions do not
    /// overlap, so the jumps inside any window sum to at most share·aᵢ·Σ τ ≤ 2·share·aᵢ·window
    /// when each jump is v·|Δtᵢ| ≤ share·aᵢ·τ / 2. The filter averages them over the window:
    /// at most share·aᵢ of added acceleration on any axis (docs/motion.md).
    pub(super) fn smoothed_limit_mm_per_s(
        &self,
        window_s: f64,
        prev_cruise_mm_per_s: f64,
        length_mm: f64,
        cruise_mm_per_s: f64,
    ) -> f64 {
        if window_s <= 0.0 {
            return 0.0;
        }
        if self.k_s2_per_mm <= 0.0 {
            return f64::INFINITY;
        }
        let time_on = |l: f64, v: f64| if v > 0.0 { l / v } else { f64::INFINITY };
        let tau = window_s
            .min(time_on(self.prev_length_mm, prev_cruise_mm_per_s))
            .min(time_on(length_mm, cruise_mm_per_s));
        0.5 * tau / self.k_s2_per_mm
    }
}

impl JunctionRule {
    /// The rule for a corner filter of `corner_s` (non-finite = off), claims sized for 1 ms.
    pub(super) fn new(corner_s: f64) -> Self {
        JunctionRule {
            corner_s: if corner_s.is_finite() {
                corner_s.max(0.0)
            } else {
                0.0
            },
            cycle_s: 0.001,
        }
    }

    /// Corner smoothing window, s (0 = off).
    pub(super) fn corner_s(&self) -> f64 {
        self.corner_s
    }

    /// A new corner window, s: whether it changed (the junctions must then be linked afresh).
    pub(super) fn set_corner_s(&mut self, corner_s: f64) -> bool {
        if corner_s != self.corner_s {
            self.corner_s = corner_s;
            true
        } else {
            false
        }
    }

    /// The cycle time junction claims are sized for, s.
    pub(super) fn set_cycle_s(&mut self, dt_s: f64) {
        if dt_s > 0.0 && dt_s.is_finite() {
            self.cycle_s = dt_s;
        }
    }

    /// Every junction in the window afresh (the corner window changed: claims are made only
    /// without one). The executing front (`front_busy`) keeps its acceleration.
    pub(super) fn relink(&self, axes: &AxisTable, window: &mut Window, front_busy: bool) {
        let reserve = axes.reserve();
        for i in 0..window.len() {
            if i == 0 && front_busy {
                continue;
            }
            if let Some(seg) = window.segment_mut(i) {
                seg.end_claim_mm_per_s2 = reserve;
                if is_straight(&seg.mv) {
                    seg.accel_mm_per_s2 = seg.full_accel_mm_per_s2 * (1.0 - JUNCTION_ACCEL_SHARE);
                }
            }
        }
        for i in 0..window.len() {
            self.link(axes, window, i, front_busy);
        }
    }

    /// Join the motion entry at window index `i` to the one before it (the corner-speed rule,
    /// docs/motion.md "Corners"); `front_busy`: the window's front executes (its acceleration
    /// is fixed).
    ///
    /// At the junction each axis' velocity jumps by v·|Δtᵢ| within one cycle, an acceleration
    /// of v·|Δtᵢ| / dt on top of the tangential acceleration of the blocks on both sides. Each
    /// axis' budget for the jump is what those blocks leave of aᵢ. Between two lines the
    /// junction *claims* what it needs to be passed at the slower block's feed — v·|Δtᵢ| /
    /// dt, or v²·|Δtᵢ| / L when several junctions fall into one cycle — if both blocks keep
    /// at least [`PROFILE_FLOOR`] of their acceleration; the lines then accelerate with the
    /// rest. A corner that cannot be passed at feed (a square's 90°) claims the fixed reserve
    /// [`JUNCTION_ACCEL_SHARE`] and is passed at what it allows (nearly a stop). Next to an
    /// arc, or with a corner filter, every junction uses the fixed reserve.
    pub(super) fn link(&self, axes: &AxisTable, window: &mut Window, i: usize, front_busy: bool) {
        let Some(next) = window.segment(i) else {
            return;
        };
        let Some(p) = window.move_before(i) else {
            if let Some(next) = window.segment_mut(i) {
                next.junction = None;
            }
            return;
        };
        let Some(prev) = window.segment(p) else {
            return;
        };
        if next.length_mm <= 0.0 || prev.length_mm <= 0.0 {
            if let Some(next) = window.segment_mut(i) {
                next.junction = None;
            }
            return;
        }
        let t_prev = tangent(&prev.mv, prev.length_mm, true);
        let t_next = tangent(&next.mv, next.length_mm, false);
        // The budget rule needs the jump to land within the cycle: with a corner filter the
        // jumps are spread and bounded by the fixed reserve ([`Junction::smoothed_limit_mm_per_s`]).
        let straight = is_straight(&prev.mv) && is_straight(&next.mv) && self.corner_s <= 0.0;
        let short_mm = next.length_mm.min(prev.length_mm);
        let mut jump = [0.0; MAX_AXES];
        for (k, j) in jump.iter_mut().enumerate() {
            let d = (t_next[k] - t_prev[k]).abs();
            *j = if d <= 1e-12 { 0.0 } else { d };
        }
        let claim = if straight {
            let v = prev.cruise_mm_per_s(100.0).min(next.cruise_mm_per_s(100.0));
            self.claim(axes, &jump, v, short_mm, (prev, &t_prev), (next, &t_next))
        } else {
            axes.reserve()
        };
        let prev_busy = p == 0 && front_busy;
        let prev_start = tangent(&prev.mv, prev.length_mm, false);
        let junction = Junction {
            k_s2_per_mm: 0.0,
            jump,
            prev_load_mm_per_s2: [0.0; MAX_AXES],
            claim_mm_per_s2: claim,
            straight,
            short_mm,
            prev_length_mm: prev.length_mm,
            prev_programmed_mm_per_s: prev.programmed_mm_per_s,
            prev_limit_mm_per_s: prev.limit_mm_per_s,
        };
        // The previous block gives what this junction claims (unless it already runs).
        let prev_accel = if let Some(prev) = window.segment_mut(p) {
            if !prev_busy && straight {
                prev.end_claim_mm_per_s2 = claim;
                let start = prev.junction.map_or([0.0; MAX_AXES], |j| j.claim_mm_per_s2);
                prev.accel_mm_per_s2 = line_accel(axes.by_index(), prev, &prev_start, &start);
                let a = prev.accel_mm_per_s2;
                if let Some(j) = prev.junction.as_mut() {
                    j.k_s2_per_mm = junction_k(axes.by_index(), j, a, &prev_start);
                }
            }
            prev.accel_mm_per_s2
        } else {
            return;
        };
        let mut junction = junction;
        for (k, l) in junction.prev_load_mm_per_s2.iter_mut().enumerate() {
            *l = prev_accel * t_prev[k].abs();
        }
        if let Some(next) = window.segment_mut(i) {
            if straight {
                next.accel_mm_per_s2 = line_accel(axes.by_index(), next, &t_next, &claim);
            }
            junction.k_s2_per_mm =
                junction_k(axes.by_index(), &junction, next.accel_mm_per_s2, &t_next);
            next.junction = Some(junction);
        }
    }

    /// What a junction between two lines claims per axis, mm/s²: what passing it at `v`
    /// takes, if both lines keep [`PROFILE_FLOOR`] of their acceleration; else the reserve.
    fn claim(
        &self,
        axes: &AxisTable,
        jump: &[f64; MAX_AXES],
        v: f64,
        short_mm: f64,
        (prev, t_prev): (&Segment, &[f64; MAX_AXES]),
        (next, t_next): (&Segment, &[f64; MAX_AXES]),
    ) -> [f64; MAX_AXES] {
        let per_s = (1.0 / self.cycle_s).max(v / short_mm);
        let mut need = [0.0; MAX_AXES];
        for k in 0..MAX_AXES {
            let Some(ax) = axes.get(k) else { continue };
            let a = ax.max_accel_mm_per_s2.max(1e-6);
            need[k] = v * jump[k] * per_s / JUMP_MARGIN;
            let floor = PROFILE_FLOOR
                * (prev.full_accel_mm_per_s2 * t_prev[k].abs())
                    .max(next.full_accel_mm_per_s2 * t_next[k].abs());
            if !need[k].is_finite() || need[k] + floor > a {
                return axes.reserve();
            }
        }
        need
    }
}

/// A line's path acceleration: every axis' limit less the larger claim of its two junctions,
/// projected on the line, mm/s².
fn line_accel(
    axes: &[Option<AxisLimits>; MAX_AXES],
    seg: &Segment,
    t: &[f64; MAX_AXES],
    start_claim: &[f64; MAX_AXES],
) -> f64 {
    let mut accel = f64::INFINITY;
    for (k, tk) in t.iter().enumerate() {
        let s = tk.abs();
        if s <= 1e-12 {
            continue;
        }
        let Some(ax) = &axes[k] else { continue };
        let a = ax.max_accel_mm_per_s2.max(1e-6);
        let left = a - start_claim[k].max(seg.end_claim_mm_per_s2[k]);
        accel = accel.min(left.max(1e-6) / s);
    }
    if accel.is_finite() {
        accel
    } else {
        seg.accel_mm_per_s2
    }
}

/// A block whose tangent is the same along it (the budget rule's tangential load is exact).
pub(super) fn is_straight(mv: &Move) -> bool {
    matches!(mv.kind, MoveKind::Line | MoveKind::Rapid)
}

/// k of a junction, s²/mm: maxᵢ |Δtᵢ| / budgetᵢ, the budget being what the blocks on both
/// sides leave of aᵢ (`next_accel` along `t_next`), or the fixed reserve next to an arc.
fn junction_k(
    axes: &[Option<AxisLimits>; MAX_AXES],
    j: &Junction,
    next_accel: f64,
    t_next: &[f64; MAX_AXES],
) -> f64 {
    let mut k: f64 = 0.0;
    for i in 0..MAX_AXES {
        if j.jump[i] <= 0.0 {
            continue;
        }
        let a = axes[i]
            .as_ref()
            .map_or(f64::INFINITY, |ax| ax.max_accel_mm_per_s2.max(1e-6));
        let budget = if j.straight {
            JUMP_MARGIN * (a - j.prev_load_mm_per_s2[i].max(next_accel * t_next[i].abs()))
        } else {
            JUNCTION_ACCEL_SHARE * a
        };
        k = k.max(j.jump[i] / budget.max(1e-9 * a));
    }
    k
}
