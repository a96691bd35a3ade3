//! Motion: executes the queued blocks in channel time and reports where the axes are.
//!
//! Each tick it takes decoded blocks from the block queue into the planner's lookahead window
//! (where they are held until released: [`planner`]), re-plans the velocity profile when
//! something was released or the override changed, and lets the [`interpolator`] move along
//! the released blocks for one tick. Block events come out as [`MotionNote`]s in program order:
//! a motion block's when its interpolation starts, a non-motion block's when interpolation
//! reaches it (M functions and assignments do not stop the motion; a dwell, `#FLUSH`,
//! `#FLUSH WAIT` and the program end do).

pub mod contour;
pub mod filter;
pub mod interpolator;
pub mod planner;
pub mod spline;
pub mod trace;
pub mod trc;

use std::sync::Arc;

use crate::queue::{BlockInfo, BlockQueue, Move, MoveKind, SyncMessage};
use crate::vocab::axis::{Position, MAX_AXES};
use crate::vocab::flush::FlushKind;
use crate::vocab::techno::{Acknowledgements, OutputGroup};

use filter::{jerk_window_s, AxisFilter};
use interpolator::{advance, advance_swing, point_at, Profile, Swing};
pub use planner::PlannerSettings;
use planner::{EntryKind, Planner};
use trace::{CsvTrace, Sample, Trace};

/// Limits of one axis (runtime.toml `[[axes]]`).
#[derive(Debug, Clone, PartialEq)]
pub struct AxisLimits {
    /// Index into `vocab::axis::AXIS_LETTERS`.
    pub index: usize,
    /// Maximum velocity, mm/min.
    pub max_velocity_mm_per_min: f64,
    /// Maximum acceleration, mm/s².
    pub max_accel_mm_per_s2: f64,
    /// Maximum jerk, mm/s³; `None` = no jerk limit.
    pub max_jerk_mm_per_s3: Option<f64>,
    /// Rapid (G0) rate, mm/min.
    pub rapid_mm_per_min: f64,
    /// Software limits, mm.
    pub min_mm: f64,
    pub max_mm: f64,
}

/// What execution did this tick, in order, for the channel to report.
#[derive(Debug, Clone, PartialEq)]
pub enum MotionNote {
    /// A block took effect (started executing): its `block` event.
    Started(BlockInfo),
    Flush(FlushKind),
    /// M00, or M01 with the M01 switch on, was reached with the axes at rest: motion holds.
    ProgramStop {
        optional: bool,
    },
    /// Planning found an error (tool radius compensation impossible): the channel stops.
    Error {
        code: u32,
        msg: String,
        /// Program and line of the block it is about, where known.
        block: Option<(String, u64)>,
    },
    /// The main program's end was reached: everything before it has run.
    End {
        m: u32,
        prog: Arc<str>,
    },
    /// Execution reached the point where these technology functions go to the PLC.
    TechnoOutput(Box<OutputGroup>),
    /// Execution reached a `#MSG SYN` block: its message is reported now.
    Message(Box<SyncMessage>),
}

/// What happens to the front entry after its share of a tick.
enum Next {
    /// Done: remove it, go on with the next.
    Pop,
    /// Not done: the tick is used up (or the motion waits).
    Stay,
    /// The program ended.
    End,
    /// Done, and motion holds here (a programmed stop).
    PopAndHold,
}

/// How the present run (the motion from one standstill to the next) is executed; chosen when
/// it starts, at rest with the axis filter settled, the only moment its windows may change.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Run {
    /// Any path: trapezoids with the junction reserve, the configured corner filter and the
    /// jerk window 2·a/j (docs/motion.md, "Jerk limits").
    General,
    /// One straight move from rest to rest: a trapezoid at `accel_mm_per_s2` under the swing
    /// rule, filtered by one window — the time-optimal jerk-limited profile (docs/motion.md,
    /// "Rest to rest").
    Lone { accel_mm_per_s2: f64, swing: Swing },
}

/// The executor of one channel.
#[derive(Debug)]
pub struct Motion {
    /// A technology output was handed over this step: the channel takes it into its units
    /// only after the step, so the program end waits a step for it.
    output_this_step: bool,
    axes: Vec<AxisLimits>,
    planner: Planner,
    /// Axis positions after the axis filter: where the axes are, mm (rotary: degrees).
    pos: Position,
    /// Axis positions the interpolator computed (before the axis filter).
    pos_in: Position,
    /// Corner and jerk filter between interpolator and axes.
    filter: AxisFilter,
    /// How the present run is executed.
    run: Run,
    /// Path velocity, acceleration and jerk of the filtered axes over the last tick
    /// (finite differences; mm/s, mm/s², mm/s³).
    out_v_mm_per_s: f64,
    out_a_mm_per_s2: f64,
    out_j_mm_per_s3: f64,
    /// Path position in the front block, mm.
    s_mm: f64,
    /// Path velocity of the interpolator, mm/s.
    v_mm_per_s: f64,
    /// The front entry has begun (its `Started` note is out).
    front_started: bool,
    /// Seconds of the front dwell done.
    dwell_done_s: f64,
    /// Feed override, percent (0–200).
    override_pct: f64,
    hold: bool,
    /// M01 stops (the operator's optional-stop switch).
    optional_stop: bool,
    /// The program end was executed; nothing more runs until the next start.
    ended: bool,
    /// Tick length seen last, s (junction limits depend on it).
    dt_s: f64,
    /// Channel time this motion has stepped through, s.
    time_s: f64,
    trace: Option<Trace>,
    csv: Option<CsvTrace>,
}

impl Motion {
    /// Motion with the default planner settings.
    pub fn new(axes: Vec<AxisLimits>) -> Self {
        Self::with_planner(axes, PlannerSettings::default())
    }

    pub fn with_planner(axes: Vec<AxisLimits>, settings: PlannerSettings) -> Self {
        let filter = AxisFilter::new(
            settings.corner_smoothing_s,
            jerk_window_s(&axes),
            [0.0; MAX_AXES],
        );
        Motion {
            output_this_step: false,
            planner: Planner::new(&axes, settings),
            axes,
            pos: [0.0; MAX_AXES],
            pos_in: [0.0; MAX_AXES],
            filter,
            run: Run::General,
            out_v_mm_per_s: 0.0,
            out_a_mm_per_s2: 0.0,
            out_j_mm_per_s3: 0.0,
            s_mm: 0.0,
            v_mm_per_s: 0.0,
            front_started: false,
            dwell_done_s: 0.0,
            override_pct: 100.0,
            hold: false,
            optional_stop: false,
            ended: false,
            dt_s: 0.001,
            time_s: 0.0,
            trace: None,
            csv: None,
        }
    }

    /// Tool radii by D number for tool radius compensation, mm (the tool list).
    pub fn set_tool_radii(&mut self, tools: Vec<(u32, f64)>) {
        self.planner.set_tool_radii(tools);
    }

    pub fn axes(&self) -> &[AxisLimits] {
        &self.axes
    }

    pub fn position(&self) -> Position {
        self.pos
    }

    /// The motion block executing now (the front entry once it has started), if it is a
    /// move: what the live view shows as the executing block's programmed feed and draws
    /// dashed when it is a rapid.
    pub(crate) fn executing_move(&self) -> Option<&Move> {
        match self.planner.front().map(|e| &e.kind) {
            Some(EntryKind::Move(seg)) if self.front_started => Some(&seg.mv),
            _ => None,
        }
    }

    /// Path velocity of the axes, mm/s: at the end of the last tick, or with the axis filter
    /// on, over the last tick (finite difference of the filtered positions).
    pub fn velocity_mm_per_s(&self) -> f64 {
        if self.filter.active() {
            self.out_v_mm_per_s
        } else {
            self.v_mm_per_s
        }
    }

    /// Path length left in the move executing now, mm (0 between moves, in a dwell or at rest
    /// before the front move starts): the DRO's distance to go.
    pub fn distance_to_go_mm(&self) -> f64 {
        match self.planner.front().map(|e| &e.kind) {
            Some(EntryKind::Move(seg)) if self.front_started => {
                (seg.length_mm - self.s_mm).max(0.0)
            }
            _ => 0.0,
        }
    }

    /// Path acceleration of the axes over the last tick (change of the path velocity), mm/s².
    pub fn acceleration_mm_per_s2(&self) -> f64 {
        self.out_a_mm_per_s2
    }

    /// Path jerk of the axes over the last tick, mm/s³.
    pub fn jerk_mm_per_s3(&self) -> f64 {
        self.out_j_mm_per_s3
    }

    /// The axis filter's windows together, s: how long the axes lag the interpolator
    /// (0 without corner smoothing and jerk limits).
    pub fn filter_lag_s(&self) -> f64 {
        if self.filter.active() {
            self.filter.total_window_s()
        } else {
            0.0
        }
    }

    /// Nothing in execution and nothing held (the queue may still hold blocks).
    pub fn idle(&self) -> bool {
        self.planner.is_empty()
    }

    /// Motion stands still only because no more blocks came: everything released has run, and
    /// what the window holds (if anything) waits for the window to fill, a flush or the program
    /// end. Not during a feed hold, not after the program end.
    pub fn waiting_for_data(&self) -> bool {
        !self.ended
            && !self.hold
            && self.planner.released() == 0
            && self.v_mm_per_s == 0.0
            && self.filter.settled()
    }

    /// Blocks held in the window (not yet released).
    pub fn held_blocks(&self) -> usize {
        self.planner.held()
    }

    /// Blocks released and not yet done (the one executing included).
    pub(crate) fn released_blocks(&self) -> usize {
        self.planner.released()
    }

    pub fn lookahead_blocks(&self) -> usize {
        self.planner.lookahead()
    }

    pub fn set_override(&mut self, pct: f64) {
        let pct = if pct.is_finite() {
            pct.clamp(0.0, 200.0)
        } else {
            100.0
        };
        if pct != self.override_pct {
            self.override_pct = pct;
            self.planner.mark_dirty();
        }
    }

    pub(crate) fn override_pct(&self) -> f64 {
        self.override_pct
    }

    /// Feed hold: brake on the path to a stop; `false` resumes.
    pub fn set_hold(&mut self, hold: bool) {
        self.hold = hold;
    }

    /// The operator's M01 switch (`mc_command_M01_stop_enable_w`): M01 stops only while on.
    pub(crate) fn set_optional_stop(&mut self, on: bool) {
        self.optional_stop = on;
    }

    pub fn hold(&self) -> bool {
        self.hold
    }

    /// A program starts: execution may run again.
    pub fn start(&mut self) {
        self.ended = false;
        self.hold = false;
        self.clear();
    }

    /// Reset: stop at once where we are.
    pub fn reset(&mut self) {
        self.hold = false;
        self.ended = false;
        self.clear();
        self.pos_in = self.pos;
        self.filter.fill(self.pos);
        self.out_v_mm_per_s = 0.0;
        self.out_a_mm_per_s2 = 0.0;
        self.out_j_mm_per_s3 = 0.0;
    }

    fn clear(&mut self) {
        self.planner.clear();
        self.s_mm = 0.0;
        self.v_mm_per_s = 0.0;
        self.front_started = false;
        self.dwell_done_s = 0.0;
    }

    /// Set the machine position (start-up, or after a reset moved nothing).
    pub fn set_position(&mut self, p: Position) {
        self.pos = p;
        self.pos_in = p;
        self.filter.fill(p);
    }

    /// Record per-tick samples for a plot, at most `max_samples` (decimated).
    pub(crate) fn enable_trace(&mut self, max_samples: usize) {
        self.trace = Some(Trace::new(max_samples));
    }

    /// Stream every `every`-th tick's axis positions, path velocity, acceleration and jerk to
    /// a CSV file (`run --trace`).
    pub(crate) fn enable_csv_trace(
        &mut self,
        path: &std::path::Path,
        every: u64,
    ) -> std::io::Result<()> {
        let axes: Vec<usize> = self.axes.iter().map(|a| a.index).collect();
        self.csv = Some(CsvTrace::create(path, &axes, every)?);
        Ok(())
    }

    /// Close the CSV trace (if any): its first write error, if there was one.
    pub(crate) fn finish_csv_trace(&mut self) -> std::io::Result<()> {
        match self.csv.take() {
            Some(c) => c.finish(),
            None => Ok(()),
        }
    }

    pub fn trace(&self) -> Option<&Trace> {
        self.trace.as_ref()
    }

    /// The channel reported an interrupt here: mark it in the trace.
    pub(crate) fn note_interrupt(&mut self) {
        let s = self.sample();
        if let Some(t) = self.trace.as_mut() {
            t.mark_interrupt(s);
        }
    }

    fn sample(&self) -> Sample {
        Sample {
            time_s: self.time_s,
            pos: self.pos,
            velocity_mm_per_s: self.out_v_mm_per_s,
            accel_mm_per_s2: self.out_a_mm_per_s2,
            jerk_mm_per_s3: self.out_j_mm_per_s3,
        }
    }

    /// Advance channel time by `dt_s`: take blocks into the window, plan, interpolate.
    /// One tick: take blocks from `queue`, plan, interpolate. A technology wait asks `acks`
    /// whether its functions are acknowledged.
    pub fn step(
        &mut self,
        dt_s: f64,
        queue: &mut BlockQueue,
        notes: &mut Vec<MotionNote>,
        acks: &impl Acknowledgements,
    ) {
        let dt_s = if dt_s.is_finite() { dt_s.max(0.0) } else { 0.0 };
        if dt_s > 0.0 {
            self.dt_s = dt_s;
        }
        self.time_s += dt_s;
        self.output_this_step = false;
        self.filter.configure(self.dt_s);
        if !self.ended {
            self.planner.set_front_busy(self.front_started);
            self.planner.set_cycle_s(self.dt_s);
            self.planner.take_from(queue);
            if let Some(e) = self.planner.take_error() {
                notes.push(MotionNote::Error {
                    code: e.code,
                    msg: e.msg,
                    block: e.block,
                });
                // Nothing more moves: the channel stops on the error (a software limit is
                // found before the axes reach it, and must stay so).
                self.v_mm_per_s = 0.0;
            } else {
                self.planner.plan_if_needed(self.override_pct, self.dt_s);
                self.execute(dt_s, notes, acks);
            }
        } else {
            self.v_mm_per_s = 0.0;
        }
        if dt_s > 0.0 {
            self.filter_step(dt_s);
        }
        if self.trace.is_some() || self.csv.is_some() {
            let s = self.sample();
            if let Some(t) = self.trace.as_mut() {
                t.record(s);
            }
            if let Some(c) = self.csv.as_mut() {
                c.record(&s);
            }
        }
    }

    /// Move the axes: the interpolated position through the axis filter, and the path
    /// velocity, acceleration and jerk the axes show.
    fn filter_step(&mut self, dt_s: f64) {
        let out = self.filter.push(self.pos_in);
        let mut d2 = 0.0;
        for (o, p) in out.iter().zip(&self.pos) {
            d2 += (o - p) * (o - p);
        }
        let v = d2.sqrt() / dt_s;
        let a = (v - self.out_v_mm_per_s) / dt_s;
        self.out_j_mm_per_s3 = (a - self.out_a_mm_per_s2) / dt_s;
        self.out_a_mm_per_s2 = a;
        self.out_v_mm_per_s = v;
        self.pos = out;
    }

    /// Run released entries for `dt_s` seconds.
    fn execute(&mut self, dt_s: f64, notes: &mut Vec<MotionNote>, acks: &impl Acknowledgements) {
        let cruise_pct = if self.hold { 0.0 } else { self.override_pct };
        let mut left = dt_s;
        // Each pass pops an entry or ends the tick, so the window length bounds the loop.
        let passes = self.planner.len() + 1;
        for _ in 0..passes {
            if self.planner.released() == 0 {
                break;
            }
            // A move starting at rest with the axes settled begins a new run.
            if !self.front_started
                && left > 0.0
                && self.v_mm_per_s == 0.0
                && self.filter.settled()
                && matches!(
                    self.planner.front().map(|e| &e.kind),
                    Some(EntryKind::Move(_))
                )
            {
                self.begin_run();
            }
            if !self.front_started && !self.start_front(left, notes) {
                break;
            }
            let Some(next) = self.run_front(cruise_pct, &mut left, notes, acks) else {
                break;
            };
            match next {
                Next::Pop => self.finish_front(),
                Next::PopAndHold => {
                    self.finish_front();
                    self.hold = true;
                    break;
                }
                Next::Stay => break,
                Next::End => {
                    self.ended = true;
                    self.clear();
                    break;
                }
            }
        }
        // Standing unless a motion block is under way (the plan brought it to rest already;
        // this only removes rounding residue).
        let moving = self.front_started
            && self
                .planner
                .front()
                .is_some_and(|e| matches!(e.kind, EntryKind::Move(_)));
        let continues = self.planner.released() > 0
            && self
                .planner
                .entries()
                .take(self.planner.released())
                .find(|e| {
                    !matches!(
                        e.kind,
                        EntryKind::Plain
                            | EntryKind::Message(_)
                            | EntryKind::Flush(FlushKind::Continue)
                    )
                })
                .is_some_and(|e| matches!(e.kind, EntryKind::Move(_)));
        if !moving && !continues {
            self.v_mm_per_s = 0.0;
        }
        self.pre_output(notes);
    }

    /// A run starts with the front move, at rest with the filter settled: a straight move
    /// that a stop follows runs as a lone move with the windows of its optimum, anything else
    /// as a general run with the configured windows.
    ///
    /// The lone move's window T is that of the time-optimal profile with the path limits
    /// v, a, j: the jerk phase a/j when both limits are reached, √(v/j) when only the velocity
    /// is, ∛(L/2j) when neither is — in whole ticks; the trapezoid under it accelerates at
    /// min(a, j·T).
    fn begin_run(&mut self) {
        let Some(planner::Entry {
            kind: EntryKind::Move(seg),
            ..
        }) = self.planner.front()
        else {
            return;
        };
        if self.planner.front_is_lone_line() {
            let (a, j) = self.planner.line_limits(seg);
            let v = match seg.cruise_mm_per_s(self.override_pct) {
                v if v > 0.0 => v,
                _ => seg.limit_mm_per_s,
            };
            // (window in ticks, the same in s, the trapezoid's acceleration)
            let (n, window_s, accel) = if j.is_finite() {
                let t = (a / j)
                    .min((v / j).sqrt())
                    .min((seg.length_mm / (2.0 * j)).cbrt());
                let n = AxisFilter::ticks(t, self.dt_s);
                let w = n as f64 * self.dt_s;
                (n, w, a.min(j * w))
            } else {
                (1, 0.0, a)
            };
            if self.filter.use_windows(1, n) {
                self.run = Run::Lone {
                    accel_mm_per_s2: accel,
                    swing: Swing::new(window_s),
                };
                return;
            }
        }
        let (mut nc, nj) = self.filter.general_ticks(self.dt_s);
        if seg.mv.path.contour_dev_mm.is_some() {
            // A contoured run blends its corners into tangent arcs within the programmed
            // deviation; the corner filter would cut them further inside (0.09 mm instead of
            // 0.05 on the contoured square), so it runs without one.
            nc = 1;
        }
        if self.filter.use_windows(nc, nj) {
            self.run = Run::General;
            let corner_s = if nc > 1 {
                self.filter.corner_window_s()
            } else {
                0.0
            };
            self.planner.set_corner_window_s(corner_s);
            self.planner.plan_if_needed(self.override_pct, self.dt_s);
        }
    }

    /// MEP_SVS / MET_SVS: a group whose pre-output point the moving front block has passed
    /// goes to the PLC now (planner/pre_output.rs); measured from where the front move is.
    fn pre_output(&mut self, notes: &mut Vec<MotionNote>) {
        if !self.front_started {
            return;
        }
        let Some(EntryKind::Move(seg)) = self.planner.front().map(|e| &e.kind) else {
            return;
        };
        let to_go_mm = (seg.length_mm - self.s_mm).max(0.0);
        let to_go_s = to_go_mm / seg.cruise_mm_per_s(self.override_pct).max(1e-9);
        while let Some(g) = self
            .planner
            .take_due_pre_output(to_go_mm, to_go_s, self.override_pct)
        {
            self.output_this_step = true;
            notes.push(MotionNote::TechnoOutput(g));
        }
    }

    /// STEP 1 of an entry: start the front entry if it may start now — a move only with time
    /// left in the tick, nothing while held at rest, a stop only once the axes stand. Emits
    /// its `Started` note. Returns whether it started.
    #[inline]
    fn start_front(&mut self, left: f64, notes: &mut Vec<MotionNote>) -> bool {
        let Some(front) = self.planner.front_mut() else {
            return false;
        };
        if matches!(front.kind, EntryKind::Move(_)) && left <= 0.0 {
            return false;
        }
        // Held at rest (feed hold that has braked, a programmed stop): the next block does
        // not start until the hold is released.
        if self.hold && self.v_mm_per_s == 0.0 {
            return false;
        }
        // A stop (dwell, flush stop, program end) takes effect when the axes stand, not only
        // the interpolator.
        if front.kind.is_barrier() && !self.filter.settled() {
            return false;
        }
        if let Some(info) = front.info.take() {
            notes.push(MotionNote::Started(info));
        }
        self.front_started = true;
        self.s_mm = 0.0;
        self.dwell_done_s = 0.0;
        if let (EntryKind::Move(seg), Some(t)) = (&front.kind, self.trace.as_mut()) {
            if let MoveKind::Arc { plane, .. } = seg.mv.kind {
                t.set_plane(plane);
            }
        }
        true
    }

    /// STEP 2 of an entry: run the started front entry for what is `left` of the tick (and
    /// take the time it used off it); what happens to it next.
    fn run_front(
        &mut self,
        cruise_pct: f64,
        left: &mut f64,
        notes: &mut Vec<MotionNote>,
        acks: &impl Acknowledgements,
    ) -> Option<Next> {
        let front = self.planner.front()?;
        Some(match &front.kind {
            EntryKind::Move(seg) => {
                let profile = Profile {
                    length_mm: seg.length_mm,
                    accel_mm_per_s2: seg.accel_mm_per_s2,
                    cruise_mm_per_s: seg.cruise_mm_per_s(cruise_pct),
                    exit_mm_per_s: seg.exit_mm_per_s,
                };
                let mv = seg.mv;
                self.run_move(&profile, &mv, left)
            }
            EntryKind::Dwell { seconds } => {
                let seconds = *seconds;
                self.v_mm_per_s = 0.0;
                if self.hold {
                    Next::Stay
                } else {
                    let take = (seconds - self.dwell_done_s).min(*left).max(0.0);
                    self.dwell_done_s += take;
                    *left -= take;
                    if self.dwell_done_s >= seconds - 1e-12 {
                        Next::Pop
                    } else {
                        Next::Stay
                    }
                }
            }
            EntryKind::Plain => Next::Pop,
            EntryKind::Message(m) => {
                notes.push(MotionNote::Message(m.clone()));
                Next::Pop
            }
            EntryKind::TechnoOutput(g) => {
                self.output_this_step = true;
                notes.push(MotionNote::TechnoOutput(g.clone()));
                Next::Pop
            }
            EntryKind::TechnoWait(seqs) => {
                self.v_mm_per_s = 0.0;
                if seqs.iter().all(|s| acks.is_acknowledged(*s)) {
                    Next::Pop
                } else {
                    // Channel time passes while the PLC works: the rest of the tick is
                    // spent standing.
                    *left = 0.0;
                    Next::Stay
                }
            }
            EntryKind::Stop { optional } => {
                if *optional && !self.optional_stop {
                    Next::Pop
                } else {
                    notes.push(MotionNote::ProgramStop {
                        optional: *optional,
                    });
                    Next::PopAndHold
                }
            }
            EntryKind::Flush(k) => {
                notes.push(MotionNote::Flush(*k));
                Next::Pop
            }
            // The program ends when its technology functions are finished too.
            EntryKind::End { .. } if self.output_this_step || !acks.all_acknowledged() => {
                *left = 0.0;
                Next::Stay
            }
            EntryKind::End { m, prog } => {
                notes.push(MotionNote::End {
                    m: *m,
                    prog: prog.clone(),
                });
                Next::End
            }
        })
    }

    /// Interpolate the front move along `profile` for what is `left` of the tick, by the rule
    /// of the present run; the axes' input position at the new path position.
    fn run_move(&mut self, profile: &Profile, mv: &Move, left: &mut f64) -> Next {
        let r = match &mut self.run {
            Run::General => advance(&mut self.s_mm, &mut self.v_mm_per_s, profile, *left),
            Run::Lone {
                accel_mm_per_s2,
                swing,
            } => advance_swing(
                &mut self.s_mm,
                &mut self.v_mm_per_s,
                &Profile {
                    accel_mm_per_s2: *accel_mm_per_s2,
                    ..*profile
                },
                *left,
                swing,
            ),
        };
        *left -= r.used_s;
        if r.finished {
            // Snap: the block ends exactly at its programmed end point.
            self.pos_in = mv.end;
            Next::Pop
        } else {
            self.pos_in = point_at(mv, profile.length_mm, self.s_mm);
            Next::Stay
        }
    }

    fn finish_front(&mut self) {
        self.planner.pop_front();
        self.front_started = false;
        self.s_mm = 0.0;
        self.dwell_done_s = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::arc::{arc_move, ArcSpec};
    use crate::machine::rng::SplitMix64;
    use crate::queue::{Action, PathMode, Plane, QueuedBlock};
    use crate::vocab::techno::NoUnits;

    fn block(line: u32, action: Action) -> QueuedBlock {
        QueuedBlock {
            info: BlockInfo {
                prog: Arc::from("t.nc"),
                line,
                offset: 0,
                counter: u64::from(line),
                n: None,
                text: None,
                stream: false,
            },
            action,
            silent: false,
        }
    }

    /// The plan that stops early among blocks planned before gives every block the exit a
    /// plan of the whole window gives, bit for bit: on short steps, reversals, arcs, plain
    /// blocks, dwells, flushes and override changes, at every tick.
    #[test]
    fn the_plan_that_stops_early_equals_the_whole_plan() {
        let axes: Vec<AxisLimits> = (0..3)
            .map(|index| AxisLimits {
                index,
                max_velocity_mm_per_min: 30_000.0,
                max_accel_mm_per_s2: 2_000.0,
                max_jerk_mm_per_s3: None,
                rapid_mm_per_min: 30_000.0,
                min_mm: -10_000.0,
                max_mm: 10_000.0,
            })
            .collect();
        let settings = PlannerSettings {
            lookahead_blocks: 8,
            corner_smoothing_s: 0.0,
        };
        let mut m = Motion::with_planner(axes, settings);
        let mut rng = SplitMix64::new(7);
        let mut q = BlockQueue::new(64);
        let mut notes = Vec::new();
        let (mut at, mut before) = ([0.0; MAX_AXES], [0.0; MAX_AXES]);
        let mut line = 0u32;
        for tick in 0..1_000_000u32 {
            while line < 5_000 && q.len() < 16 {
                line += 1;
                let feed = 500.0 + rng.unit() * 20_000.0;
                let r = rng.unit();
                let action = if r < 0.05 {
                    Action::None
                } else if r < 0.10 {
                    Action::Dwell { seconds: 0.002 }
                } else if r < 0.12 {
                    Action::Flush(FlushKind::Continue)
                } else if r < 0.15 {
                    let spec = ArcSpec {
                        plane: Plane::Xy,
                        ijk: [Some(1.0 + rng.unit()), Some(0.0), None],
                        radius: None,
                        cw: rng.unit() < 0.5,
                    };
                    let mut to = at;
                    to[0] += 2.0 * spec.ijk[0].unwrap_or(1.0);
                    match arc_move(&spec, at, to, feed, 1e-6) {
                        Ok(mv) => {
                            (before, at) = (at, to);
                            Action::Move(Box::new(mv))
                        }
                        Err(_) => Action::None,
                    }
                } else {
                    // A short step, now and then straight back (a reversal).
                    let to = if rng.unit() < 0.2 {
                        before
                    } else {
                        let mut to = at;
                        for x in to.iter_mut().take(3) {
                            *x += (rng.unit() - 0.5) * 4.0 * rng.unit();
                        }
                        to
                    };
                    let mv = Move {
                        kind: MoveKind::Line,
                        start: at,
                        end: to,
                        feed_mm_per_min: feed,
                        path: PathMode::default(),
                    };
                    (before, at) = (at, to);
                    Action::Move(Box::new(mv))
                };
                q.push(block(line, action));
            }
            if line == 5_000 && q.is_empty() && m.planner.is_empty() {
                break;
            }
            if tick % 997 == 0 {
                m.set_override(50.0 + rng.unit() * 100.0);
            }
            m.step(0.001, &mut q, &mut notes, &NoUnits);
            notes.clear();
            // The plan this tick made (it stops early where it may), against the whole window's.
            let (planned, whole) = m.planner.plan_both_ways(m.override_pct, m.dt_s);
            assert_eq!(planned, whole, "tick {tick}");
        }
        assert!(line == 5_000 && m.planner.is_empty(), "ran {line} blocks");
    }
}
