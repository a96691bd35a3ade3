//! The decoder: reads NC lines from the top frame (file text, cache entry or stream segment),
//! interprets control flow, parameters and modal state, and queues blocks for motion.
//!
//! It decodes only while the block queue has room and only up to its per-tick budget, and it
//! pulls a new stream segment only when it has decoded the previous one: that is the whole of
//! the channel's back-pressure.

pub mod arc;
mod expr;
pub mod flow;
pub mod frame;
pub mod modal;
pub mod vars;

use std::fmt;
use std::sync::Arc;
use std::time::Duration;

use crate::lang::block::{
    Block, Body, Call, Command, Control, FlushKind, GotoTarget, Item, Label, SplineCommand, Value,
};
use crate::lang::{is_comment_end, parse_block, parse_var_declaration};
use crate::queue::{
    Action, BlockInfo, BlockQueue, Move, MoveKind, Position, QueuedBlock, AXIS_LETTERS, MAX_AXES,
};
use crate::source::cache::Cache;
use crate::source::store::{Opened, ProgramKind, ProgramStore};
use crate::source::stream::StreamBuffer;

use flow::{closes_loop, is_loop_statement, nesting, FlowEntry, Nesting, Skip, SkipUntil};
use frame::{
    read_file_line, Frame, FrameKind, LabelIndex, LineMeta, LinePos, LineRead, Source, StreamNote,
    StreamReader, MAX_SEEN_LABELS,
};
use modal::{apply_g, apply_m, BlockGs, Modal, MotionMode, ZeroOffsets};
use vars::{VarSlot, VarStore};

/// Error numbers of our own range, where the ISG number is not known (README, "Error numbers").
pub mod own_codes {
    pub const NESTING_TOO_DEEP: u32 = 90101;
    pub const STREAM_ALREADY_ACTIVE: u32 = 90102;
    pub const MAIN_END_MISSING: u32 = 90103;
    pub const SUB_END_MISSING: u32 = 90104;
    pub const ARC_INCONSISTENT: u32 = 90130;
    pub const NO_FEED: u32 = 90131;
    pub const BAD_VALUE: u32 = 90132;
    pub const TOO_MANY_VARIABLES: u32 = 90152;
}

/// What the decoder needs from the configuration.
#[derive(Debug, Clone)]
pub struct DecoderSettings {
    /// Lines decoded per tick at most (runtime.toml `decoder.blocks_per_tick`).
    pub blocks_per_tick: usize,
    /// Subroutine nesting depth at most (main program = level 0).
    pub max_depth: usize,
    /// Axes the channel has, by letter index of `AXIS_LETTERS`.
    pub axes: [bool; MAX_AXES],
    pub zero_offsets: ZeroOffsets,
    /// How far the end point may lie off the circle, mm.
    pub arc_tolerance_mm: f64,
}

impl Default for DecoderSettings {
    fn default() -> Self {
        DecoderSettings {
            blocks_per_tick: 64,
            max_depth: 20,
            axes: [true, true, true, false, false, false],
            zero_offsets: [[0.0; MAX_AXES]; 6],
            arc_tolerance_mm: 0.01,
        }
    }
}

/// A decoding error: the ISG number, the message and the column when the parser knows it.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodeError {
    pub code: u32,
    pub msg: String,
    pub col: Option<u32>,
}

impl DecodeError {
    pub fn new(code: u32, msg: impl Into<String>) -> Self {
        DecodeError {
            code,
            msg: msg.into(),
            col: None,
        }
    }
    fn at(mut self, col: u32) -> Self {
        self.col = Some(col);
        self
    }
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {}", self.code, self.msg)
    }
}

/// Block search target (seed 003 §2.3.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SearchTarget {
    /// The first block with this N number.
    BlockNumber(u32),
    /// The block with this block counter.
    Counter(u64),
    /// The first block starting at or after this byte offset of the main program / stream.
    Offset(u64),
}

impl fmt::Display for SearchTarget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SearchTarget::BlockNumber(n) => write!(f, "n:{n}"),
            SearchTarget::Counter(k) => write!(f, "count:{k}"),
            SearchTarget::Offset(o) => write!(f, "offset:{o}"),
        }
    }
}

impl std::str::FromStr for SearchTarget {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (kind, v) = s.split_once(':').ok_or_else(|| {
            format!("search target '{s}': expected n:<N>, count:<K> or offset:<BYTES>")
        })?;
        let bad = |_| format!("search target '{s}': '{v}' is not a whole number");
        match kind {
            "n" => v.parse().map(SearchTarget::BlockNumber).map_err(bad),
            "count" => v.parse().map(SearchTarget::Counter).map_err(bad),
            "offset" => v.parse().map(SearchTarget::Offset).map_err(bad),
            _ => Err(format!(
                "search target '{s}': kind must be n, count or offset"
            )),
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct Search {
    target: SearchTarget,
    /// Machine position when the search began: the positioning move starts here.
    from: Position,
}

/// What the decoder reports besides queued blocks; the channel turns these into events.
#[derive(Debug, Clone, PartialEq)]
pub enum Note {
    ProgramStart {
        prog: Arc<str>,
        stream: bool,
    },
    Segment {
        bytes: usize,
    },
    Discard {
        bytes: usize,
    },
    Warning {
        code: u32,
        msg: String,
    },
    Error {
        code: u32,
        msg: String,
        prog: Arc<str>,
        line: u32,
        col: Option<u32>,
    },
    Search {
        target: SearchTarget,
        found: bool,
    },
    Cache {
        op: &'static str,
        file: String,
    },
}

/// Where the decoder stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DecoderState {
    /// No program.
    Idle,
    Running,
    /// The main program's end has been decoded (and queued).
    Ended,
    /// An error stopped decoding; only a reset clears it.
    Failed,
}

/// The channel's parts the decoder reads from and writes to during one step.
pub struct DecoderIo<'a> {
    pub stream: &'a mut StreamBuffer,
    pub store: &'a mut ProgramStore,
    pub cache: &'a mut Cache,
    pub queue: &'a mut BlockQueue,
    /// Motion has nothing left to do (for `#FLUSH WAIT`).
    pub motion_idle: bool,
    /// Keep each block's text for the event log (and report cache hits: events are on).
    pub want_text: bool,
    /// Channel time at the start of this tick.
    pub now: Duration,
    /// Length of this tick: decoding stops for the tick once simulated file-system latency
    /// has used it up.
    pub period: Duration,
}

/// Counters for the report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DecoderStats {
    /// Lines decoded (all of them: skipped, comments, loop passes).
    pub lines: u64,
    /// Blocks queued (those that take effect).
    pub blocks: u64,
}

pub struct Decoder {
    settings: DecoderSettings,
    frames: Vec<Frame>,
    stream: StreamReader,
    /// A stream frame is on the frame stack.
    stream_active: bool,
    vars: VarStore,
    modal: Modal,
    /// ISG block counter of the current program.
    counter: u64,
    state: DecoderState,
    search: Option<Search>,
    /// Bit n set: blocks with `/n` are skipped (`/` is `/1`).
    skip_mask: u16,
    /// `#FLUSH WAIT`: decoding waits until motion is empty.
    wait_idle: bool,
    /// The top frame is a stream that has no complete line: motion may starve.
    starved: bool,
    /// Channel time when the last simulated file-system read completes (runtime.toml
    /// `fs_latency_us`). Decoding does nothing before it; motion runs on meanwhile.
    ready_at: Duration,
    line: String,
    notes: Vec<Note>,
    stats: DecoderStats,
}

type Res<T = ()> = Result<T, DecodeError>;

impl Decoder {
    pub fn new(settings: DecoderSettings) -> Self {
        Decoder {
            settings,
            frames: Vec::new(),
            stream: StreamReader::default(),
            stream_active: false,
            vars: VarStore::new(),
            modal: Modal::defaults([0.0; MAX_AXES]),
            counter: 0,
            state: DecoderState::Idle,
            search: None,
            skip_mask: 0,
            wait_idle: false,
            starved: false,
            ready_at: Duration::ZERO,
            line: String::new(),
            notes: Vec::new(),
            stats: DecoderStats::default(),
        }
    }

    pub fn state(&self) -> DecoderState {
        self.state
    }
    /// Axes the channel has, by `AXIS_LETTERS` index.
    pub fn axes(&self) -> [bool; MAX_AXES] {
        self.settings.axes
    }
    pub fn modal(&self) -> &Modal {
        &self.modal
    }
    pub fn vars(&self) -> &VarStore {
        &self.vars
    }
    pub fn vars_mut(&mut self) -> &mut VarStore {
        &mut self.vars
    }
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }
    pub fn counter(&self) -> u64 {
        self.counter
    }
    /// Streaming mode: a stream frame is being decoded.
    pub fn streaming(&self) -> bool {
        self.stream_active
    }
    /// Waiting for stream data that has not arrived.
    pub fn starved(&self) -> bool {
        self.starved && self.state == DecoderState::Running
    }
    pub fn searching(&self) -> bool {
        self.search.is_some()
    }
    pub fn set_skip_mask(&mut self, mask: u16) {
        self.skip_mask = mask;
    }
    pub fn depth(&self) -> usize {
        self.frames.len()
    }
    /// Notes since the last call, oldest first.
    pub fn take_notes(&mut self, into: &mut Vec<Note>) {
        // A swap: both vectors keep their allocations from tick to tick.
        into.clear();
        std::mem::swap(&mut self.notes, into);
    }

    /// Start a main program (automatic mode). Channel defaults are restored here — for a
    /// stream once, at stream start, as seed 003 §2.4 describes.
    pub fn start(
        &mut self,
        name: &str,
        store: &mut ProgramStore,
        machine_pos: Position,
        search: Option<SearchTarget>,
    ) -> Res {
        self.frames.clear();
        self.modal = Modal::defaults(machine_pos);
        self.vars.start_program();
        self.counter = 0;
        self.wait_idle = false;
        self.starved = false;
        self.ready_at = Duration::ZERO;
        // A read charged to an earlier program is not this one's to wait for.
        store.take_owed();
        self.stream_active = false;
        self.search = search.map(|target| Search {
            target,
            from: machine_pos,
        });
        let opened = store
            .open(name, ProgramKind::Main)
            .map_err(|e| DecodeError::new(e.code(), e.to_string()))?;
        match opened {
            Opened::File(p) => {
                let prog = p.name.clone();
                self.frames
                    .push(Frame::new(FrameKind::Main, Source::File(p), prog.clone()));
                self.notes.push(Note::ProgramStart {
                    prog,
                    stream: false,
                });
            }
            Opened::Stream { name } => {
                self.begin_stream();
                self.frames
                    .push(Frame::new(FrameKind::Main, Source::Stream, name.clone()));
                self.notes.push(Note::ProgramStart {
                    prog: name,
                    stream: true,
                });
            }
        }
        self.state = DecoderState::Running;
        Ok(())
    }

    /// Channel reset: frames, stream position, parameters and modal state go; V.S. stays.
    pub fn reset(&mut self, machine_pos: Position) {
        self.frames.clear();
        self.stream.restart();
        self.stream_active = false;
        self.vars.reset();
        self.modal = Modal::defaults(machine_pos);
        self.counter = 0;
        self.state = DecoderState::Idle;
        self.search = None;
        self.wait_idle = false;
        self.starved = false;
        self.ready_at = Duration::ZERO;
    }

    fn begin_stream(&mut self) {
        self.stream.restart();
        self.stream_active = true;
    }

    /// Decode up to the per-tick budget.
    ///
    /// Simulated file-system latency never blocks the tick: a file read (main program, call,
    /// `#CACHE LOAD`) moves `ready_at` on by its cost, counted from when the decoder was free,
    /// and decoding goes on in this tick only while `ready_at` lies inside it. So reads of
    /// 200 µs in 1 ms ticks give five per tick, and a 5 ms read pauses decoding for five ticks.
    pub fn step(&mut self, io: &mut DecoderIo<'_>) {
        let mut budget = self.settings.blocks_per_tick;
        let tick_end = io.now + io.period;
        while budget > 0 && self.state == DecoderState::Running {
            let owed = io.store.take_owed();
            if !owed.is_zero() {
                self.ready_at = self.ready_at.max(io.now) + owed;
            }
            if self.ready_at >= tick_end {
                break;
            }
            if self.wait_idle {
                if io.queue.is_empty() && io.motion_idle {
                    self.wait_idle = false;
                } else {
                    break;
                }
            }
            if !io.queue.has_room() {
                break;
            }
            let Some(top) = self.frames.last_mut() else {
                self.state = DecoderState::Idle;
                break;
            };
            let mut line = std::mem::take(&mut self.line);
            let read = if top.is_stream() {
                let mut note = None;
                let r = self.stream.next_line(io.stream, &mut line, &mut note);
                if let Some(StreamNote::Segment { bytes }) = note {
                    self.notes.push(Note::Segment { bytes });
                }
                r
            } else {
                read_file_line(top, &mut line)
            };
            match read {
                LineRead::Pending => {
                    self.starved = true;
                    self.line = line;
                    break;
                }
                LineRead::Eof => {
                    self.line = line;
                    budget -= 1;
                    if let Err(e) = self.end_of_file(io) {
                        let meta = LineMeta {
                            line: self.frames.last().map_or(0, |f| f.line_no),
                            offset: 0,
                        };
                        self.fail(e, meta);
                    }
                }
                LineRead::Line(meta) => {
                    self.starved = false;
                    budget -= 1;
                    self.counter += 1;
                    self.stats.lines += 1;
                    let r = self.process_line(&line, meta, io);
                    self.line = line;
                    if let Err(e) = r {
                        self.fail(e, meta);
                    }
                }
            }
        }
    }

    fn fail(&mut self, e: DecodeError, meta: LineMeta) {
        let prog = self
            .frames
            .last()
            .map(|f| f.prog.clone())
            .unwrap_or_else(|| Arc::from(""));
        self.notes.push(Note::Error {
            code: e.code,
            msg: e.msg,
            prog,
            line: meta.line,
            col: e.col,
        });
        self.state = DecoderState::Failed;
        self.search = None;
    }

    /// Raise an error from outside the decoder's own lines (e.g. stream data without CR LF).
    pub fn abort(&mut self, code: u32, msg: impl Into<String>) {
        let line = self.frames.last().map_or(0, |f| f.line_no);
        self.fail(DecodeError::new(code, msg), LineMeta { line, offset: 0 });
    }

    fn top(&mut self) -> &mut Frame {
        // process_line and friends run only with a frame on the stack (checked in step).
        let i = self.frames.len() - 1;
        &mut self.frames[i]
    }

    fn process_line(&mut self, text: &str, meta: LineMeta, io: &mut DecoderIo<'_>) -> Res {
        let top = self.top();
        if top.comment_block {
            if is_comment_end(text) {
                top.comment_block = false;
            }
            return Ok(());
        }
        let skipping = top.skip.is_some();
        let block = match parse_block(text) {
            Ok(b) => b,
            // A syntax error in a skipped line never runs, so it is no error.
            Err(_) if skipping => return Ok(()),
            Err(e) => return Err(DecodeError::new(e.code, e.message.clone()).at(e.col)),
        };
        let top = self.top();
        if top.var_block {
            match block.body {
                Body::Command(Command::EndVar) => top.var_block = false,
                // Blank and comment-only lines declare nothing.
                Body::Items(ref items) if items.is_empty() => {}
                _ => {
                    let d = parse_var_declaration(text)
                        .map_err(|e| DecodeError::new(e.code, e.message.clone()).at(e.col))?;
                    self.declare(&d)?;
                }
            }
            return Ok(());
        }
        if top.is_stream() {
            if let Body::Control(c) = &block.body {
                if is_loop_statement(c) {
                    return Err(DecodeError::new(
                        21478,
                        "loop statement in streaming program; streaming aborted",
                    ));
                }
            }
            if let Body::Call(Call::Local { .. }) = &block.body {
                return Err(DecodeError::new(
                    21479,
                    "local subroutine call (LL) in streaming program",
                ));
            }
        }
        if skipping {
            let run_it = self.skip_line(&block)?;
            if !run_it {
                return Ok(());
            }
        } else if let Some(l) = &block.label {
            self.note_label(l)?;
        }
        if let Some(s) = self.search {
            let hit = match s.target {
                SearchTarget::BlockNumber(n) => block.n == Some(n),
                SearchTarget::Counter(k) => self.counter >= k,
                SearchTarget::Offset(o) => self.frames.len() == 1 && meta.offset >= o,
            };
            if hit {
                self.finish_search(s, &block, text, meta, io);
            }
        }
        if let Some(level) = block.skip_level {
            if self.skip_mask & (1u16 << level.min(15)) != 0 {
                return Ok(());
            }
        }
        match &block.body {
            Body::Items(items) if items.is_empty() => Ok(()),
            Body::Items(items) => self.exec_items(items, &block, text, meta, io),
            Body::Control(c) => self.exec_control(c, meta),
            Body::Command(c) => self.exec_command(c, &block, text, meta, io),
            Body::Call(c) => self.exec_call(c, &block, text, meta, io),
            Body::ProgramHead { local: true, .. } => {
                // A local subroutine section met while running: it runs only when called.
                let top = self.top();
                top.skip = Some(Skip::new(SkipUntil::LocalSubroutine));
                Ok(())
            }
            Body::ProgramHead { local: false, .. } => Ok(()),
        }
    }

    /// Record a label passed in a stream: a label seen twice is 20836; a later `$GOTO` to a
    /// seen label is a backward jump.
    fn note_label(&mut self, l: &Label) -> Res {
        let top = self.top();
        if !top.is_stream() {
            return Ok(());
        }
        if top.seen_labels.contains(l) {
            return Err(DecodeError::new(
                20836,
                format!("label {} defined twice", label_text(l)),
            ));
        }
        if top.seen_labels.len() < MAX_SEEN_LABELS {
            top.seen_labels.insert(l.clone());
        }
        Ok(())
    }

    /// One line while skipping. Returns whether the line is to be executed after all (the
    /// label line a forward jump was looking for).
    fn skip_line(&mut self, block: &Block) -> Res<bool> {
        let is_stream = self.top().is_stream();
        let Some(skip) = self.top().skip.clone() else {
            return Ok(true);
        };
        if let SkipUntil::Label(t) = &skip.until {
            if let Some(l) = &block.label {
                self.note_label(l)?;
                if label_matches(l, t) {
                    self.top().skip = None;
                    return Ok(true);
                }
            }
            if let Body::Control(c) = &block.body {
                // Structures opened or closed between jump and label keep the stack right.
                let top = self.top();
                match c {
                    Control::If(_) => top.flow.push(FlowEntry::If { taken: true }),
                    Control::Switch(_) => top.flow.push(FlowEntry::Switch { value: f64::NAN }),
                    Control::EndIf if matches!(top.flow.last(), Some(FlowEntry::If { .. })) => {
                        top.flow.pop();
                    }
                    Control::EndSwitch
                        if matches!(top.flow.last(), Some(FlowEntry::Switch { .. })) =>
                    {
                        top.flow.pop();
                    }
                    _ => {}
                }
            }
            if is_stream && block_ends_program(block) {
                return Err(DecodeError::new(
                    20840,
                    format!("label {} not found before program end", goto_text(t)),
                ));
            }
            return Ok(false);
        }
        if skip.until == SkipUntil::LocalSubroutine {
            if let Body::Items(items) = &block.body {
                if items_have_m(items, &[17, 29]) {
                    self.top().skip = None;
                }
            }
            return Ok(false);
        }
        let Body::Control(c) = &block.body else {
            return Ok(false);
        };
        match nesting(c) {
            Nesting::Open => {
                if let Some(s) = self.top().skip.as_mut() {
                    s.depth += 1;
                }
                return Ok(false);
            }
            Nesting::Close if skip.depth > 0 => {
                if let Some(s) = self.top().skip.as_mut() {
                    s.depth -= 1;
                }
                return Ok(false);
            }
            _ => {}
        }
        if skip.depth > 0 {
            return Ok(false);
        }
        match (&skip.until, c) {
            (SkipUntil::IfBranch, Control::ElseIf(e))
                if crate::lang::eval::is_true(self.eval(e)?) =>
            {
                self.top().skip = None;
                self.set_if_taken();
            }
            (SkipUntil::IfBranch, Control::Else) => {
                self.top().skip = None;
                self.set_if_taken();
            }
            (SkipUntil::IfBranch | SkipUntil::IfEnd, Control::EndIf) => {
                let top = self.top();
                top.skip = None;
                top.flow.pop();
            }
            (SkipUntil::Case, Control::Case(e)) => {
                let v = self.eval(e)?;
                if let Some(FlowEntry::Switch { value }) = self.top().flow.last() {
                    if crate::lang::eval::case_matches(*value, v) {
                        self.top().skip = None;
                    }
                }
            }
            (SkipUntil::Case, Control::Default) => self.top().skip = None,
            (SkipUntil::Case | SkipUntil::SwitchEnd, Control::EndSwitch) => {
                let top = self.top();
                top.skip = None;
                top.flow.pop();
            }
            (SkipUntil::LoopExit, c) => {
                let top = self.top();
                if top.flow.last().is_some_and(|e| closes_loop(e, c)) {
                    top.skip = None;
                    top.flow.pop();
                }
            }
            (SkipUntil::LoopContinue, c) => {
                let top = self.top();
                if top.flow.last().is_some_and(|e| closes_loop(e, c)) {
                    top.skip = None;
                    return Ok(true);
                }
            }
            _ => {}
        }
        Ok(false)
    }

    fn set_if_taken(&mut self) {
        if let Some(FlowEntry::If { taken }) = self.top().flow.last_mut() {
            *taken = true;
        }
    }

    fn skip(&mut self, until: SkipUntil) {
        self.top().skip = Some(Skip::new(until));
    }

    fn stray(&self, c: &Control) -> DecodeError {
        use crate::lang::codes::StrayKind as K;
        let kind = match c {
            Control::Else => Some(K::Else),
            Control::ElseIf(_) => Some(K::ElseIf),
            Control::EndIf => Some(K::EndIf),
            Control::Case(_) => Some(K::Case),
            Control::Default => Some(K::Default),
            Control::Break => Some(K::Break),
            Control::EndSwitch => Some(K::EndSwitch),
            Control::EndFor => Some(K::EndFor),
            Control::EndWhile => Some(K::EndWhile),
            Control::EndDo(_) => Some(K::EndDo),
            Control::Until(_) => Some(K::Until),
            Control::Continue => Some(K::Continue),
            _ => None,
        };
        let code = kind.map_or(20200, K::code);
        DecodeError::new(code, format!("unexpected {}", control_name(c)))
    }

    fn exec_control(&mut self, c: &Control, meta: LineMeta) -> Res {
        use crate::lang::eval::is_true;
        let here = LinePos {
            pos: meta.offset as usize,
            line_no: meta.line - 1,
        };
        match c {
            Control::If(e) => {
                let v = is_true(self.eval(e)?);
                self.top().flow.push(FlowEntry::If { taken: v });
                if !v {
                    self.skip(SkipUntil::IfBranch);
                }
            }
            Control::IfGoto(e, t) => {
                if is_true(self.eval(e)?) {
                    self.goto(t)?;
                }
            }
            Control::ElseIf(_) | Control::Else => match self.top().flow.last() {
                Some(FlowEntry::If { .. }) => self.skip(SkipUntil::IfEnd),
                _ => return Err(self.stray(c)),
            },
            Control::EndIf => match self.top().flow.last() {
                Some(FlowEntry::If { .. }) => {
                    self.top().flow.pop();
                }
                _ => return Err(self.stray(c)),
            },
            Control::Switch(e) => {
                let value = self.eval(e)?;
                self.top().flow.push(FlowEntry::Switch { value });
                self.skip(SkipUntil::Case);
            }
            // Executing into a later case: fall through (no `$BREAK` before it).
            Control::Case(_) | Control::Default => match self.top().flow.last() {
                Some(FlowEntry::Switch { .. }) => {}
                _ => return Err(self.stray(c)),
            },
            Control::EndSwitch => match self.top().flow.last() {
                Some(FlowEntry::Switch { .. }) => {
                    self.top().flow.pop();
                }
                _ => return Err(self.stray(c)),
            },
            Control::Break => {
                let inner = self
                    .top()
                    .flow
                    .iter()
                    .rev()
                    .find(|e| e.is_loop() || matches!(e, FlowEntry::Switch { .. }))
                    .cloned();
                match inner {
                    Some(FlowEntry::Switch { .. }) => {
                        // Close inner $IFs between the $BREAK and its switch.
                        while matches!(self.top().flow.last(), Some(FlowEntry::If { .. })) {
                            self.top().flow.pop();
                        }
                        self.skip(SkipUntil::SwitchEnd);
                    }
                    Some(_) => {
                        while matches!(
                            self.top().flow.last(),
                            Some(FlowEntry::If { .. } | FlowEntry::Switch { .. })
                        ) {
                            self.top().flow.pop();
                        }
                        self.skip(SkipUntil::LoopExit);
                    }
                    None => return Err(self.stray(c)),
                }
            }
            Control::Continue => {
                if !self.top().flow.iter().any(FlowEntry::is_loop) {
                    return Err(self.stray(c));
                }
                while matches!(
                    self.top().flow.last(),
                    Some(FlowEntry::If { .. } | FlowEntry::Switch { .. })
                ) {
                    self.top().flow.pop();
                }
                self.skip(SkipUntil::LoopContinue);
            }
            Control::For {
                var,
                start,
                end,
                step,
            } => {
                let key = self.resolve(var)?;
                let start = self.eval(start)?;
                let end = self.eval(end)?;
                let step = match step {
                    Some(s) => self.eval(s)?,
                    None => 1.0,
                };
                if step == 0.0 || !step.is_finite() {
                    return Err(DecodeError::new(
                        own_codes::BAD_VALUE,
                        "$FOR step must not be 0",
                    ));
                }
                self.set_var(key.clone(), start)?;
                let body = self.top().line_pos();
                self.top().flow.push(FlowEntry::For {
                    var: key,
                    end,
                    step,
                    body,
                });
                if !for_continues(start, end, step) {
                    self.skip(SkipUntil::LoopExit);
                }
            }
            Control::EndFor => match self.top().flow.last().cloned() {
                Some(FlowEntry::For {
                    var,
                    end,
                    step,
                    body,
                }) => {
                    let v = self.vars.get(&var).unwrap_or(0.0) + step;
                    self.set_var(var, v)?;
                    if for_continues(v, end, step) {
                        self.top().seek(body);
                    } else {
                        self.top().flow.pop();
                    }
                }
                _ => return Err(self.stray(c)),
            },
            Control::While(e) => {
                let v = is_true(self.eval(e)?);
                self.top().flow.push(FlowEntry::While { head: here });
                if !v {
                    self.skip(SkipUntil::LoopExit);
                }
            }
            Control::EndWhile => match self.top().flow.last().cloned() {
                Some(FlowEntry::While { head }) => {
                    // Back to the $WHILE line, which evaluates and pushes again.
                    self.top().flow.pop();
                    self.top().seek(head);
                }
                _ => return Err(self.stray(c)),
            },
            Control::Do => {
                let body = self.top().line_pos();
                self.top().flow.push(FlowEntry::Do { body });
            }
            Control::EndDo(e) => match self.top().flow.last().cloned() {
                Some(FlowEntry::Do { body }) => {
                    if is_true(self.eval(e)?) {
                        self.top().seek(body);
                    } else {
                        self.top().flow.pop();
                    }
                }
                _ => return Err(self.stray(c)),
            },
            Control::Repeat => {
                let body = self.top().line_pos();
                self.top().flow.push(FlowEntry::Repeat { body });
            }
            Control::Until(e) => match self.top().flow.last().cloned() {
                Some(FlowEntry::Repeat { body }) => {
                    if is_true(self.eval(e)?) {
                        self.top().flow.pop();
                    } else {
                        self.top().seek(body);
                    }
                }
                _ => return Err(self.stray(c)),
            },
            Control::Goto(t) => self.goto(t)?,
        }
        Ok(())
    }

    fn goto(&mut self, t: &GotoTarget) -> Res {
        let top = self.top();
        if top.is_stream() {
            let key = goto_label(t);
            if top.seen_labels.contains(&key) {
                return Err(DecodeError::new(
                    21477,
                    format!("backward jump to {} in streaming program", goto_text(t)),
                ));
            }
            top.skip = Some(Skip::new(SkipUntil::Label(t.clone())));
            return Ok(());
        }
        let index = self.label_index()?;
        let Some((at, depth)) = index.find(t) else {
            return Err(DecodeError::new(
                20840,
                format!("label {} not found", goto_text(t)),
            ));
        };
        let top = self.top();
        top.seek(at);
        // The label's structural depth decides which open structures the jump leaves.
        top.flow.truncate(depth);
        while top.flow.len() < depth {
            top.flow.push(FlowEntry::If { taken: true });
        }
        Ok(())
    }

    /// The label index of the top file frame, built once per program text.
    fn label_index(&mut self) -> Res<Arc<LabelIndex>> {
        let top = self.top();
        if let Some(i) = &top.label_index {
            return Ok(i.clone());
        }
        let Source::File(p) = &top.source else {
            return Ok(Arc::new(LabelIndex::default()));
        };
        let index = Arc::new(build_label_index(&p.text)?);
        self.top().label_index = Some(index.clone());
        Ok(index)
    }

    fn declare(&mut self, d: &crate::lang::block::VarDecl) -> Res {
        let init = match &d.init {
            Some(e) => self.eval(e)?,
            None => 0.0,
        };
        let total: u64 = d.dims.iter().map(|&n| n as u64).product::<u64>().max(1);
        if d.dims.len() > 3 || total > 100_000 {
            return Err(DecodeError::new(
                own_codes::BAD_VALUE,
                format!("array V.{}.{} too large", scope_letter(d.scope), d.name),
            ));
        }
        let dims = d.dims.len() as u8;
        for flat in 0..total {
            let mut indices = [0i64; 3];
            let mut rest = flat;
            for k in (0..d.dims.len()).rev() {
                let n = d.dims[k] as u64;
                indices[k] = (rest % n) as i64;
                rest /= n;
            }
            self.set_var(
                VarSlot::V {
                    scope: d.scope,
                    name: d.name.as_str().into(),
                    indices,
                    dims,
                },
                init,
            )?;
        }
        Ok(())
    }

    fn set_var(&mut self, k: VarSlot, v: f64) -> Res {
        self.vars
            .set(k, v)
            .map_err(|_| DecodeError::new(own_codes::TOO_MANY_VARIABLES, "too many variables"))
    }

    fn info(&self, block: &Block, text: &str, meta: LineMeta, io: &DecoderIo<'_>) -> BlockInfo {
        let top = &self.frames[self.frames.len() - 1];
        BlockInfo {
            prog: top.prog.clone(),
            line: meta.line,
            offset: meta.offset,
            counter: self.counter,
            n: block.n,
            text: io.want_text.then(|| text.into()),
            stream: top.is_stream(),
        }
    }

    /// Queue a block that takes effect. During block search nothing is queued: the block
    /// was evaluated, its state collected.
    fn emit(&mut self, info: BlockInfo, action: Action, silent: bool, io: &mut DecoderIo<'_>) {
        if self.search.is_some() {
            return;
        }
        if !silent {
            self.stats.blocks += 1;
        }
        io.queue.push(QueuedBlock {
            info,
            action,
            silent,
        });
    }

    fn finish_search(
        &mut self,
        s: Search,
        block: &Block,
        text: &str,
        meta: LineMeta,
        io: &mut DecoderIo<'_>,
    ) {
        self.search = None;
        self.notes.push(Note::Search {
            target: s.target,
            found: true,
        });
        if s.from != self.modal.pos {
            let info = self.info(block, text, meta, io);
            let mv = Move {
                kind: MoveKind::Rapid,
                start: s.from,
                end: self.modal.pos,
                feed_mm_per_min: 0.0,
                path: Default::default(),
            };
            self.emit(info, Action::Move(mv), true, io);
        }
    }

    fn exec_items(
        &mut self,
        items: &[Item],
        block: &Block,
        text: &str,
        meta: LineMeta,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        let mut gs = BlockGs::default();
        let mut axes: [Option<f64>; MAX_AXES] = [None; MAX_AXES];
        let mut ijk: [Option<f64>; 3] = [None; 3];
        let mut radius: Option<f64> = None;
        let mut ms: [u32; 8] = [0; 8];
        let mut n_ms = 0usize;
        for it in items {
            match it {
                Item::Assign { target, value, col } => {
                    let key = self.resolve(target).map_err(|e| e.at(*col))?;
                    let v = self.eval(value).map_err(|e| e.at(*col))?;
                    self.set_var(key, v)?;
                }
                Item::GValue { g, value, col } => {
                    // G132..G134 with a weighting value: evaluated, accepted, no motion effect.
                    if let Value::Expr(e) = value {
                        self.eval(e).map_err(|e| e.at(*col))?;
                    }
                    if !apply_g(&mut self.modal, *g, &mut gs) {
                        return Err(
                            DecodeError::new(20131, format!("unknown G function G{g}")).at(*col)
                        );
                    }
                }
                Item::Word(w) => {
                    let v = match &w.value {
                        Value::Num(n) => *n,
                        Value::Expr(e) => self.eval(e).map_err(|e| e.at(w.col))?,
                    };
                    match w.letter {
                        b'G' => {
                            let g = whole(v).ok_or_else(|| {
                                DecodeError::new(20131, format!("G{v} is not a G function"))
                                    .at(w.col)
                            })?;
                            if !apply_g(&mut self.modal, g, &mut gs) {
                                return Err(DecodeError::new(
                                    20131,
                                    format!("unknown G function G{g}"),
                                )
                                .at(w.col));
                            }
                        }
                        b'M' => {
                            let m = whole(v).ok_or_else(|| {
                                DecodeError::new(20157, format!("M{v} is not an M function"))
                                    .at(w.col)
                            })?;
                            if n_ms == ms.len() {
                                return Err(DecodeError::new(
                                    20200,
                                    "too many M functions in one block",
                                )
                                .at(w.col));
                            }
                            ms[n_ms] = m;
                            n_ms += 1;
                            apply_m(&mut self.modal, m);
                        }
                        b'F' => {
                            if !(v >= 0.0 && v.is_finite()) {
                                return Err(DecodeError::new(
                                    own_codes::BAD_VALUE,
                                    format!("feed F{v} out of range"),
                                )
                                .at(w.col));
                            }
                            self.modal.feed_mm_per_min = v;
                        }
                        b'S' => self.modal.spindle_rpm = v,
                        b'T' => self.modal.tool = whole(v).unwrap_or(0),
                        b'D' => self.modal.tool_offset = whole(v).unwrap_or(0),
                        b'I' => ijk[0] = Some(v),
                        b'J' => ijk[1] = Some(v),
                        b'K' => ijk[2] = Some(v),
                        b'R' => radius = Some(v),
                        letter => {
                            if let Some(i) = AXIS_LETTERS.iter().position(|&a| a == letter) {
                                if !v.is_finite() {
                                    return Err(DecodeError::new(
                                        own_codes::BAD_VALUE,
                                        "axis value not finite",
                                    )
                                    .at(w.col));
                                }
                                if !(self.settings.axes[i] || gs.dwell && letter == b'X') {
                                    return Err(DecodeError::new(
                                        20200,
                                        format!(
                                            "axis {} is not configured in this channel",
                                            letter as char
                                        ),
                                    )
                                    .at(w.col));
                                }
                                axes[i] = Some(v);
                            }
                            // H and E: accepted, no effect in the emulator.
                        }
                    }
                }
            }
        }
        let ms = &ms[..n_ms];
        let info = self.info(block, text, meta, io);
        let mut queued_main = false;
        if gs.dwell {
            let seconds = axes[0].take().unwrap_or(0.0).max(0.0);
            self.emit(info.clone(), Action::Dwell { seconds }, false, io);
            queued_main = true;
        }
        if axes.iter().any(Option::is_some) {
            let start = self.modal.pos;
            let mut end = start;
            let offset = if gs.machine_coords || self.modal.zero_offset == 0 {
                [0.0; MAX_AXES]
            } else {
                self.settings.zero_offsets[self.modal.zero_offset - 1]
            };
            for i in 0..MAX_AXES {
                if let Some(v) = axes[i] {
                    end[i] = if self.modal.absolute {
                        v + offset[i]
                    } else {
                        start[i] + v
                    };
                }
            }
            let feed = self.modal.feed_mm_per_min;
            let mv = match self.modal.motion {
                MotionMode::Rapid => Move {
                    kind: MoveKind::Rapid,
                    start,
                    end,
                    feed_mm_per_min: 0.0,
                    path: Default::default(),
                },
                m => {
                    if feed <= 0.0 {
                        return Err(DecodeError::new(
                            own_codes::NO_FEED,
                            "no feed programmed (F) for G1/G2/G3",
                        ));
                    }
                    if m == MotionMode::Linear {
                        Move {
                            kind: MoveKind::Line,
                            start,
                            end,
                            feed_mm_per_min: feed,
                            path: Default::default(),
                        }
                    } else {
                        arc::arc_move(
                            &arc::ArcSpec {
                                plane: self.modal.plane,
                                ijk,
                                radius,
                                cw: m == MotionMode::ArcCw,
                            },
                            start,
                            end,
                            feed,
                            self.settings.arc_tolerance_mm,
                        )
                        .map_err(|e| {
                            DecodeError::new(
                                own_codes::ARC_INCONSISTENT,
                                format!("circle not consistent: {e:?}"),
                            )
                        })?
                    }
                }
            };
            let mut mv = mv;
            mv.path = self.modal.path_mode(gs.contour_this_block);
            self.modal.pos = end;
            self.emit(info.clone(), Action::Move(mv), queued_main, io);
            queued_main = true;
        }
        let end_m = ms.iter().copied().find(|m| matches!(m, 2 | 30 | 17 | 29));
        match end_m {
            Some(m @ (17 | 29)) => {
                if self.top().kind == FrameKind::Main {
                    return Err(DecodeError::new(
                        20376,
                        format!("unexpected M{m} in main program"),
                    ));
                }
                if !queued_main {
                    self.emit(info, Action::None, false, io);
                }
                self.check_open_flow()?;
                self.return_from_subroutine();
            }
            Some(m) => {
                if self.search.is_some() {
                    return Err(DecodeError::new(
                        21532,
                        format!(
                            "block search target {} not found",
                            self.search
                                .map(|s| s.target.to_string())
                                .unwrap_or_default()
                        ),
                    ));
                }
                if self.top().kind != FrameKind::Main {
                    self.notes.push(Note::Warning {
                        code: 20377,
                        msg: format!("M{m} in a subroutine: the program ends"),
                    });
                } else {
                    self.check_open_flow()?;
                }
                if !queued_main {
                    self.emit(info.clone(), Action::None, false, io);
                }
                self.emit(info, Action::End { m }, true, io);
                self.end_program();
            }
            None => {
                if !queued_main {
                    self.emit(info, Action::None, false, io);
                }
            }
        }
        Ok(())
    }

    fn check_open_flow(&mut self) -> Res {
        if !self.top().flow.is_empty() {
            return Err(DecodeError::new(
                20375,
                "open control blocks at program end",
            ));
        }
        Ok(())
    }

    /// M17/M29: back to the caller, past the call line.
    fn return_from_subroutine(&mut self) {
        if let Some(f) = self.frames.pop() {
            if f.is_stream() {
                self.discard_stream_rest();
                self.stream_active = false;
            }
            self.vars.pop_level();
        }
    }

    /// M30/M2: the program ends; in a stream the rest of the current segment goes.
    fn end_program(&mut self) {
        if self.stream_active {
            self.discard_stream_rest();
            self.stream_active = false;
        }
        self.frames.clear();
        self.state = DecoderState::Ended;
        self.starved = false;
    }

    fn discard_stream_rest(&mut self) {
        let bytes = self.stream.discard_rest();
        if bytes > 0 {
            self.notes.push(Note::Discard { bytes });
        }
    }

    fn end_of_file(&mut self, _io: &mut DecoderIo<'_>) -> Res {
        let searching = self.search.is_some();
        let top = self.top();
        if let Some(Skip {
            until: SkipUntil::Label(t),
            ..
        }) = &top.skip
        {
            return Err(DecodeError::new(
                20840,
                format!("label {} not found", goto_text(t)),
            ));
        }
        if searching {
            return Err(DecodeError::new(21532, "block search target not found"));
        }
        match top.kind {
            FrameKind::Main => Err(DecodeError::new(
                own_codes::MAIN_END_MISSING,
                "end of main program without M30/M02",
            )),
            _ => Err(DecodeError::new(
                own_codes::SUB_END_MISSING,
                "end of subroutine without M17/M29",
            )),
        }
    }

    fn exec_command(
        &mut self,
        c: &Command,
        block: &Block,
        text: &str,
        meta: LineMeta,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        let info = self.info(block, text, meta, io);
        match c {
            Command::Flush(kind) => {
                if self.modal.cross_block_active() {
                    return Err(DecodeError::new(21909, "#FLUSH while a cross-block function is active (TRC, contouring, spline, HSC)"));
                }
                self.emit(info, Action::Flush(*kind), false, io);
                if *kind == FlushKind::Wait && self.search.is_none() {
                    self.wait_idle = true;
                }
            }
            Command::CacheLoad { file } => {
                let loaded = io
                    .cache
                    .load(file, io.store)
                    .map_err(|e| DecodeError::new(e.code(), e.to_string()))?;
                self.notes.push(Note::Cache {
                    op: loaded.op(),
                    file: file.clone(),
                });
                self.emit(info, Action::None, false, io);
            }
            Command::CacheClear { file } => {
                io.cache
                    .clear(file)
                    .map_err(|e| DecodeError::new(e.code(), e.to_string()))?;
                self.notes.push(Note::Cache {
                    op: "clear",
                    file: file.clone(),
                });
                self.emit(info, Action::None, false, io);
            }
            Command::CacheClearAll => {
                io.cache
                    .clear_all()
                    .map_err(|e| DecodeError::new(e.code(), e.to_string()))?;
                self.notes.push(Note::Cache {
                    op: "clear_all",
                    file: String::new(),
                });
                self.emit(info, Action::None, false, io);
            }
            Command::CommentBegin => self.top().comment_block = true,
            // Outside a comment block `#COMMENT END` closes nothing; accepted silently.
            Command::CommentEnd => {}
            Command::Spline(s) => {
                match s {
                    SplineCommand::On => self.modal.spline = true,
                    SplineCommand::Off => self.modal.spline = false,
                    t => self.modal.spline_type = *t,
                }
                self.emit(info, Action::None, false, io);
            }
            Command::Hsc { on, .. } => {
                self.modal.hsc = *on;
                self.emit(info, Action::None, false, io);
            }
            Command::ContourMode { options } => {
                if let Some(dev) = crate::motion::contour::path_dev_mm(options) {
                    self.modal.contour_dev_mm = dev;
                }
                self.emit(info, Action::None, false, io)
            }
            Command::Var => self.top().var_block = true,
            Command::EndVar => {}
        }
        Ok(())
    }

    fn exec_call(
        &mut self,
        c: &Call,
        block: &Block,
        text: &str,
        meta: LineMeta,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        if self.frames.len() > self.settings.max_depth {
            return Err(DecodeError::new(
                own_codes::NESTING_TOO_DEEP,
                format!("subroutine nesting deeper than {}", self.settings.max_depth),
            ));
        }
        let info = self.info(block, text, meta, io);
        match c {
            Call::Global { file } => {
                let frame = self.open_subroutine(file, FrameKind::Global, io)?;
                self.emit(info, Action::None, false, io);
                self.vars.push_level(Vec::new());
                self.frames.push(frame);
            }
            Call::Cycle { name, params } => {
                let mut values = Vec::with_capacity(params.len());
                for (n, e) in params {
                    values.push((*n, self.eval(e)?));
                }
                let frame = self.open_subroutine(name, FrameKind::Cycle, io)?;
                self.emit(info, Action::None, false, io);
                self.vars.push_level(values);
                self.frames.push(frame);
            }
            Call::Local { name } => {
                let index = self.label_index()?;
                let Some(at) = index.local_subs.get(&name.to_ascii_uppercase()).copied() else {
                    return Err(DecodeError::new(
                        20373,
                        format!("local subroutine {name} not found"),
                    ));
                };
                let top = self.top();
                let Source::File(p) = &top.source else {
                    return Err(DecodeError::new(
                        21479,
                        "local subroutine call (LL) in streaming program",
                    ));
                };
                let mut frame =
                    Frame::new(FrameKind::Local, Source::File(p.clone()), top.prog.clone());
                frame.label_index = Some(index);
                frame.seek(at);
                self.emit(info, Action::None, false, io);
                self.vars.push_level(Vec::new());
                self.frames.push(frame);
            }
        }
        Ok(())
    }

    /// A global subroutine or cycle: the cache first, then the file system, then the stream.
    fn open_subroutine(
        &mut self,
        name: &str,
        kind: FrameKind,
        io: &mut DecoderIo<'_>,
    ) -> Res<Frame> {
        if let Some(p) = io.cache.get(name) {
            if io.want_text {
                // Only with events on: the hot call path stays free of the allocation.
                self.notes.push(Note::Cache {
                    op: "hit",
                    file: name.to_string(),
                });
            }
            let prog = p.name.clone();
            return Ok(Frame::new(kind, Source::File(p), prog));
        }
        match io
            .store
            .open(name, ProgramKind::Subroutine)
            .map_err(|e| DecodeError::new(e.code(), e.to_string()))?
        {
            Opened::File(p) => {
                let prog: Arc<str> = p.name.clone();
                Ok(Frame::new(kind, Source::File(p), prog))
            }
            Opened::Stream { name } => {
                if self.stream_active {
                    return Err(DecodeError::new(
                        own_codes::STREAM_ALREADY_ACTIVE,
                        "the streaming program is already running",
                    ));
                }
                self.begin_stream();
                self.notes.push(Note::ProgramStart {
                    prog: name.clone(),
                    stream: true,
                });
                Ok(Frame::new(kind, Source::Stream, name))
            }
        }
    }

    fn eval(&self, e: &crate::lang::block::Expr) -> Res<f64> {
        expr::eval(e, &self.vars)
    }

    fn resolve(&self, v: &crate::lang::block::VarRef) -> Res<VarSlot> {
        expr::resolve(v, &self.vars)
    }
}

/// Scan a whole file once for labels (position and structural depth) and `%L` sections.
fn build_label_index(text: &[u8]) -> Res<LabelIndex> {
    let mut index = LabelIndex::default();
    let mut pos = 0usize;
    let mut line_no = 0u32;
    let mut depth = 0usize;
    let mut comment = false;
    let mut line = String::new();
    loop {
        let at = LinePos { pos, line_no };
        let Some(next) = frame::cut_line(text, pos, &mut line, true) else {
            break;
        };
        pos = next;
        line_no += 1;
        if comment {
            if is_comment_end(&line) {
                comment = false;
            }
            continue;
        }
        let Ok(block) = parse_block(&line) else {
            continue;
        };
        if let Some(l) = &block.label {
            if index.labels.insert(l.clone(), (at, depth)).is_some() {
                return Err(DecodeError::new(
                    20836,
                    format!("label {} defined twice (line {})", label_text(l), line_no),
                ));
            }
        }
        match &block.body {
            Body::Command(Command::CommentBegin) => comment = true,
            Body::ProgramHead { name, local: true } => {
                index
                    .local_subs
                    .insert(name.to_ascii_uppercase(), LinePos { pos, line_no });
            }
            Body::Control(c) => match nesting(c) {
                Nesting::Open => depth += 1,
                Nesting::Close => depth = depth.saturating_sub(1),
                Nesting::Neither => {}
            },
            _ => {}
        }
    }
    Ok(index)
}

fn for_continues(v: f64, end: f64, step: f64) -> bool {
    if step > 0.0 {
        v <= end + 1e-9
    } else {
        v >= end - 1e-9
    }
}

/// A whole number written as a float (`G01` parses as 1.0).
fn whole(v: f64) -> Option<u32> {
    let r = v.round();
    ((v - r).abs() < 1e-9 && (0.0..=u32::MAX as f64).contains(&r)).then_some(r as u32)
}

fn items_have_m(items: &[Item], codes: &[u32]) -> bool {
    items.iter().any(|i| match i {
        Item::Word(w) if w.letter == b'M' => match w.value {
            Value::Num(v) => whole(v).is_some_and(|m| codes.contains(&m)),
            Value::Expr(_) => false,
        },
        _ => false,
    })
}

fn block_ends_program(b: &Block) -> bool {
    matches!(&b.body, Body::Items(items) if items_have_m(items, &[2, 30]))
}

fn goto_label(t: &GotoTarget) -> Label {
    match t {
        GotoTarget::Number(n) => Label::Number(*n),
        GotoTarget::Name(s) => Label::Name(s.clone()),
    }
}

fn label_matches(l: &Label, t: &GotoTarget) -> bool {
    *l == goto_label(t)
}

fn label_text(l: &Label) -> String {
    match l {
        Label::Number(n) => format!("N{n}"),
        Label::Name(s) => format!("[{s}]"),
    }
}

fn goto_text(t: &GotoTarget) -> String {
    label_text(&goto_label(t))
}

fn scope_letter(s: crate::lang::block::VScope) -> char {
    use crate::lang::block::VScope;
    match s {
        VScope::Program => 'P',
        VScope::Local => 'L',
        VScope::SelfRetaining => 'S',
        VScope::External => 'E',
    }
}

fn control_name(c: &Control) -> &'static str {
    match c {
        Control::If(_) => "$IF",
        Control::IfGoto(..) => "$IF … $GOTO",
        Control::ElseIf(_) => "$ELSEIF",
        Control::Else => "$ELSE",
        Control::EndIf => "$ENDIF",
        Control::Switch(_) => "$SWITCH",
        Control::Case(_) => "$CASE",
        Control::Default => "$DEFAULT",
        Control::Break => "$BREAK",
        Control::EndSwitch => "$ENDSWITCH",
        Control::For { .. } => "$FOR",
        Control::EndFor => "$ENDFOR",
        Control::While(_) => "$WHILE",
        Control::EndWhile => "$ENDWHILE",
        Control::Do => "$DO",
        Control::EndDo(_) => "$ENDDO",
        Control::Repeat => "$REPEAT",
        Control::Until(_) => "$UNTIL",
        Control::Continue => "$CONTINUE",
        Control::Goto(_) => "$GOTO",
    }
}
