//! Tool radius compensation hand-off (G41/G42/G40): the compensator under way, the block whose
//! element waits in it, the plain blocks waiting behind that element and the tool radii.

use std::collections::VecDeque;

use crate::queue::{BlockInfo, Move};

use super::super::trc::{Comp, PlanError, TRC_IMPOSSIBLE};

/// What the window's compensation hand-off holds between blocks.
#[derive(Debug, Default)]
pub(super) struct RadiusComp {
    /// Tool radius compensation under way (G41/G42), if any.
    active: Option<Comp>,
    /// The event of the block whose element waits in the compensator.
    info: Option<BlockInfo>,
    /// Plain blocks programmed after the waiting element.
    waiting: VecDeque<Option<BlockInfo>>,
    /// Reused buffer of compensated moves.
    out: Vec<Move>,
    /// Tool radii by D number, mm.
    tool_radii: Vec<(u32, f64)>,
}

impl RadiusComp {
    /// Compensation is under way.
    pub(super) fn is_on(&self) -> bool {
        self.active.is_some()
    }

    /// Blocks held here: the one whose element waits, and the plain blocks behind it.
    pub(super) fn held(&self) -> usize {
        usize::from(self.info.is_some()) + self.waiting.len()
    }

    /// A plain block waits behind the element in the compensator.
    pub(super) fn wait(&mut self, info: Option<BlockInfo>) {
        self.waiting.push_back(info);
    }

    /// The next plain block that waited behind the element, if any.
    pub(super) fn pop_waiting(&mut self) -> Option<Option<BlockInfo>> {
        self.waiting.pop_front()
    }

    /// Take the compensator out (to run it while the window takes its moves).
    pub(super) fn take_active(&mut self) -> Option<Comp> {
        self.active.take()
    }

    /// Put the compensator back.
    pub(super) fn put_active(&mut self, c: Comp) {
        self.active = Some(c);
    }

    /// Switch the compensator off after a failed finish; the waiting blocks stay.
    pub(super) fn drop_active(&mut self) {
        self.active = None;
    }

    /// The event of the block whose element waited in the compensator.
    pub(super) fn take_info(&mut self) -> Option<BlockInfo> {
        self.info.take()
    }

    /// The event of the block whose element now waits; the one that waited before.
    pub(super) fn replace_info(&mut self, info: Option<BlockInfo>) -> Option<BlockInfo> {
        std::mem::replace(&mut self.info, info)
    }

    /// The reused buffer of compensated moves (empty), to be put back with `put_out`.
    pub(super) fn take_out(&mut self) -> Vec<Move> {
        std::mem::take(&mut self.out)
    }

    /// Put the buffer of compensated moves back.
    pub(super) fn put_out(&mut self, out: Vec<Move>) {
        self.out = out;
    }

    /// G41/G42 switches on with `mv`, the radius of its D word's tool.
    pub(super) fn select(&mut self, info: Option<BlockInfo>, mv: Move) -> Result<(), PlanError> {
        let d = mv.path.tool_offset;
        let radius = if d == 0 {
            0.0
        } else {
            self.tool_radii
                .iter()
                .find(|(n, _)| *n == d)
                .map(|(_, r)| *r)
                .ok_or_else(|| PlanError {
                    code: TRC_IMPOSSIBLE,
                    msg: format!("tool radius compensation: no tool data for D{d}"),
                    block: None,
                })?
        };
        self.active = Some(Comp::select(mv.path.comp, radius, mv));
        self.info = info;
        Ok(())
    }

    /// Drop the compensator and every block waiting in it (compensation failed, reset).
    pub(super) fn clear(&mut self) {
        self.active = None;
        self.info = None;
        self.waiting.clear();
    }

    /// Tool radii by D number, mm (the tool list).
    pub(super) fn set_tool_radii(&mut self, tools: Vec<(u32, f64)>) {
        self.tool_radii = tools;
    }
}
