//! The decoder: reads NC lines from the top frame (file text, cache entry or stream segment),
//! interprets control flow, parameters and modal state, and queues blocks for motion.
//!
//! It decodes only while the block queue has room and only up to its per-tick budget, and it
//! pulls a new stream segment only when it has decoded the previous one: that is the whole of
//! the channel's back-pressure.

mod axis_vars;
mod calls;
mod cycles;
mod error;
mod expr;
pub mod flow;
pub mod frame;
mod io;
mod labels;
mod line;
pub mod modal;
mod note;
mod search;
mod settings;
pub mod vars;
mod words;

use std::sync::Arc;
use std::time::Duration;

use crate::lang::block::{AxisName, Block, Body, Call};
use crate::lang::codes;
use crate::lang::{continuation, is_comment_end, parse_block, parse_var_line, Joiner, VarLine};
use crate::queue::{Action, BlockInfo, QueuedBlock};
use crate::source::store::{Opened, ProgramKind, ProgramStore};
use crate::vocab::axis::{Position, MAX_AXES};

use crate::lang::control::{goto_text, is_loop_statement};
use frame::{read_file_line, Frame, FrameKind, Skip, SkipUntil, Source, StreamNote, StreamReader};
use line::{LineMeta, LineRead, LineTooLong};
use modal::Modal;
use vars::{VarSlot, VarStore};

use labels::{LabelScan, ScanFound, ScanGoal, ScanStep, ScanWork};
pub use labels::{LABEL_SCAN_BYTES_PER_TICK, LABEL_SCAN_LINES_PER_TICK, MAX_INDEXED_LABELS};
use search::Search;
pub use search::SearchTarget;

pub use error::DecodeError;
use error::{var_error, Res};
pub use io::DecoderIo;
pub(crate) use note::Note;
pub(crate) use settings::letter_names;
pub use settings::{DecoderSettings, DECLARED_VALUES_PER_TICK, LINE_BYTES_PER_TICK};

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

/// Counters for the report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DecoderStats {
    /// Lines decoded (all of them: skipped, comments, loop passes).
    pub lines: u64,
    /// Blocks queued (those that take effect).
    pub blocks: u64,
    /// Label scans run (an index built for `$GOTO`/`LL`, or one label searched).
    pub label_scans: u64,
    /// Most lines a label scan read in one tick (at most [`LABEL_SCAN_LINES_PER_TICK`]).
    pub max_scan_lines_per_tick: usize,
    /// Most bytes of NC text decoded in one tick (at most [`LINE_BYTES_PER_TICK`] plus one
    /// line).
    pub max_line_bytes_per_tick: usize,
    /// Most bytes a label scan read in one tick (at most [`LABEL_SCAN_BYTES_PER_TICK`]
    /// plus one line).
    pub max_scan_bytes_per_tick: usize,
}

pub struct Decoder {
    settings: DecoderSettings,
    /// Bit i: the configured axis in slot i has a name longer than its letter (`X1`), so the
    /// letter alone names no axis. Read for every axis word; built once from the settings.
    renamed_slots: u8,
    frames: Vec<Frame>,
    stream: StreamReader,
    /// A stream frame is on the frame stack.
    stream_active: bool,
    vars: VarStore,
    modal: Modal,
    /// The tool list's radii by D number, mm (`V.G.WZ[j].R`).
    tool_radii: Vec<(u32, f64)>,
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
    /// Values made by `#VAR` declarations in this tick ([`DECLARED_VALUES_PER_TICK`]).
    declared_this_tick: usize,
    /// A label scan of the top frame's text under way (module `labels`): the line that
    /// needs it waits, rewound, and runs again when the scan is done.
    scan: Option<LabelScan>,
    /// What a finished targeted scan found, for the line that asked for it.
    scan_found: Option<(ScanGoal, ScanFound)>,
    /// What label scans read in this tick.
    scanned_this_tick: ScanWork,
    /// Bytes of NC text decoded in this tick ([`LINE_BYTES_PER_TICK`]).
    line_bytes_this_tick: usize,
    /// A `#CACHE LOAD` waiting for the loader.
    cache_read: Option<calls::CacheRead>,
    /// The line being run has to wait (for a label scan, a `#CACHE LOAD` read): it is read
    /// again later.
    wait_line: bool,
    line: String,
    /// A block written over several lines (`\` at the end of a line) being collected, and
    /// where its first line stands.
    joiner: Joiner,
    join_meta: LineMeta,
    notes: Vec<Note>,
    stats: DecoderStats,
    /// The word collection of the block being executed, kept between blocks.
    words: Option<Box<words::Words>>,
    /// The implicit subroutine calls' state in the running program.
    implicit: calls::ImplicitState,
}

/// Whether the decoder may read its next line in this tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ready {
    Go,
    /// Something has just arrived: check everything again.
    Again,
    /// Not in this tick.
    Stop,
}

impl Decoder {
    pub fn new(settings: DecoderSettings) -> Self {
        let renamed_slots = (0..MAX_AXES)
            .filter(|&i| settings.axes[i] && !settings.axis_names[i].is_letter())
            .fold(0u8, |m, i| m | 1 << i);
        Decoder {
            settings,
            renamed_slots,
            frames: Vec::new(),
            stream: StreamReader::default(),
            stream_active: false,
            vars: VarStore::new(),
            modal: Modal::defaults([0.0; MAX_AXES]),
            tool_radii: Vec::new(),
            counter: 0,
            state: DecoderState::Idle,
            search: None,
            skip_mask: 0,
            wait_idle: false,
            starved: false,
            ready_at: Duration::ZERO,
            declared_this_tick: 0,
            scan: None,
            scan_found: None,
            scanned_this_tick: ScanWork::default(),
            line_bytes_this_tick: 0,
            cache_read: None,
            wait_line: false,
            line: String::new(),
            joiner: Joiner::default(),
            join_meta: LineMeta { line: 0, offset: 0 },
            notes: Vec::new(),
            stats: DecoderStats::default(),
            words: None,
            implicit: calls::ImplicitState::default(),
        }
    }

    pub fn state(&self) -> DecoderState {
        self.state
    }
    /// The running program reads the stream interface (a stream frame is on the stack).
    pub fn reads_stream(&self) -> bool {
        self.stream_active
    }
    /// Axes the channel has, by `AXIS_LETTERS` index.
    pub fn axes(&self) -> [bool; MAX_AXES] {
        self.settings.axes
    }
    /// The name of the axis in each slot (`X`, `X1`, …), by `AXIS_LETTERS` index.
    pub(crate) fn axis_names(&self) -> &[AxisName; MAX_AXES] {
        &self.settings.axis_names
    }
    pub fn modal(&self) -> &Modal {
        &self.modal
    }
    pub fn vars(&self) -> &VarStore {
        &self.vars
    }
    pub(crate) fn vars_mut(&mut self) -> &mut VarStore {
        &mut self.vars
    }
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }
    pub fn counter(&self) -> u64 {
        self.counter
    }
    /// Waiting for stream data that has not arrived.
    pub(crate) fn starved(&self) -> bool {
        self.starved && self.state == DecoderState::Running
    }
    pub(crate) fn searching(&self) -> bool {
        self.search.is_some()
    }
    pub(crate) fn set_skip_mask(&mut self, mask: u16) {
        self.skip_mask = mask;
    }
    /// The text of the file program `prog` while a frame of it is open (the live view's
    /// listing); `None` for the stream and for a program no frame runs.
    pub(crate) fn program_text(&self, prog: &str) -> Option<Arc<Vec<u8>>> {
        self.frames.iter().rev().find_map(|f| match &f.source {
            frame::Source::File(t) if &*f.prog == prog => Some(Arc::clone(&t.text)),
            _ => None,
        })
    }
    pub fn depth(&self) -> usize {
        self.frames.len()
    }
    /// The message reported for error `code`: the kernel's text for it (error text file,
    /// P-STUP-00168) followed by ncchannel's `detail` in parentheses, or `detail` alone.
    pub(crate) fn reported_message(&self, code: u32, detail: String) -> String {
        match self
            .settings
            .error_texts
            .as_deref()
            .and_then(|t| t.get(code))
        {
            Some(text) => format!("{text} ({detail})"),
            None => detail,
        }
    }

    /// Notes since the last call, oldest first.
    pub(crate) fn take_notes(&mut self, into: &mut Vec<Note>) {
        // A swap: both vectors keep their allocations from tick to tick.
        into.clear();
        std::mem::swap(&mut self.notes, into);
    }

    /// Start a main program (automatic mode). Channel defaults are restored here — for a
    /// stream once, at stream start, as ISG FCT-C19 Data streaming §2.4 describes.
    pub fn start(
        &mut self,
        name: &str,
        store: &mut ProgramStore,
        machine_pos: Position,
        search: Option<SearchTarget>,
    ) -> Res {
        self.frames.clear();
        self.joiner = Joiner::default();
        self.modal = Modal::defaults(machine_pos);
        self.vars.start_program();
        self.counter = 0;
        self.wait_idle = false;
        self.starved = false;
        self.ready_at = Duration::ZERO;
        self.forget_scan();
        // A read charged to an earlier program is not this one's to wait for.
        store.take_owed();
        self.stream_active = false;
        self.implicit = calls::ImplicitState::at_start(&self.settings.implicit);
        self.search = search.map(|target| Search {
            target,
            from: machine_pos,
        });
        let opened = store.open(name, ProgramKind::Main)?;
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
            Opened::Loading(p) => {
                let prog = p.name.clone();
                self.frames.push(Frame::new(
                    FrameKind::Main,
                    Source::Loading(p),
                    prog.clone(),
                ));
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
        self.joiner = Joiner::default();
        self.stream.restart();
        self.stream_active = false;
        self.vars.reset();
        self.modal = Modal::defaults(machine_pos);
        self.counter = 0;
        self.state = DecoderState::Idle;
        self.search = None;
        self.implicit = calls::ImplicitState::default();
        self.wait_idle = false;
        self.starved = false;
        self.ready_at = Duration::ZERO;
        self.forget_scan();
    }

    /// No label scan under way or waited for.
    fn forget_scan(&mut self) {
        self.scan = None;
        self.scan_found = None;
        self.cache_read = None;
        self.wait_line = false;
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
        self.decode(io);
        self.stats.max_scan_lines_per_tick = self
            .stats
            .max_scan_lines_per_tick
            .max(self.scanned_this_tick.lines);
        self.stats.max_scan_bytes_per_tick = self
            .stats
            .max_scan_bytes_per_tick
            .max(self.scanned_this_tick.bytes);
        self.stats.max_line_bytes_per_tick = self
            .stats
            .max_line_bytes_per_tick
            .max(self.line_bytes_this_tick);
        io.store.end_tick();
    }

    /// Everything a line waits for: the tick's byte and `#VAR` budgets, simulated
    /// file-system latency, a label scan, the loader, `#FLUSH WAIT`, room in the queue, the
    /// start subroutine, a frame's file.
    fn ready_to_read(&mut self, io: &mut DecoderIo<'_>, tick_end: Duration) -> Ready {
        if self.declared_this_tick >= DECLARED_VALUES_PER_TICK
            || self.line_bytes_this_tick >= LINE_BYTES_PER_TICK
        {
            return Ready::Stop;
        }
        let owed = io.store.take_owed();
        if !owed.is_zero() {
            self.ready_at = self.ready_at.max(io.now) + owed;
        }
        if self.ready_at >= tick_end {
            return Ready::Stop;
        }
        if self.scan.is_some() && !self.advance_scan() {
            return Ready::Stop;
        }
        match self.cache_read_arrived(io.store) {
            Some(false) => return Ready::Stop,
            // The read's simulated latency is waited for first (top of the loop).
            Some(true) => return Ready::Again,
            None => {}
        }
        if self.wait_idle {
            if io.queue.is_empty() && io.motion_idle {
                self.wait_idle = false;
            } else {
                return Ready::Stop;
            }
        }
        if !io.queue.has_room() {
            return Ready::Stop;
        }
        if self.implicit.start_pending {
            if let Err(e) = self.start_subroutine(io) {
                self.fail(e, LineMeta { line: 0, offset: 0 });
                return Ready::Stop;
            }
        }
        self.frame_file_arrived(io.store)
    }

    /// A top frame whose file the loader reads: `Again` when the text has just arrived (its
    /// simulated latency is waited for first), `Stop` while it has not or could not be read.
    fn frame_file_arrived(&mut self, store: &mut ProgramStore) -> Ready {
        let Some(top) = self.frames.last_mut() else {
            return Ready::Go;
        };
        let Source::Loading(p) = &top.source else {
            return Ready::Go;
        };
        match store.finish_read(p) {
            None => Ready::Stop,
            Some(Ok(text)) => {
                top.source = Source::File(text);
                Ready::Again
            }
            Some(Err(e)) => {
                self.fail(e.into(), LineMeta { line: 0, offset: 0 });
                Ready::Stop
            }
        }
    }

    /// The decoding loop of [`Decoder::step`].
    fn decode(&mut self, io: &mut DecoderIo<'_>) {
        let mut budget = self.settings.blocks_per_tick;
        let tick_end = io.now + io.period;
        self.declared_this_tick = 0;
        self.scanned_this_tick = ScanWork::default();
        self.line_bytes_this_tick = 0;
        while budget > 0 && self.state == DecoderState::Running {
            match self.ready_to_read(io, tick_end) {
                Ready::Stop => break,
                Ready::Again => continue,
                Ready::Go => {}
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
            if let LineRead::Line(_) = read {
                // The line and its end (CR LF at most).
                self.line_bytes_this_tick += line.len() + 2;
            }
            match read {
                LineRead::Pending => {
                    self.starved = true;
                    self.line = line;
                    break;
                }
                LineRead::Eof if self.joiner.is_open() => {
                    // The file ends in a continued line: the block is what there is.
                    self.line = line;
                    budget -= 1;
                    self.run_joined(io);
                }
                LineRead::TooLong(meta) => {
                    self.line = line;
                    self.fail(LineTooLong.error(meta.line), meta);
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
                    self.stats.lines += 1;
                    if self.joiner.is_open()
                        || (continuation(&line).is_some() && !self.top().comment_block)
                    {
                        if !self.joiner.is_open() {
                            self.join_meta = meta;
                        }
                        if self.joiner.push(&line) {
                            self.run_joined(io);
                        }
                        self.line = line;
                        continue;
                    }
                    self.counter += 1;
                    let r = self.process_line(&line, meta, io);
                    self.line = line;
                    if let Err(e) = r {
                        self.fail(e, meta);
                    }
                    self.rewind_if_waiting(meta);
                }
            }
        }
    }

    /// Run the block collected from several lines; an error's column names the line it
    /// was written in.
    fn run_joined(&mut self, io: &mut DecoderIo<'_>) {
        let joiner = std::mem::take(&mut self.joiner);
        let meta = self.join_meta;
        self.counter += 1;
        let r = self.process_line(joiner.text(), meta, io);
        if let Err(mut e) = r {
            let mut at = meta;
            if let Some(col) = e.col {
                let (line, col) = joiner.position(col);
                at.line = at.line.saturating_add(line);
                e.col = Some(col);
            }
            self.fail(e, at);
        }
        self.joiner = joiner;
        self.joiner.close();
        self.rewind_if_waiting(meta);
    }

    /// A line that has to wait (for a label scan) did nothing: it is read again, and its
    /// block counter given back.
    fn rewind_if_waiting(&mut self, meta: LineMeta) {
        if !std::mem::take(&mut self.wait_line) {
            return;
        }
        self.counter -= 1;
        let at = line::LinePos {
            pos: usize::try_from(meta.offset).unwrap_or(usize::MAX),
            line_no: meta.line.saturating_sub(1),
        };
        self.top().seek(at);
    }

    /// A `#CACHE LOAD` waiting for the loader: `Some(true)` when its text has just arrived,
    /// `Some(false)` while it has not, `None` when no load waits.
    fn cache_read_arrived(&mut self, store: &mut ProgramStore) -> Option<bool> {
        let r = self.cache_read.as_mut().filter(|r| r.read.is_none())?;
        let read = store.finish_read(&r.pending);
        let arrived = read.is_some();
        r.read = read;
        Some(arrived)
    }

    /// Go on with the label scan under way, within what is left of this tick's scan budget.
    /// `true` when it is done (its result installed) and decoding may go on.
    fn advance_scan(&mut self) -> bool {
        let Some(scan) = self.scan.as_mut() else {
            return true;
        };
        let step = scan.advance(&mut self.scanned_this_tick);
        let warnings = scan.take_warnings();
        let goal = scan.goal().clone();
        for w in warnings {
            self.notes.push(Note::Warning {
                code: w.code,
                msg: w.msg,
            });
        }
        match step {
            Ok(ScanStep::Pending) => false,
            Ok(ScanStep::Done(found)) => {
                self.scan = None;
                match found {
                    ScanFound::Index(index) => self.top().label_index = Some(Arc::new(index)),
                    other => self.scan_found = Some((goal, other)),
                }
                true
            }
            Err(e) => {
                self.scan = None;
                let top = self.top();
                let meta = LineMeta {
                    line: top.line_no + 1,
                    offset: top.pos as u64,
                };
                self.fail(e, meta);
                false
            }
        }
    }

    fn fail(&mut self, e: DecodeError, meta: LineMeta) {
        let prog = self
            .frames
            .last()
            .map(|f| f.prog.clone())
            .unwrap_or_else(|| Arc::from(""));
        let msg = match self
            .settings
            .error_texts
            .as_deref()
            .and_then(|t| t.get(e.code))
        {
            Some(text) => format!("{text} ({})", e.msg),
            None => e.msg,
        };
        self.notes.push(Note::Error {
            code: e.code,
            msg,
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
        if top.var_block {
            // The lines of a `#VAR` block are declarations, read exactly as `check` reads
            // them (`V.P.TABLE[10]` is no ordinary block).
            match parse_var_line(text)? {
                VarLine::Blank => {}
                VarLine::End => top.var_block = false,
                // The comment block ends inside the `#VAR` block: both flags hold.
                VarLine::CommentBegin => top.comment_block = true,
                VarLine::Decl(d) => self.declare(&d)?,
            }
            return Ok(());
        }
        let skipping = top.skip.is_some();
        let block = match parse_block(text) {
            Ok(b) => b,
            // A syntax error in a skipped line never runs, so it is no error.
            Err(_) if skipping => return Ok(()),
            Err(e) => return Err(e.into()),
        };
        if self.top().is_stream() {
            stream_allows(&block)?;
        }
        if skipping {
            let run_it = self.skip_line(&block)?;
            if !run_it {
                return Ok(());
            }
        } else if let Some(l) = &block.label {
            self.note_label(l)?;
        }
        if self.search.is_some() {
            self.search_block(&block, text, meta, io);
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
            Body::ProgramHead { .. } if self.top().kind == FrameKind::Local => {
                // A local subroutine without M17/M29 ends where the next program begins.
                self.check_open_flow()?;
                self.return_from_subroutine();
                self.resume_held_end(io)
            }
            Body::ProgramHead { local: true, .. } => {
                // A local subroutine section met while running: it runs only when called.
                let top = self.top();
                top.skip = Some(Skip::new(SkipUntil::LocalSubroutine));
                Ok(())
            }
            Body::ProgramHead { local: false, .. } => Ok(()),
        }
    }

    fn set_var(&mut self, k: VarSlot, v: f64) -> Res {
        self.vars.set(k, v).map_err(var_error)
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
                codes::LABEL_NOT_FOUND,
                format!("label {} not found", goto_text(t)),
            ));
        }
        if searching {
            return Err(DecodeError::new(
                codes::SEARCH_NOT_FOUND,
                "block search target not found",
            ));
        }
        match top.kind {
            FrameKind::Main => Err(DecodeError::new(
                codes::MAIN_END_MISSING,
                "end of main program without M30/M02",
            )),
            _ => Err(DecodeError::new(
                codes::SUB_END_MISSING,
                "end of subroutine without M17/M29",
            )),
        }
    }

    fn eval(&self, e: &crate::lang::block::Expr) -> Res<f64> {
        expr::eval(e, &expr::Env(self))
    }

    fn resolve(&self, v: &crate::lang::block::VarRef) -> Res<VarSlot> {
        expr::resolve(v, &expr::Env(self))
    }
}

/// What a streaming program may not hold: loops (21478) and local subroutine calls (21479).
fn stream_allows(block: &Block) -> Res {
    match &block.body {
        Body::Control(c) if is_loop_statement(c) => Err(DecodeError::new(
            codes::STREAM_LOOP,
            "loop statement in streaming program; streaming aborted",
        )),
        Body::Call(Call::Local { .. } | Call::Cycle { local: true, .. }) => Err(DecodeError::new(
            codes::STREAM_LOCAL_CALL,
            "local subroutine call (LL) in streaming program",
        )),
        _ => Ok(()),
    }
}
