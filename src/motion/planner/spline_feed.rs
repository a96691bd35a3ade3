//! Spline hand-off (G151): the spline being built from G1 points, the blocks waiting for
//! their curve and the plain blocks programmed between them.

use std::collections::VecDeque;

use crate::queue::{BlockInfo, Move, SplineKind};

use super::super::spline::{Segment, Spline};

/// What the window's spline hand-off holds between blocks.
#[derive(Debug, Default)]
pub(super) struct SplineFeed {
    /// The spline being built (G151), if any.
    spline: Option<Spline>,
    /// Spline blocks waiting for their curve: (point number, event).
    infos: VecDeque<(usize, Option<BlockInfo>)>,
    /// Plain blocks programmed after spline point n, waiting for its curve.
    waiting: VecDeque<(usize, Option<BlockInfo>)>,
    /// Reused buffer of finished curve segments.
    out: Vec<Segment>,
}

impl SplineFeed {
    /// A spline is being built.
    pub(super) fn is_building(&self) -> bool {
        self.spline.is_some()
    }

    /// Blocks held here, waiting for their curve.
    pub(super) fn held(&self) -> usize {
        self.infos.len() + self.waiting.len()
    }

    /// A spline of another kind than `kind` is being built.
    pub(super) fn other_kind(&self, kind: SplineKind) -> bool {
        self.spline.as_ref().is_some_and(|s| s.kind() != kind)
    }

    /// The number of the point received last, if a spline is being built.
    pub(super) fn received(&self) -> Option<usize> {
        self.spline.as_ref().map(Spline::received)
    }

    /// A plain block programmed after point `at` waits for its curve.
    pub(super) fn wait(&mut self, at: usize, info: Option<BlockInfo>) {
        self.waiting.push_back((at, info));
    }

    /// A G1 point in spline mode into the spline (a new one if none is being built): whether
    /// it moved (the curve segments it completes are in `out`) or not (the block waits like a
    /// plain one, in order).
    pub(super) fn point(
        &mut self,
        info: Option<BlockInfo>,
        kind: SplineKind,
        mv: &Move,
        out: &mut Vec<Segment>,
    ) -> bool {
        let sp = self
            .spline
            .get_or_insert_with(|| Spline::new(kind, mv.start, mv.feed_mm_per_min, mv.path));
        if mv.end == sp.last() {
            // No motion: the block takes effect like a plain one, in order.
            let at = sp.received();
            self.waiting.push_back((at, info));
            return false;
        }
        let at = sp.received() + 1;
        self.infos.push_back((at, info));
        if let Some(sp) = self.spline.as_mut() {
            sp.push(mv.end, mv.feed_mm_per_min, out);
        }
        true
    }

    /// Take the spline being built out (to finish it), if any.
    pub(super) fn take_spline(&mut self) -> Option<Spline> {
        self.spline.take()
    }

    /// The next spline block whose curve is up to `point`, if any.
    pub(super) fn pop_info_upto(&mut self, point: usize) -> Option<Option<BlockInfo>> {
        if self.infos.front().is_some_and(|(at, _)| *at <= point) {
            return self.infos.pop_front().map(|(_, i)| i);
        }
        None
    }

    /// The next plain block programmed up to `point`, if any.
    pub(super) fn pop_waiting_upto(&mut self, point: usize) -> Option<Option<BlockInfo>> {
        if self.waiting.front().is_some_and(|(at, _)| *at <= point) {
            return self.waiting.pop_front().map(|(_, i)| i);
        }
        None
    }

    /// Every block still waiting, in the order programmed (their curve never came: nothing
    /// moved).
    pub(super) fn drain_rest(&mut self) -> Vec<(usize, Option<BlockInfo>)> {
        let mut rest: Vec<(usize, Option<BlockInfo>)> =
            self.infos.drain(..).chain(self.waiting.drain(..)).collect();
        rest.sort_by_key(|(at, _)| *at);
        rest
    }

    /// The reused buffer of curve segments (empty), to be put back with `put_out`.
    pub(super) fn take_out(&mut self) -> Vec<Segment> {
        std::mem::take(&mut self.out)
    }

    /// Put the buffer of curve segments back.
    pub(super) fn put_out(&mut self, out: Vec<Segment>) {
        self.out = out;
    }

    /// Drop the spline and every block waiting for it (reset, error).
    pub(super) fn clear(&mut self) {
        self.spline = None;
        self.infos.clear();
        self.waiting.clear();
    }
}
