//! Planner: the lookahead window of blocks held in the channel (the "memory effect" of ISG
//! FCT-C19 Data streaming §2.3.1), the rules that release them for execution (`#FLUSH`, a full
//! window, the program end), contour blends (G261/G61) and the velocity plan over the released
//! motion blocks.
//!
//! `Planner` is a thin struct of parts, each in its own file and owning its state; its
//! methods take blocks in and hand each part what it needs:
//!
//! | file | part |
//! |------|------|
//! | `window.rs` | the held and released entries and the release rules |
//! | `entry.rs` | the shared types: `Entry`, `EntryKind`, `Segment`, `Junction` |
//! | `axes.rs` | the axis limits by index and the fixed junction reserve |
//! | `junction.rs` | the junction rule: corner velocity limits and acceleration claims |
//! | `velocity.rs` | nominal velocities, path accelerations and the backward pass |
//! | `blend.rs` | contour blends (corner rounding) and their dynamics |
//! | `radius_comp.rs` | the tool radius compensation hand-off |
//! | `spline_feed.rs` | the spline hand-off |
//! | `limits.rs` | the software-limit check on the path the axes follow |

mod axes;
mod blend;
mod entry;
mod junction;
mod limits;
mod pre_output;
mod radius_comp;
mod spline_feed;
mod velocity;
mod window;

use crate::queue::{
    Action, BlockInfo, CompSide, Move, MoveKind, QueuedBlock, SplineKind, TechnoStep,
};
use crate::vocab::flush::FlushKind;

use super::spline;
use super::trc::PlanError;
use super::AxisLimits;
use axes::AxisTable;
use junction::JunctionRule;
use limits::LimitCheck;
use radius_comp::RadiusComp;
use spline_feed::SplineFeed;
use window::Window;

pub use axes::JUNCTION_ACCEL_SHARE;
pub(crate) use entry::{Entry, EntryKind, Segment};

/// Planner settings (runtime.toml `[planner]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlannerSettings {
    /// Motion blocks held and planned over (lookahead window), at least 1.
    pub lookahead_blocks: usize,
    /// Corner smoothing window, s (0 = off): see [`super::filter`].
    pub corner_smoothing_s: f64,
}

impl Default for PlannerSettings {
    fn default() -> Self {
        PlannerSettings {
            lookahead_blocks: 32,
            corner_smoothing_s: 0.0,
        }
    }
}

/// The lookahead window and the parts that feed and plan it.
#[derive(Debug)]
pub(crate) struct Planner {
    /// Axis limits and the junction reserve.
    axes: AxisTable,
    /// The entries, held and released.
    window: Window,
    /// The junction rule's corner window (s) and cycle (s).
    junctions: JunctionRule,
    /// Tool radius compensation hand-off.
    comp: RadiusComp,
    /// Spline hand-off.
    spline: SplineFeed,
    /// Software limits on the path after compensation, contouring and splines.
    limits: LimitCheck,
    /// An error found while planning (compensation impossible, a software limit on the path
    /// the axes follow), for the channel.
    error: Option<PlanError>,
    /// The front entry is executing (its geometry is fixed).
    front_busy: bool,
    /// Technology outputs with a pre-output in the window (planner/pre_output.rs): none, the
    /// usual case, costs one comparison a tick.
    pre_outputs: usize,
}

impl Planner {
    pub(crate) fn new(axes: &[AxisLimits], settings: PlannerSettings) -> Self {
        let axes = AxisTable::new(axes);
        let limits = LimitCheck::new(axes.by_index());
        Planner {
            window: Window::new(settings.lookahead_blocks),
            junctions: JunctionRule::new(settings.corner_smoothing_s),
            comp: RadiusComp::default(),
            spline: SplineFeed::default(),
            limits,
            error: None,
            front_busy: false,
            pre_outputs: 0,
            axes,
        }
    }

    pub(crate) fn lookahead(&self) -> usize {
        self.window.lookahead()
    }

    /// The front entry executes (its geometry and acceleration are fixed) or not.
    pub(crate) fn set_front_busy(&mut self, busy: bool) {
        self.front_busy = busy;
    }

    /// The corner window the axis filter now uses, s (0 = none): junction velocities are
    /// planned for it, so the plan is recomputed.
    pub(crate) fn set_corner_window_s(&mut self, corner_s: f64) {
        if self.junctions.set_corner_s(corner_s) {
            self.junctions
                .relink(&self.axes, &mut self.window, self.front_busy);
            self.window.mark_dirty();
        }
    }

    /// The cycle time junction claims are sized for, s.
    pub(crate) fn set_cycle_s(&mut self, dt_s: f64) {
        self.junctions.set_cycle_s(dt_s);
    }

    pub(crate) fn len(&self) -> usize {
        self.window.len()
    }
    pub(crate) fn is_empty(&self) -> bool {
        self.window.is_empty()
    }
    /// Entries released for execution and not yet done.
    pub(crate) fn released(&self) -> usize {
        self.window.released()
    }
    /// Entries held back (the memory effect), blocks waiting for their spline curve included.
    pub(crate) fn held(&self) -> usize {
        self.window.held() + self.spline.held() + self.comp.held()
    }
    pub(crate) fn front(&self) -> Option<&Entry> {
        self.window.front()
    }
    pub(crate) fn front_mut(&mut self) -> Option<&mut Entry> {
        self.window.front_mut()
    }
    pub(crate) fn entries(&self) -> impl Iterator<Item = &Entry> {
        self.window.iter()
    }
    /// The front entry is a straight move that ends a run: after it, among the released
    /// entries, the next one that is not a plain block or `#FLUSH CONTINUE` stops the motion
    /// (dwell, `#FLUSH`, `#FLUSH WAIT`, program end). No later release can join it then.
    pub(crate) fn front_is_lone_line(&self) -> bool {
        self.window.front_is_lone_line()
    }

    /// Path acceleration and jerk limits of a straight move with every axis' full
    /// acceleration (no junction reserve: a lone line has no junction), mm/s², mm/s³
    /// (infinite: no jerk limit on any moving axis).
    pub(crate) fn line_limits(&self, seg: &Segment) -> (f64, f64) {
        velocity::line_limits(&self.axes, seg)
    }

    /// The plan must be recomputed before the next tick's interpolation.
    pub(crate) fn mark_dirty(&mut self) {
        self.window.mark_dirty();
    }

    /// Take blocks from the queue into the window while it has room, applying the release
    /// rules.
    pub(crate) fn take_from(&mut self, queue: &mut crate::queue::BlockQueue) {
        while !self.window.full() {
            let Some(b) = queue.pop_front() else { break };
            self.push(b);
        }
        if self.window.full() {
            self.window.release_all();
        }
    }

    /// Put one decoded block into the window (held unless a rule releases it).
    #[inline]
    pub(crate) fn push(&mut self, b: QueuedBlock) {
        let QueuedBlock {
            info,
            action,
            silent,
        } = b;
        // Only the program end keeps its program's name: no reference count traffic for the
        // other blocks.
        let prog = matches!(action, Action::End { .. }).then(|| info.prog.clone());
        let info = (!silent).then_some(info);
        // Tool radius compensation: every move while it is on (and the G40 block) goes
        // through the compensator; splines: G1 points in spline mode go to the spline. A plain
        // block waits behind the element or point it follows; anything else ends the spline
        // first, then (unless it is a compensated move) the waiting compensated element.
        let comp_move = matches!(&action, Action::Move(mv)
            if mv.path.comp != CompSide::Off || self.comp.is_on());
        let spline_move = matches!(&action, Action::Move(mv)
            if !comp_move && mv.path.spline.is_some() && matches!(mv.kind, MoveKind::Line));
        if matches!(action, Action::None) {
            if let Some(at) = self.spline.received() {
                self.spline.wait(at, info);
                return;
            }
            if self.comp.is_on() {
                self.comp.wait(info);
                return;
            }
        }
        if !spline_move {
            self.finish_spline();
        }
        if let Action::Move(mv) = &action {
            if comp_move {
                self.comp_move(info, **mv);
                return;
            }
            if let (true, Some(kind)) = (spline_move, mv.path.spline) {
                self.comp_finish();
                self.spline_point(info, kind, mv);
                return;
            }
        }
        self.comp_finish();
        let kind = match action {
            Action::None => EntryKind::Plain,
            Action::Dwell { seconds } => EntryKind::Dwell {
                seconds: if seconds.is_finite() {
                    seconds.max(0.0)
                } else {
                    0.0
                },
            },
            Action::Flush(k) => EntryKind::Flush(k),
            Action::Techno(TechnoStep::Output(g)) => EntryKind::TechnoOutput(g),
            Action::Techno(TechnoStep::Wait(w)) => EntryKind::TechnoWait(w),
            Action::Message(m) => EntryKind::Message(m),
            Action::Stop { optional } => EntryKind::Stop { optional },
            Action::End { m } => EntryKind::End {
                m,
                prog: prog.unwrap_or_else(|| std::sync::Arc::from("")),
            },
            Action::Move(mut mv) => {
                if let Some(arc) = blend::blend_corner(&mut self.window, &mut mv, self.front_busy) {
                    self.push_move(None, arc);
                }
                EntryKind::Move(Box::new(velocity::segment(&self.axes, *mv)))
            }
        };
        self.push_entry(info, kind, true);
    }

    /// Append one entry and apply the release rules.
    fn push_entry(&mut self, info: Option<BlockInfo>, kind: EntryKind, counted: bool) {
        let is_move = matches!(kind, EntryKind::Move(_));
        let counted = counted && is_move;
        if let Some(i) = &info {
            self.limits.entered(i);
        }
        // A programmed move was checked by the decoder with the same rule, and a contour
        // trims it to a piece of itself; what compensation and splines make of it is new.
        if let EntryKind::Move(seg) = &kind {
            if seg.mv.path.comp != CompSide::Off || seg.mv.path.spline.is_some() {
                self.check_limits(&seg.mv);
            }
        }
        self.pre_outputs += usize::from(pre_output::has_lead(&kind));
        let release = self.window.releases(&kind, self.held() == 0);
        let continue_after = matches!(kind, EntryKind::Flush(FlushKind::Continue));
        let at = self.window.push_back(Entry {
            info,
            kind,
            counted,
        });
        if is_move {
            self.junctions
                .link(&self.axes, &mut self.window, at, self.front_busy);
            self.window.moved_in(counted);
        }
        if release {
            self.window.release_all();
        }
        if continue_after {
            self.window.release_next_move();
        }
    }

    /// A silent motion entry (a contour blend) at the back of the window; it does not count
    /// towards the lookahead.
    fn push_move(&mut self, info: Option<BlockInfo>, mv: Move) {
        let mut seg = velocity::segment(&self.axes, mv);
        blend::blend_dynamics(&self.axes, &mut seg);
        self.check_limits(&seg.mv);
        let kind = EntryKind::Move(Box::new(seg));
        let at = self.window.push_back(Entry {
            info,
            kind,
            counted: false,
        });
        self.junctions
            .link(&self.axes, &mut self.window, at, self.front_busy);
    }

    /// A G1 point in spline mode: into the spline (a new one if the type changed), and the
    /// curve it completes into the window.
    fn spline_point(&mut self, info: Option<BlockInfo>, kind: SplineKind, mv: &Move) {
        if self.spline.other_kind(kind) {
            self.finish_spline();
        }
        let mut out = self.spline.take_out();
        if self.spline.point(info, kind, mv, &mut out) {
            self.emit_spline(&mut out);
        }
        self.spline.put_out(out);
    }

    /// A move while compensation is on, or the block that switches it on or off.
    fn comp_move(&mut self, info: Option<BlockInfo>, mv: Move) {
        let side = mv.path.comp;
        let mut out = self.comp.take_out();
        let done = match (self.comp.take_active(), side) {
            (None, CompSide::Off) => Ok(()),
            (None, _) => self.comp.select(info, mv),
            (Some(c), CompSide::Off) => {
                let r = c.deselect(mv, &mut out);
                // The G40 line is this block's; what comes before it is the waiting element's.
                let last = out.pop();
                let pending = self.comp.take_info();
                self.emit_comp(&mut out, pending);
                if let Some(l) = last {
                    out.push(l);
                }
                self.emit_comp(&mut out, info);
                r
            }
            (Some(mut c), s) if s == c.side() => {
                let r = c.next(mv, &mut out);
                let pending = self.comp.replace_info(info);
                self.emit_comp(&mut out, pending);
                self.comp.put_active(c);
                r
            }
            (Some(mut c), _) => {
                let r = c.finish(&mut out);
                let pending = self.comp.take_info();
                self.emit_comp(&mut out, pending);
                r.and_then(|()| self.comp.select(info, mv))
            }
        };
        if let Err(e) = done {
            self.comp.clear();
            self.error = Some(e);
        }
        out.clear();
        self.comp.put_out(out);
    }

    /// Finish the element waiting in the compensator, if any. Inlined check: this runs for
    /// every block, and almost always finds nothing.
    #[inline]
    fn comp_finish(&mut self) {
        if self.comp.is_on() {
            self.comp_finish_now();
        }
    }

    /// A stop while compensation is on: the waiting element ends at its own offset end.
    fn comp_finish_now(&mut self) {
        let Some(mut c) = self.comp.take_active() else {
            return;
        };
        let mut out = self.comp.take_out();
        let r = c.finish(&mut out);
        let pending = self.comp.take_info();
        self.emit_comp(&mut out, pending);
        self.comp.put_active(c);
        if let Err(e) = r {
            self.comp.drop_active();
            self.error = Some(e);
        }
        self.comp.put_out(out);
    }

    /// Compensated moves of one block into the window (its event on the first), then the
    /// plain blocks that waited behind it.
    fn emit_comp(&mut self, out: &mut Vec<Move>, info: Option<BlockInfo>) {
        let mut info = info;
        for (k, mv) in out.drain(..).enumerate() {
            if mv.length_mm() <= 0.0 && info.is_none() {
                continue;
            }
            let kind = EntryKind::Move(Box::new(velocity::segment(&self.axes, mv)));
            self.push_entry(info.take(), kind, k == 0);
        }
        if let Some(i) = info {
            self.push_entry(Some(i), EntryKind::Plain, false);
        }
        while let Some(i) = self.comp.pop_waiting() {
            self.push_entry(i, EntryKind::Plain, false);
        }
    }

    /// Software limits on the path the axes follow (planner/limits.rs), once: the first
    /// error stays until the channel takes it.
    fn check_limits(&mut self, mv: &Move) {
        if self.error.is_some() {
            return;
        }
        self.error = self.limits.check(mv);
    }

    /// The error compensation ran into, once.
    pub(crate) fn take_error(&mut self) -> Option<PlanError> {
        self.error.take()
    }

    /// Tool radii by D number, mm (the tool list).
    pub(crate) fn set_tool_radii(&mut self, tools: Vec<(u32, f64)>) {
        self.comp.set_tool_radii(tools);
    }

    /// Finish the spline being built, if any (inlined check, as `comp_finish`).
    #[inline]
    fn finish_spline(&mut self) {
        if self.spline.is_building() {
            self.finish_spline_now();
        }
    }

    /// End the spline: the rest of its curve and everything waiting for it.
    fn finish_spline_now(&mut self) {
        let Some(sp) = self.spline.take_spline() else {
            return;
        };
        let mut out = self.spline.take_out();
        sp.finish(&mut out);
        self.emit_spline(&mut out);
        // Blocks whose curve never came (nothing moved): in order, as plain entries.
        for (_, info) in self.spline.drain_rest() {
            self.push_entry(info, EntryKind::Plain, false);
        }
        self.spline.put_out(out);
    }

    /// Curve segments into the window: each segment's first piece carries its block's event,
    /// and plain blocks programmed after that block follow it.
    fn emit_spline(&mut self, out: &mut Vec<spline::Segment>) {
        for seg in out.drain(..) {
            let mut info = None;
            while let Some(i) = self.spline.pop_info_upto(seg.point) {
                if info.is_some() {
                    self.push_entry(i, EntryKind::Plain, false);
                } else {
                    info = i;
                }
            }
            for (k, mv) in seg.pieces.into_iter().enumerate() {
                let kind = EntryKind::Move(Box::new(velocity::segment(&self.axes, mv)));
                self.push_entry(if k == 0 { info.take() } else { None }, kind, k == 0);
            }
            while let Some(i) = self.spline.pop_waiting_upto(seg.point) {
                self.push_entry(i, EntryKind::Plain, false);
            }
        }
    }

    /// Remove the front entry (it has been executed).
    pub(crate) fn pop_front(&mut self) -> Option<Entry> {
        let e = self.window.pop_front()?;
        if pre_output::has_lead(&e.kind) {
            self.pre_outputs -= 1;
        }
        Some(e)
    }

    /// A MEP_SVS / MET_SVS group whose pre-output point the front move has reached
    /// (`to_go_mm` and `to_go_s` left of it), taken out of the window to go to the PLC now.
    #[inline]
    pub(crate) fn take_due_pre_output(
        &mut self,
        to_go_mm: f64,
        to_go_s: f64,
        override_pct: f64,
    ) -> Option<Box<crate::vocab::techno::OutputGroup>> {
        if self.pre_outputs == 0 {
            return None;
        }
        let g = pre_output::take_due(&mut self.window, to_go_mm, to_go_s, override_pct)?;
        self.pre_outputs -= 1;
        Some(g)
    }

    /// Drop everything (reset, error).
    pub(crate) fn clear(&mut self) {
        self.pre_outputs = 0;
        self.window.clear();
        self.spline.clear();
        self.comp.clear();
    }

    /// Recompute the exit velocities of the released motion blocks if something changed.
    pub(crate) fn plan_if_needed(&mut self, override_pct: f64, dt_s: f64) {
        if self.window.take_dirty() {
            velocity::plan(
                &mut self.window,
                self.junctions.corner_s(),
                override_pct,
                dt_s,
            );
        }
    }
}

#[cfg(test)]
impl Planner {
    /// The plan as it stands (made incrementally by the ticks), then the plan of the whole
    /// window: each as every released motion block's exit velocity (its bits), front first.
    pub(crate) fn plan_both_ways(&mut self, override_pct: f64, dt_s: f64) -> (Vec<u64>, Vec<u64>) {
        self.plan_if_needed(override_pct, dt_s);
        let planned = self.exits();
        // No exit left to compare with: this plan cannot stop early.
        for e in self.window.iter_mut() {
            if let EntryKind::Move(seg) = &mut e.kind {
                seg.exit_mm_per_s = f64::NAN;
            }
        }
        self.mark_dirty();
        self.plan_if_needed(override_pct, dt_s);
        (planned, self.exits())
    }

    fn exits(&self) -> Vec<u64> {
        self.window
            .iter()
            .take(self.window.released())
            .filter_map(|e| match &e.kind {
                EntryKind::Move(seg) => Some(seg.exit_mm_per_s.to_bits()),
                _ => None,
            })
            .collect()
    }
}
