//! The software-limit check on the path the axes follow (after compensation, contouring and
//! splines), and the block it is reported against.

use std::sync::Arc;

use crate::geometry::arc::outside_limits;
use crate::geometry::SoftLimits;
use crate::lang::codes;
use crate::queue::{BlockInfo, CompSide, Move};
use crate::vocab::axis::MAX_AXES;

use super::super::trc::PlanError;
use super::super::AxisLimits;

/// Software limits per axis and the last block that entered the window with its event.
#[derive(Debug)]
pub(super) struct LimitCheck {
    /// Software limits per axis, mm (the decoder's check, on the path after compensation,
    /// contouring and splines).
    soft_limits: [SoftLimits; MAX_AXES],
    /// Per axis, the limits apply (the axis is configured).
    soft_enabled: [bool; MAX_AXES],
    /// Program and line of the last block that entered the window with its event.
    last_block: Option<(Arc<str>, u32)>,
}

impl LimitCheck {
    pub(super) fn new(by_index: &[Option<AxisLimits>; MAX_AXES]) -> Self {
        let soft_limits = std::array::from_fn(|i| {
            by_index[i]
                .as_ref()
                .map_or(SoftLimits::default(), |a: &AxisLimits| SoftLimits {
                    min_mm: a.min_mm,
                    max_mm: a.max_mm,
                })
        });
        let soft_enabled = std::array::from_fn(|i| by_index[i].is_some());
        LimitCheck {
            soft_limits,
            soft_enabled,
            last_block: None,
        }
    }

    /// A block with its event entered the window: errors name it from now on.
    pub(super) fn entered(&mut self, info: &BlockInfo) {
        // Blocks of the same program share its name: only the line changes, and no
        // reference count is taken and given back (two locked operations a block).
        match &mut self.last_block {
            Some((prog, line)) if Arc::ptr_eq(prog, &info.prog) => *line = info.line,
            last => *last = Some((info.prog.clone(), info.line)),
        }
    }

    /// Software limits on the path the axes follow (21897): a move entering the window —
    /// compensated, a contour blend, a spline piece — that takes an axis beyond a limit
    /// stops the channel before the axes get there (the window runs ahead of them). The
    /// decoder checks the programmed end points; this catches what compensation, contouring
    /// and splines add to them.
    pub(super) fn check(&self, mv: &Move) -> Option<PlanError> {
        let b = outside_limits(mv, &self.soft_limits, &self.soft_enabled)?;
        let path = if mv.path.comp != CompSide::Off {
            "compensated path reaches"
        } else if mv.path.spline.is_some() {
            "spline reaches"
        } else if mv.path.contour_dev_mm.is_some() && !b.at_end {
            "contour reaches"
        } else if b.at_end {
            "end point"
        } else {
            "arc reaches"
        };
        Some(PlanError {
            code: codes::SOFT_LIMIT,
            msg: b.message(path),
            block: self
                .last_block
                .as_ref()
                .map(|(p, l)| (p.to_string(), u64::from(*l))),
        })
    }
}
