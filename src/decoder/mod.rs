//! The decoder: reads NC lines from the top frame (file text, cache entry or stream segment),
//! interprets control flow, parameters and modal state, and queues blocks for motion.
//!
//! It decodes only while the block queue has room and only up to its per-tick budget, and it
//! pulls a new stream segment only when it has decoded the previous one: that is the whole of
//! the channel's back-pressure.

mod error;
pub mod flow;
pub mod frame;
mod interp;
mod io;
mod labels;
mod line;
pub mod modal;
mod note;
mod reader;
mod search_target;
mod settings;
pub mod vars;

use std::sync::Arc;
use std::time::Duration;

use crate::lang::block::{AxisName, Block, Body, Call, Item};
use crate::lang::codes;
use crate::lang::{continuation, is_comment_end, parse_block_reusing, parse_var_line, VarLine};
use crate::source::loader::Loader;
use crate::source::store::{Opened, ProgramKind, ProgramStore};
use crate::vocab::axis::{Position, MAX_AXES};

use crate::lang::control::{goto_text, is_loop_statement};
use flow::{FlowStep, SkipUntil};
use frame::{Frame, FrameKind, Source};
use interp::Interpreter;
use line::{BlockAt, LineMeta, LineRead, LineTooLong};
use modal::Modal;
use reader::{FileArrival, Reader};
use vars::VarStore;

pub use labels::{LABEL_SCAN_BYTES_PER_TICK, LABEL_SCAN_LINES_PER_TICK, MAX_INDEXED_LABELS};
pub use search_target::SearchTarget;

/// The tool list's data sets the decoder selects with D (the channel hands them over).
pub use crate::params::tools::ToolTable;
pub use error::DecodeError;
use error::Res;
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
    /// The frame stack, the line joiner and what a line waits for.
    reader: Reader,
    /// Modal state, variables, calls: what a block does.
    interp: Interpreter,
    state: DecoderState,
    /// What happened besides queued blocks, since the channel last took them.
    notes: Vec<Note>,
    /// Counters for the report (blocks and label scans are counted by the parts).
    stats: DecoderStats,
    /// The last block's item list, emptied, for the next line's parse: one allocation kept
    /// from line to line rather than one taken and freed a block ([`Self::item_list`]).
    spare_items: Vec<Item>,
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
    /// A decoder whose reader and variables free what could cost a tick through `loader`.
    pub fn new(settings: DecoderSettings, loader: Loader) -> Self {
        Decoder {
            reader: Reader::new(loader.clone()),
            interp: Interpreter::new(settings, loader),
            state: DecoderState::Idle,
            notes: Vec::new(),
            stats: DecoderStats::default(),
            spare_items: Vec::new(),
        }
    }

    pub fn state(&self) -> DecoderState {
        self.state
    }
    /// The running program reads the stream interface (a stream frame is on the stack).
    pub fn reads_stream(&self) -> bool {
        self.reader.stream_active()
    }
    /// Axes the channel has, by `AXIS_LETTERS` index.
    pub fn axes(&self) -> [bool; MAX_AXES] {
        self.interp.settings().axes
    }
    /// The name of the axis in each slot (`X`, `X1`, …), by `AXIS_LETTERS` index.
    pub(crate) fn axis_names(&self) -> &[AxisName; MAX_AXES] {
        &self.interp.settings().axis_names
    }
    pub fn modal(&self) -> &Modal {
        self.interp.modal()
    }
    /// Zero-offset groups G54 … G59 by axis, mm: the list's, as programs have written them
    /// (`V.G.NP[i]`), as far as the decoder has run.
    pub(crate) fn zero_offsets(&self) -> &modal::ZeroOffsets {
        self.interp.zero_offsets()
    }
    pub fn vars(&self) -> &VarStore {
        self.interp.vars()
    }
    pub(crate) fn vars_mut(&mut self) -> &mut VarStore {
        self.interp.vars_mut()
    }
    pub fn stats(&self) -> DecoderStats {
        DecoderStats {
            blocks: self.interp.blocks(),
            label_scans: self.reader.label_scans(),
            ..self.stats
        }
    }
    pub fn counter(&self) -> u64 {
        self.interp.counter()
    }
    /// Waiting for stream data that has not arrived.
    pub(crate) fn starved(&self) -> bool {
        self.reader.starved() && self.state == DecoderState::Running
    }
    pub(crate) fn searching(&self) -> bool {
        self.interp.searching()
    }
    pub(crate) fn set_skip_mask(&mut self, mask: u16) {
        self.interp.set_skip_mask(mask);
    }
    /// The tool list's data sets by D number, mm (`V.G.WZ[j].*`, `V.G.WZ_AKT.*`, length
    /// compensation), and whether a T word selects the D data set of its number
    /// (`einrechnen_mit_t`, P-CHAN-00014).
    pub(crate) fn set_tools(&mut self, tools: ToolTable, t_selects_d: bool) {
        self.interp.set_tools(tools, t_selects_d);
    }
    /// The active D and its tool radius, mm (D0 or a D the tool list lacks: radius 0).
    pub(crate) fn active_tool(&self) -> (u32, f64) {
        self.interp.active_tool()
    }
    /// The text of the file program `prog` while a frame of it is open (the live view's
    /// listing); `None` for the stream and for a program no frame runs.
    pub(crate) fn program_text(&self, prog: &str) -> Option<Arc<Vec<u8>>> {
        self.reader.program_text(prog)
    }
    /// The message reported for error `code`: the kernel's text for it (error text file,
    /// P-STUP-00168) followed by ncchannel's `detail` in parentheses, or `detail` alone.
    pub(crate) fn reported_message(&self, code: u32, detail: String) -> String {
        match self
            .interp
            .settings()
            .error_texts
            .as_deref()
            .and_then(|t| t.get(code))
        {
            Some(text) => format!("{text} ({detail})"),
            None => detail,
        }
    }

    /// Whether the decoder has notes for the channel: most ticks it has none.
    pub(crate) fn has_notes(&self) -> bool {
        !self.notes.is_empty()
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
        self.reader.start();
        self.interp.start(machine_pos, search);
        // A read charged to an earlier program is not this one's to wait for.
        store.take_owed();
        let opened = store.open(name, ProgramKind::Main)?;
        match opened {
            Opened::File(p) => {
                let prog = p.name.clone();
                self.reader
                    .push(Frame::new(FrameKind::Main, Source::File(p), prog.clone()));
                self.notes.push(Note::ProgramStart {
                    prog,
                    stream: false,
                });
            }
            Opened::Loading(p) => {
                let prog = p.name.clone();
                self.reader.push(Frame::new(
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
                self.reader.begin_stream();
                self.reader
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
        self.reader.reset();
        self.interp.reset(machine_pos);
        self.state = DecoderState::Idle;
    }

    /// Decode up to the per-tick budget.
    ///
    /// Simulated file-system latency never blocks the tick: a file read (main program, call,
    /// `#CACHE LOAD`) moves `ready_at` on by its cost, counted from when the decoder was free,
    /// and decoding goes on in this tick only while `ready_at` lies inside it. So reads of
    /// 200 µs in 1 ms ticks give five per tick, and a 5 ms read pauses decoding for five ticks.
    pub fn step(&mut self, io: &mut DecoderIo<'_>) {
        self.decode(io);
        let (scanned, line_bytes) = self.reader.tick_work();
        self.stats.max_scan_lines_per_tick = self.stats.max_scan_lines_per_tick.max(scanned.lines);
        self.stats.max_scan_bytes_per_tick = self.stats.max_scan_bytes_per_tick.max(scanned.bytes);
        self.stats.max_line_bytes_per_tick = self.stats.max_line_bytes_per_tick.max(line_bytes);
        io.store.end_tick();
    }

    /// Everything a line waits for: the tick's byte and `#VAR` budgets, simulated
    /// file-system latency, a label scan, the loader, `#FLUSH WAIT`, room in the queue, the
    /// start subroutine, a frame's file.
    fn ready_to_read(&mut self, io: &mut DecoderIo<'_>, tick_end: Duration) -> Ready {
        if self.reader.budget_spent() {
            return Ready::Stop;
        }
        let owed = io.store.take_owed();
        if self.reader.busy(owed, io.now, tick_end) {
            return Ready::Stop;
        }
        if self.reader.scanning() && !self.advance_scan() {
            return Ready::Stop;
        }
        match self.reader.cache_read_arrived(io.store) {
            Some(false) => return Ready::Stop,
            // The read's simulated latency is waited for first (top of the loop).
            Some(true) => return Ready::Again,
            None => {}
        }
        if self
            .reader
            .waits_for_idle(io.queue.is_empty() && io.motion_idle)
        {
            return Ready::Stop;
        }
        if !io.queue.has_room() {
            return Ready::Stop;
        }
        if let Err(e) = self
            .interp
            .start_subroutine(&mut self.reader, &mut self.notes, io)
        {
            self.fail(e, LineMeta { line: 0, offset: 0 });
            return Ready::Stop;
        }
        self.frame_file_arrived(io.store)
    }

    /// A top frame whose file the loader reads: `Again` when the text has just arrived (its
    /// simulated latency is waited for first), `Stop` while it has not or could not be read.
    fn frame_file_arrived(&mut self, store: &mut ProgramStore) -> Ready {
        match self.reader.frame_file_arrived(store) {
            FileArrival::Ready => Ready::Go,
            FileArrival::Arrived => Ready::Again,
            FileArrival::Waiting => Ready::Stop,
            FileArrival::Failed(e) => {
                self.fail(e, LineMeta { line: 0, offset: 0 });
                Ready::Stop
            }
        }
    }

    /// The decoding loop of [`Decoder::step`]: read a line, then join, run or end the frame.
    fn decode(&mut self, io: &mut DecoderIo<'_>) {
        let mut budget = self.interp.settings().blocks_per_tick;
        let tick_end = io.now + io.period;
        self.reader.begin_tick();
        while budget > 0 && self.state == DecoderState::Running {
            match self.ready_to_read(io, tick_end) {
                Ready::Stop => break,
                Ready::Again => continue,
                Ready::Go => {}
            }
            if self.reader.last().is_none() {
                self.state = DecoderState::Idle;
                break;
            }
            let mut line = self.reader.take_line();
            let read = self.reader.read_line(io.stream, &mut line, &mut self.notes);
            match read {
                LineRead::Pending => {
                    self.reader.put_line(line);
                    break;
                }
                LineRead::Eof if self.reader.joining() => {
                    // The file ends in a continued line: the block is what there is.
                    self.reader.put_line(line);
                    budget -= 1;
                    self.run_joined(io);
                }
                LineRead::TooLong(meta) => {
                    self.reader.put_line(line);
                    self.fail(LineTooLong.error(meta.line), meta);
                }
                LineRead::Eof => {
                    self.reader.put_line(line);
                    budget -= 1;
                    if let Err(e) = self.end_of_file(io) {
                        let meta = LineMeta {
                            line: self.reader.last().map_or(0, |f| f.line_no()),
                            offset: 0,
                        };
                        self.fail(e, meta);
                    }
                }
                LineRead::Line(meta) => {
                    budget -= 1;
                    self.stats.lines += 1;
                    if self.reader.joining()
                        || (continuation(&line).is_some()
                            && !self.reader.current().in_comment_block())
                    {
                        if self.reader.join(&line, meta) {
                            self.run_joined(io);
                        }
                        self.reader.put_line(line);
                        continue;
                    }
                    self.interp.count_line();
                    let r = self.process_line(&line, meta, io);
                    self.reader.put_line(line);
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
        let (joiner, meta) = self.reader.take_joined();
        self.interp.count_line();
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
        self.reader.put_joined(joiner);
        self.rewind_if_waiting(meta);
    }

    /// A line that has to wait (for a label scan) did nothing: it is read again, and its
    /// block counter given back.
    fn rewind_if_waiting(&mut self, meta: LineMeta) {
        if self.reader.rewind_if_waiting(meta) {
            self.interp.give_back_line();
        }
    }

    /// Go on with the label scan under way, within what is left of this tick's scan budget.
    /// `true` when it is done (its result installed) and decoding may go on.
    fn advance_scan(&mut self) -> bool {
        match self.reader.advance_scan(&mut self.notes) {
            Ok(done) => done,
            Err((e, meta)) => {
                self.fail(e, meta);
                false
            }
        }
    }

    fn fail(&mut self, e: DecodeError, meta: LineMeta) {
        let prog = self
            .reader
            .last()
            .map(|f| f.prog().clone())
            .unwrap_or_else(|| Arc::from(""));
        // ncchannel's detail only: the channel puts the kernel's text before it, once
        // (`reported_message`, called by the channel's `fail`).
        self.notes.push(Note::Error {
            code: e.code,
            msg: e.msg,
            prog,
            line: meta.line,
            col: e.col,
        });
        self.state = DecoderState::Failed;
        self.interp.end_search();
    }

    /// Raise an error from outside the decoder's own lines (e.g. stream data without CR LF).
    pub fn abort(&mut self, code: u32, msg: impl Into<String>) {
        let line = self.reader.last().map_or(0, |f| f.line_no());
        self.fail(DecodeError::new(code, msg), LineMeta { line, offset: 0 });
    }

    /// Run one line (a block, or a line of a `#COMMENT`/`#VAR` block); the main program's
    /// end decoded in it ends decoding.
    fn process_line(&mut self, text: &str, meta: LineMeta, io: &mut DecoderIo<'_>) -> Res {
        let r = self.run_line(text, meta, io);
        if self.interp.take_ended() {
            self.state = DecoderState::Ended;
        }
        r
    }

    /// The steps of one line: comment and `#VAR` blocks, the skip's unparsed lines, parse,
    /// then [`Self::run_block`]; the block's item list is kept for the next line.
    fn run_line(&mut self, text: &str, meta: LineMeta, io: &mut DecoderIo<'_>) -> Res {
        let top = self.reader.top();
        if top.in_comment_block() {
            if is_comment_end(text) {
                top.set_comment_block(false);
            }
            return Ok(());
        }
        if top.in_var_block() {
            // The lines of a `#VAR` block are declarations, read exactly as `check` reads
            // them (`V.P.TABLE[10]` is no ordinary block).
            match parse_var_line(text)? {
                VarLine::Blank => {}
                VarLine::End => top.set_var_block(false),
                // The comment block ends inside the `#VAR` block: both flags hold.
                VarLine::CommentBegin => top.set_comment_block(true),
                VarLine::Decl(d) => {
                    let made = self.interp.declare(&d)?;
                    self.reader.count_declared(made);
                }
            }
            return Ok(());
        }
        let skipping = top.flow().skipping();
        let stream = self.reader.current().is_stream();
        if skipping
            && self.reader.top().flow().skips_structure()
            && !may_matter_when_skipped(text, stream)
        {
            return Ok(());
        }
        let mut block = match parse_block_reusing(text, self.item_list()) {
            Ok(b) => b,
            // A syntax error in a skipped line never runs, so it is no error; but the skip
            // reads every `$` statement to find its structure's end, so a malformed one is
            // an error there too (docs/design-choices.md, "Malformed $ statements in
            // skipped lines").
            Err(e) if skipping && !codes::is_control_statement_fault(e.code) => return Ok(()),
            Err(e) => return Err(e.into()),
        };
        let r = self.run_block(&block, text, meta, stream, skipping, io);
        if let Some(items) = block.take_items() {
            self.spare_items = items;
        }
        r
    }

    /// The kept item list for the next parse, or a new one when the last line kept none (a
    /// command, a control statement, an error).
    fn item_list(&mut self) -> Vec<Item> {
        match std::mem::take(&mut self.spare_items) {
            list if list.capacity() == 0 => Vec::with_capacity(crate::lang::ITEM_LIST_CAPACITY),
            list => list,
        }
    }

    /// The steps of one parsed block: the stream's limits, the flow's skipping and labels,
    /// block search, `/n` skipping, then the block's body. `stream` and `skipping` as
    /// [`Self::run_line`] found them for the line.
    fn run_block(
        &mut self,
        block: &Block,
        text: &str,
        meta: LineMeta,
        stream: bool,
        skipping: bool,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        if stream {
            stream_allows(block)?;
        }
        if skipping {
            let flow = self.reader.top().flow_mut();
            let run_it = flow.skip_line(block, stream, &self.interp)?;
            if !run_it {
                return Ok(());
            }
        } else if let Some(l) = &block.label {
            self.reader.top().flow_mut().note_label(l, stream)?;
        }
        let at = BlockAt { block, text, meta };
        if self.interp.searching() {
            self.interp
                .search_block(at, &mut self.reader, &mut self.notes, io);
        }
        if let Some(level) = block.skip_level {
            if self.interp.skips_level(level) {
                return Ok(());
            }
        }
        let (ip, rd, notes) = (&mut self.interp, &mut self.reader, &mut self.notes);
        match &block.body {
            Body::Items(items) if items.is_empty() => Ok(()),
            Body::Items(items) => ip.exec_items(items, at, rd, notes, io),
            Body::Control(c) => {
                let top = rd.top();
                let next = top.line_pos();
                match top.flow_mut().exec_control(c, meta, next, ip)? {
                    FlowStep::Next => Ok(()),
                    FlowStep::Seek(at) => {
                        top.seek(at);
                        Ok(())
                    }
                    FlowStep::Goto(target) => rd.goto(target),
                }
            }
            Body::Command(c) => ip.exec_command(c, at, rd, notes, io),
            Body::Call(c) => ip.exec_call(c, at, rd, notes, io),
            Body::ProgramHead(_) if rd.current().kind() == FrameKind::Local => {
                // A local subroutine without M17/M29 ends where the next program begins.
                rd.top().flow().warn_open_flow(notes);
                ip.return_from_subroutine(rd, notes);
                ip.resume_held_end(rd, notes, io)
            }
            Body::ProgramHead(head) if head.local => {
                // A local subroutine section met while running: it runs only when called.
                rd.top().flow_mut().begin_skip(SkipUntil::LocalSubroutine);
                Ok(())
            }
            Body::ProgramHead(_) => Ok(()),
        }
    }

    fn end_of_file(&mut self, _io: &mut DecoderIo<'_>) -> Res {
        let searching = self.interp.searching();
        let top = self.reader.top();
        if let Some(t) = top.flow().skipping_to() {
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
        let (code, end) = match top.kind() {
            FrameKind::Main => (codes::OPEN_INVALID_BLOCK_MAIN, "main program"),
            FrameKind::Local => (codes::OPEN_INVALID_BLOCK_LOCAL, "local subroutine"),
            FrameKind::Global | FrameKind::Cycle => {
                (codes::OPEN_INVALID_BLOCK_GLOBAL, "global subroutine")
            }
        };
        if let Some(e) = top.flow().open_invalid_block(code, end) {
            return Err(e);
        }
        match top.kind() {
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
}

/// What a streaming program may not hold: loops (21478) and local subroutine calls (21479).
/// Can a line matter while a structure (`$IF` branch, `$SWITCH` case, loop) is skipped? Only
/// a `$` statement nests or ends the skip, and in a stream an `LL` call is refused even
/// there ([`stream_allows`]); any other line is skipped unparsed — a syntax error in it never
/// runs, as for a parsed one. A `$` or (streams) an `L` anywhere, in a comment too, sends the
/// line through the parser: the test may say yes too often, never too seldom.
#[inline]
fn may_matter_when_skipped(text: &str, stream: bool) -> bool {
    let b = text.as_bytes();
    memchr::memchr(b'$', b).is_some() || (stream && memchr::memchr2(b'L', b'l', b).is_some())
}

fn stream_allows(block: &Block) -> Res {
    match &block.body {
        Body::Control(c) if is_loop_statement(c) => Err(DecodeError::new(
            codes::STREAM_LOOP,
            "loop statement in streaming program; streaming aborted",
        )),
        Body::Call(c) if matches!(**c, Call::Local { .. } | Call::Cycle { local: true, .. }) => {
            Err(DecodeError::new(
                codes::STREAM_LOCAL_CALL,
                "local subroutine call (LL) in streaming program",
            ))
        }
        _ => Ok(()),
    }
}
