//! The lookahead window: the blocks held in the channel, the rules that release them and the
//! flag that the plan over the released ones is stale.
//!
//! Release rules. Motion blocks taken from the block queue are *held* until one of these
//! releases every block in the window: the window holds `lookahead_blocks` motion blocks (it is
//! full); the program end (M30/M2) enters it; a `#FLUSH`, `#FLUSH CONTINUE` or `#FLUSH WAIT`
//! enters it. `#FLUSH CONTINUE` also releases the next motion block the moment it arrives, so a
//! stream that delivers it in time continues without a stop ("if the next motion block is
//! presented in good time before an NC block end, motion is resumed without stopping"). A
//! non-motion block or a dwell with nothing held before it is released at once: it takes no
//! part in cross-block planning.

use std::collections::VecDeque;

use crate::queue::MoveKind;
use crate::vocab::flush::FlushKind;

use super::entry::{Entry, EntryKind, Segment};

/// Non-motion blocks the window holds beyond its motion blocks, per motion block: bounds the
/// window when a program is mostly assignments or M functions. It also bounds how many such
/// blocks one tick takes in: 8 lets the default window (32 blocks, 304 entries) take a whole
/// stream buffer of 17-byte assignments (241 lines) per tick, the interface's full rate.
const NON_MOTION_PER_BLOCK: usize = 8;

/// The window of entries: a prefix of it is released, the rest held.
#[derive(Debug)]
pub(super) struct Window {
    /// Motion blocks held and planned over (at least 1).
    lookahead: usize,
    /// Entries the window holds at most, motion and non-motion.
    max_entries: usize,
    entries: VecDeque<Entry>,
    /// Entries at the front that may execute.
    released: usize,
    /// Motion blocks in the window.
    moves: usize,
    /// `#FLUSH CONTINUE` seen: release the next motion block when it arrives.
    release_next_move: bool,
    /// The plan must be recomputed (new releases, override change).
    dirty: bool,
    /// Released entries at the front whose plan inputs have not changed since the last plan
    /// (only ever entries appended or released behind them): the next plan may stop among
    /// them (see [`Window::plan_fresh`]).
    fresh: usize,
    /// The corner window, override and cycle time the last plan was made for (their bits):
    /// a plan for others recomputes every block.
    plan_for: [u64; 3],
}

impl Window {
    pub(super) fn new(lookahead_blocks: usize) -> Self {
        let lookahead = lookahead_blocks.max(1);
        let max_entries = lookahead * (1 + NON_MOTION_PER_BLOCK) + 16;
        Window {
            lookahead,
            max_entries,
            entries: VecDeque::with_capacity(max_entries),
            released: 0,
            moves: 0,
            release_next_move: false,
            dirty: false,
            fresh: 0,
            plan_for: [0; 3],
        }
    }

    pub(super) fn lookahead(&self) -> usize {
        self.lookahead
    }
    pub(super) fn len(&self) -> usize {
        self.entries.len()
    }
    pub(super) fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
    /// Entries released for execution and not yet done.
    pub(super) fn released(&self) -> usize {
        self.released
    }
    /// Entries held back in the window.
    pub(super) fn held(&self) -> usize {
        self.entries.len() - self.released
    }
    pub(super) fn front(&self) -> Option<&Entry> {
        self.entries.front()
    }
    /// The front entry. Its plan inputs may change without a replan of the others: no block
    /// lies before it, and its exit is the next block's entry.
    pub(super) fn front_mut(&mut self) -> Option<&mut Entry> {
        self.entries.front_mut()
    }
    pub(super) fn iter(&self) -> std::collections::vec_deque::Iter<'_, Entry> {
        self.entries.iter()
    }
    /// Every entry, to change: the next plan recomputes every block.
    pub(super) fn iter_mut(&mut self) -> std::collections::vec_deque::IterMut<'_, Entry> {
        self.fresh = 0;
        self.entries.iter_mut()
    }
    /// The released entries, front first.
    pub(super) fn released_mut(
        &mut self,
    ) -> std::iter::Take<std::collections::vec_deque::IterMut<'_, Entry>> {
        self.entries.iter_mut().take(self.released)
    }

    /// The motion block at index `i`, if that entry is one.
    pub(super) fn segment(&self, i: usize) -> Option<&Segment> {
        match self.entries.get(i).map(|e| &e.kind) {
            Some(EntryKind::Move(seg)) => Some(seg),
            _ => None,
        }
    }

    /// The motion block at index `i`, if that entry is one, to change: the next plan
    /// recomputes it and every block after it.
    pub(super) fn segment_mut(&mut self, i: usize) -> Option<&mut Segment> {
        if i > 0 {
            self.fresh = self.fresh.min(i);
        }
        match self.entries.get_mut(i).map(|e| &mut e.kind) {
            Some(EntryKind::Move(seg)) => Some(seg),
            _ => None,
        }
    }

    /// The front entry is a straight move that ends a run: after it, among the released
    /// entries, the next one that is not a plain block or `#FLUSH CONTINUE` stops the motion
    /// (dwell, `#FLUSH`, `#FLUSH WAIT`, program end). No later release can join it then.
    pub(super) fn front_is_lone_line(&self) -> bool {
        let Some(Entry {
            kind: EntryKind::Move(seg),
            ..
        }) = self.entries.front()
        else {
            return false;
        };
        if !matches!(seg.mv.kind, MoveKind::Line | MoveKind::Rapid) || seg.length_mm <= 0.0 {
            return false;
        }
        for e in self.entries.iter().take(self.released).skip(1) {
            match &e.kind {
                EntryKind::Plain
                | EntryKind::Message(_)
                | EntryKind::Flush(FlushKind::Continue) => {}
                k => return k.is_barrier(),
            }
        }
        false
    }

    /// The window holds `lookahead` motion blocks or its most entries.
    #[inline]
    pub(super) fn full(&self) -> bool {
        self.moves >= self.lookahead || self.entries.len() >= self.max_entries
    }

    /// The plan must be recomputed before the next tick's interpolation, every block of it.
    pub(super) fn mark_dirty(&mut self) {
        self.dirty = true;
        self.fresh = 0;
    }

    /// A plan for the corner window, override and cycle time `plan_for` (their bits) starts:
    /// the released entries at the front it may stop among, because their inputs are the last
    /// plan's. Among them, a motion block whose exit comes out as the last plan gave it has
    /// the same entry as then too, and so has every block before it: the plan may stop there.
    pub(super) fn plan_fresh(&self, plan_for: [u64; 3]) -> usize {
        if plan_for == self.plan_for {
            self.fresh
        } else {
            0
        }
    }

    /// The plan of every released entry is current, for `plan_for`.
    pub(super) fn planned(&mut self, plan_for: [u64; 3]) {
        self.plan_for = plan_for;
        self.fresh = self.released;
    }

    /// The plan was stale; it is taken as recomputed from now on.
    pub(super) fn take_dirty(&mut self) -> bool {
        std::mem::take(&mut self.dirty)
    }

    /// Whether an entry of `kind` entering now is released with everything before it:
    /// `nothing_held` says no block is held before it (in the window or waiting outside it).
    #[inline]
    pub(super) fn releases(&self, kind: &EntryKind, nothing_held: bool) -> bool {
        match kind {
            EntryKind::Flush(_) | EntryKind::Stop { .. } | EntryKind::End { .. } => true,
            EntryKind::Move(_) => self.release_next_move,
            // Nothing held before it: it takes no part in cross-block planning, so it runs
            // when interpolation reaches it, not when more motion arrives.
            EntryKind::Plain
            | EntryKind::Message(_)
            | EntryKind::Dwell { .. }
            | EntryKind::TechnoOutput(_)
            | EntryKind::TechnoWait(_) => nothing_held,
        }
    }

    /// Append one entry at the back; its index.
    #[inline]
    pub(super) fn push_back(&mut self, entry: Entry) -> usize {
        self.entries.push_back(entry);
        self.entries.len() - 1
    }

    /// Count a motion entry that entered (`counted`: towards the lookahead); it was the next
    /// motion block `#FLUSH CONTINUE` waited for, if any.
    #[inline]
    pub(super) fn moved_in(&mut self, counted: bool) {
        if counted {
            self.moves += 1;
        }
        if self.release_next_move {
            self.release_next_move = false;
        }
    }

    /// `#FLUSH CONTINUE` entered: release the next motion block when it arrives.
    pub(super) fn release_next_move(&mut self) {
        self.release_next_move = true;
    }

    /// Release every block in the window.
    #[inline]
    pub(super) fn release_all(&mut self) {
        if self.released != self.entries.len() {
            self.released = self.entries.len();
            self.dirty = true;
        }
    }

    /// Remove the front entry (it has been executed).
    pub(super) fn pop_front(&mut self) -> Option<Entry> {
        let e = self.entries.pop_front()?;
        if e.counted {
            self.moves -= 1;
        }
        self.released = self.released.saturating_sub(1);
        self.fresh = self.fresh.saturating_sub(1);
        Some(e)
    }

    /// Drop everything (reset, error).
    pub(super) fn clear(&mut self) {
        self.entries.clear();
        self.released = 0;
        self.moves = 0;
        self.release_next_move = false;
        self.dirty = false;
        self.fresh = 0;
    }

    /// The last motion entry before index `i`, unless a barrier lies between.
    pub(super) fn move_before(&self, i: usize) -> Option<usize> {
        for j in (0..i).rev() {
            match &self.entries[j].kind {
                EntryKind::Move(_) => return Some(j),
                k if k.is_barrier() => return None,
                _ => {}
            }
        }
        None
    }

    /// The last motion entry in the window, unless a flush of any kind or a barrier follows it.
    pub(super) fn last_move_unflushed(&self) -> Option<usize> {
        for (i, e) in self.entries.iter().enumerate().rev() {
            match &e.kind {
                EntryKind::Move(_) => return Some(i),
                // A flush of any kind suppresses the blend at the motion blocks around it
                // (TF5200 "Flushing NC channel"), `#FLUSH CONTINUE` included.
                k if k.is_barrier() || matches!(k, EntryKind::Flush(_)) => return None,
                _ => {}
            }
        }
        None
    }
}
