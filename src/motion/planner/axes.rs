//! The axis limits the planner's parts read, by axis index, and the fixed junction reserve.

use crate::vocab::axis::MAX_AXES;

use super::super::AxisLimits;

/// Share of each axis' acceleration kept for velocity jumps at block junctions; the velocity
/// profile uses the rest.
pub const JUNCTION_ACCEL_SHARE: f64 = 0.25;

/// Axis limits by index (`None` = no such axis) and the per-axis junction reserve.
#[derive(Debug)]
pub(super) struct AxisTable {
    /// Limits by axis index (velocities mm/min, acceleration mm/s², jerk mm/s³).
    by_index: [Option<AxisLimits>; MAX_AXES],
    /// Per axis, the fixed junction reserve [`JUNCTION_ACCEL_SHARE`]·aᵢ, mm/s².
    reserve: [f64; MAX_AXES],
}

impl AxisTable {
    pub(super) fn new(axes: &[AxisLimits]) -> Self {
        let mut by_index: [Option<AxisLimits>; MAX_AXES] = Default::default();
        for a in axes {
            if a.index < MAX_AXES {
                by_index[a.index] = Some(a.clone());
            }
        }
        let reserve = std::array::from_fn(|i| {
            by_index[i].as_ref().map_or(0.0, |a: &AxisLimits| {
                JUNCTION_ACCEL_SHARE * a.max_accel_mm_per_s2.max(1e-6)
            })
        });
        AxisTable { by_index, reserve }
    }

    /// Limits by axis index.
    pub(super) fn by_index(&self) -> &[Option<AxisLimits>; MAX_AXES] {
        &self.by_index
    }

    /// Limits of axis `i`, if it is configured.
    pub(super) fn get(&self, i: usize) -> Option<&AxisLimits> {
        self.by_index[i].as_ref()
    }

    /// Per axis, the fixed junction reserve, mm/s².
    pub(super) fn reserve(&self) -> [f64; MAX_AXES] {
        self.reserve
    }
}
