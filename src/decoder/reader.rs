//! The reader: the frame stack, the stream segment being read, the line joiner, and what a
//! line waits for (the tick's budgets, simulated file-system latency, label scans, the loader,
//! `#FLUSH WAIT`).

use std::sync::Arc;
use std::time::Duration;

use super::error::{DecodeError, Res};
use super::frame::{read_file_line, Frame, StreamNote, StreamReader};
use super::labels::{LabelIndex, LabelScan, ScanFound, ScanGoal, ScanStep, ScanWork};
use super::line::{LineMeta, LinePos, LineRead};
use super::note::Note;
use super::settings::{DECLARED_VALUES_PER_TICK, LINE_BYTES_PER_TICK};
use crate::lang::block::GotoTarget;
use crate::lang::codes;
use crate::lang::control::{goto_label, goto_text};
use crate::lang::Joiner;
use crate::source::loader::{Loader, PendingRead};
use crate::source::store::{ProgramStore, ProgramText, StoreError};
use crate::source::stream::StreamBuffer;

/// A `#CACHE LOAD` whose file the loader reads: the line waits, and runs again with the text.
#[derive(Debug)]
pub(super) struct CacheRead {
    pub(super) file: String,
    pub(super) pending: PendingRead,
    /// The loader's answer, once there.
    pub(super) read: Option<Result<ProgramText, StoreError>>,
}

/// What the top frame's file is doing ([`Reader::frame_file_arrived`]).
#[derive(Debug)]
pub(super) enum FileArrival {
    /// Nothing to wait for (no frame, or its text is there).
    Ready,
    /// The text has just arrived: its simulated latency is waited for first.
    Arrived,
    /// Not yet read.
    Waiting,
    /// The loader could not read it.
    Failed(DecodeError),
}

/// The frame stack and everything a line waits for.
#[derive(Debug)]
pub(super) struct Reader {
    /// Program levels, main program first, the running one last.
    frames: Vec<Frame>,
    stream: StreamReader,
    /// A stream frame is on the frame stack.
    stream_active: bool,
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
    /// Label scans begun since the decoder was made.
    label_scans: u64,
    /// Bytes of NC text decoded in this tick ([`LINE_BYTES_PER_TICK`]).
    line_bytes_this_tick: usize,
    /// A `#CACHE LOAD` waiting for the loader.
    cache_read: Option<CacheRead>,
    /// The line being run has to wait (for a label scan, a `#CACHE LOAD` read): it is read
    /// again later.
    wait_line: bool,
    /// The line being read, kept between lines for its allocation.
    line: String,
    /// A block written over several lines (`\` at the end of a line) being collected, and
    /// where its first line stands.
    joiner: Joiner,
    join_meta: LineMeta,
    /// Frees the frames and label scans the reader lets go of when that could cost a tick
    /// (a large text, a large label table).
    loader: Loader,
}

impl Reader {
    pub(super) fn new(loader: Loader) -> Self {
        Reader {
            loader,
            frames: Vec::new(),
            stream: StreamReader::default(),
            stream_active: false,
            wait_idle: false,
            starved: false,
            ready_at: Duration::ZERO,
            declared_this_tick: 0,
            scan: None,
            scan_found: None,
            scanned_this_tick: ScanWork::default(),
            label_scans: 0,
            line_bytes_this_tick: 0,
            cache_read: None,
            wait_line: false,
            line: String::new(),
            joiner: Joiner::default(),
            join_meta: LineMeta { line: 0, offset: 0 },
        }
    }
}

/// Whatever the reader still holds when the decoder goes is freed as a frame popped is.
impl Drop for Reader {
    fn drop(&mut self) {
        self.release_frames();
        self.release_scan();
    }
}

impl Reader {
    /// Let go of every frame, each through [`Reader::release`].
    fn release_frames(&mut self) {
        let loader = &self.loader;
        for f in self.frames.drain(..) {
            loader.free_if(f.is_heavy(), f);
        }
    }

    /// Let go of the label scan under way, if any: a large one through the loader thread.
    fn release_scan(&mut self) {
        if let Some(scan) = self.scan.take() {
            self.loader.free_if(scan.is_heavy(), scan);
        }
    }

    /// A new program starts: no frames, nothing waited for.
    pub(super) fn start(&mut self) {
        self.release_frames();
        self.joiner = Joiner::default();
        self.wait_idle = false;
        self.starved = false;
        self.ready_at = Duration::ZERO;
        self.forget_scan();
        self.stream_active = false;
    }

    /// Channel reset: frames and the stream position go.
    pub(super) fn reset(&mut self) {
        self.release_frames();
        self.joiner = Joiner::default();
        self.stream.restart();
        self.stream_active = false;
        self.wait_idle = false;
        self.starved = false;
        self.ready_at = Duration::ZERO;
        self.forget_scan();
    }

    /// No label scan under way or waited for.
    fn forget_scan(&mut self) {
        self.release_scan();
        self.scan_found = None;
        self.cache_read = None;
        self.wait_line = false;
    }

    // --- The frame stack ---

    pub(super) fn push(&mut self, frame: Frame) {
        self.frames.push(frame);
    }

    /// The running frame leaves the stack (a return); a stream frame ends its stream, the
    /// rest of its segment going (reported as a discard). False: no frame was running.
    pub(super) fn pop(&mut self, notes: &mut Vec<Note>) -> bool {
        let Some(f) = self.frames.pop() else {
            return false;
        };
        if f.is_stream() {
            self.discard_stream_rest(notes);
            self.stream_active = false;
        }
        self.loader.free_if(f.is_heavy(), f);
        true
    }

    /// M30/M2: every frame goes; in a stream the rest of the current segment goes.
    pub(super) fn end_program(&mut self, notes: &mut Vec<Note>) {
        if self.stream_active {
            self.discard_stream_rest(notes);
            self.stream_active = false;
        }
        self.release_frames();
        self.starved = false;
    }

    fn discard_stream_rest(&mut self, notes: &mut Vec<Note>) {
        let bytes = self.stream.discard_rest();
        if bytes > 0 {
            notes.push(Note::Discard { bytes });
        }
    }

    /// Program levels open (main program = 1).
    pub(super) fn depth(&self) -> usize {
        self.frames.len()
    }

    /// The running frame. Lines are run only with a frame on the stack (checked in
    /// `Decoder::decode`).
    pub(super) fn top(&mut self) -> &mut Frame {
        let i = self.frames.len() - 1;
        &mut self.frames[i]
    }

    /// The running frame (there is one: see [`Reader::top`]).
    pub(super) fn current(&self) -> &Frame {
        &self.frames[self.frames.len() - 1]
    }

    /// The running frame, if any.
    #[inline]
    pub(super) fn last(&self) -> Option<&Frame> {
        self.frames.last()
    }

    /// The text of the file program `prog` while a frame of it is open.
    pub(super) fn program_text(&self, prog: &str) -> Option<Arc<Vec<u8>>> {
        self.frames.iter().rev().find_map(|f| match f.file() {
            Some(t) if **f.prog() == *prog => Some(Arc::clone(&t.text)),
            _ => None,
        })
    }

    // --- The stream ---

    /// A stream frame is on the stack.
    pub(super) fn stream_active(&self) -> bool {
        self.stream_active
    }

    /// A stream program starts reading the stream interface from its beginning.
    pub(super) fn begin_stream(&mut self) {
        self.stream.restart();
        self.stream_active = true;
    }

    /// Waiting for stream data that has not arrived.
    pub(super) fn starved(&self) -> bool {
        self.starved
    }

    // --- Reading lines ---

    /// The top frame's next line into `line`: a new stream segment pulled is noted.
    #[inline]
    pub(super) fn read_line(
        &mut self,
        stream: &mut StreamBuffer,
        line: &mut String,
        notes: &mut Vec<Note>,
    ) -> LineRead {
        let i = self.frames.len() - 1;
        let top = &mut self.frames[i];
        let read = if top.is_stream() {
            let mut note = None;
            let r = self.stream.next_line(stream, line, &mut note);
            if let Some(StreamNote::Segment { bytes }) = note {
                notes.push(Note::Segment { bytes });
            }
            r
        } else {
            read_file_line(top, line)
        };
        match read {
            LineRead::Line(_) => {
                // The line and its end (CR LF at most).
                self.line_bytes_this_tick += line.len() + 2;
                self.starved = false;
            }
            LineRead::Pending => self.starved = true,
            _ => {}
        }
        read
    }

    /// The line buffer, lent out while its line runs ([`Reader::put_line`] gives it back).
    #[inline]
    pub(super) fn take_line(&mut self) -> String {
        std::mem::take(&mut self.line)
    }

    #[inline]
    pub(super) fn put_line(&mut self, line: String) {
        self.line = line;
    }

    /// A block written over several lines is being collected.
    #[inline]
    pub(super) fn joining(&self) -> bool {
        self.joiner.is_open()
    }

    /// Add a line to the block being collected (its first line starts it at `meta`); `true`
    /// when the block is complete.
    pub(super) fn join(&mut self, line: &str, meta: LineMeta) -> bool {
        if !self.joiner.is_open() {
            self.join_meta = meta;
        }
        self.joiner.push(line)
    }

    /// The collected block and where its first line stands, lent out while it runs
    /// ([`Reader::put_joined`] gives it back).
    pub(super) fn take_joined(&mut self) -> (Joiner, LineMeta) {
        (std::mem::take(&mut self.joiner), self.join_meta)
    }

    /// The collected block has run: the joiner is empty again, its buffer kept.
    pub(super) fn put_joined(&mut self, joiner: Joiner) {
        self.joiner = joiner;
        self.joiner.close();
    }

    /// A line that has to wait (for a label scan) did nothing: `true`, and it is read again
    /// (its block counter is for the caller to give back).
    pub(super) fn rewind_if_waiting(&mut self, meta: LineMeta) -> bool {
        if !std::mem::take(&mut self.wait_line) {
            return false;
        }
        let at = LinePos {
            pos: usize::try_from(meta.offset).unwrap_or(usize::MAX),
            line_no: meta.line.saturating_sub(1),
        };
        self.top().seek(at);
        true
    }

    // --- Budgets and waits ---

    /// A tick begins: its budgets are full.
    #[inline]
    pub(super) fn begin_tick(&mut self) {
        self.declared_this_tick = 0;
        self.scanned_this_tick = ScanWork::default();
        self.line_bytes_this_tick = 0;
    }

    /// The tick's byte or `#VAR` budget is used up.
    #[inline]
    pub(super) fn budget_spent(&self) -> bool {
        self.declared_this_tick >= DECLARED_VALUES_PER_TICK
            || self.line_bytes_this_tick >= LINE_BYTES_PER_TICK
    }

    /// Values made by a `#VAR` declaration count against the tick's budget.
    pub(super) fn count_declared(&mut self, values: usize) {
        self.declared_this_tick += values;
    }

    /// Lines and bytes label scans read in this tick, and bytes of NC text decoded.
    #[inline]
    pub(super) fn tick_work(&self) -> (ScanWork, usize) {
        (self.scanned_this_tick, self.line_bytes_this_tick)
    }

    /// Label scans begun so far.
    pub(super) fn label_scans(&self) -> u64 {
        self.label_scans
    }

    /// Simulated file-system latency `owed` moves the time decoding may go on by its cost,
    /// counted from when the decoder was free; `true` while that time lies past `tick_end`.
    #[inline]
    pub(super) fn busy(&mut self, owed: Duration, now: Duration, tick_end: Duration) -> bool {
        if !owed.is_zero() {
            self.ready_at = self.ready_at.max(now) + owed;
        }
        self.ready_at >= tick_end
    }

    /// `#FLUSH WAIT`: decoding waits until motion is empty.
    pub(super) fn wait_for_idle(&mut self) {
        self.wait_idle = true;
    }

    /// Still waiting for motion to be empty (`idle`: queue and motion have nothing left).
    #[inline]
    pub(super) fn waits_for_idle(&mut self, idle: bool) -> bool {
        if self.wait_idle && idle {
            self.wait_idle = false;
        }
        self.wait_idle
    }

    /// The line being run waits for something.
    pub(super) fn line_waits(&self) -> bool {
        self.wait_line
    }

    /// A `#CACHE LOAD` waits for the loader to read its file; the line waits with it.
    pub(super) fn wait_for_cache_read(&mut self, read: CacheRead) {
        self.cache_read = Some(read);
        self.wait_line = true;
    }

    /// The `#CACHE LOAD` read waited for, if any.
    pub(super) fn take_cache_read(&mut self) -> Option<CacheRead> {
        self.cache_read.take()
    }

    /// A `#CACHE LOAD` waiting for the loader: `Some(true)` when its text has just arrived,
    /// `Some(false)` while it has not, `None` when no load waits.
    #[inline]
    pub(super) fn cache_read_arrived(&mut self, store: &mut ProgramStore) -> Option<bool> {
        let r = self.cache_read.as_mut().filter(|r| r.read.is_none())?;
        let read = store.finish_read(&r.pending);
        let arrived = read.is_some();
        r.read = read;
        Some(arrived)
    }

    /// A top frame whose file the loader reads: has its text arrived?
    #[inline]
    pub(super) fn frame_file_arrived(&mut self, store: &mut ProgramStore) -> FileArrival {
        let Some(top) = self.frames.last_mut() else {
            return FileArrival::Ready;
        };
        let Some(p) = top.loading() else {
            return FileArrival::Ready;
        };
        match store.finish_read(p) {
            None => FileArrival::Waiting,
            Some(Ok(text)) => {
                top.loaded(text);
                FileArrival::Arrived
            }
            Some(Err(e)) => FileArrival::Failed(e.into()),
        }
    }

    // --- Label scans ---

    /// A label scan is under way.
    #[inline]
    pub(super) fn scanning(&self) -> bool {
        self.scan.is_some()
    }

    /// Go on with the label scan under way, within what is left of this tick's scan budget;
    /// its warnings are noted. `Ok(true)` when it is done (its result installed) and
    /// decoding may go on; an error comes with where the top frame stands.
    pub(super) fn advance_scan(
        &mut self,
        notes: &mut Vec<Note>,
    ) -> Result<bool, (DecodeError, LineMeta)> {
        let Some(scan) = self.scan.as_mut() else {
            return Ok(true);
        };
        let step = scan.advance(&mut self.scanned_this_tick);
        let warnings = scan.take_warnings();
        let goal = scan.goal().clone();
        for w in warnings {
            notes.push(Note::Warning {
                code: w.code,
                msg: w.msg,
            });
        }
        match step {
            Ok(ScanStep::Pending) => Ok(false),
            Ok(ScanStep::Done(found)) => {
                self.release_scan();
                match found {
                    ScanFound::Index(index) => self.top().set_label_index(Arc::new(index)),
                    other => self.scan_found = Some((goal, other)),
                }
                Ok(true)
            }
            Err(e) => {
                self.release_scan();
                let at = self.top().line_pos();
                let meta = LineMeta {
                    line: at.line_no + 1,
                    offset: at.pos as u64,
                };
                Err((e, meta))
            }
        }
    }

    /// `$GOTO`: in a stream a forward skip to the label; in a file a jump by the label index of
    /// the top frame's text, which the reader builds over several ticks.
    pub(super) fn goto(&mut self, t: &GotoTarget) -> Res {
        let top = self.top();
        if top.is_stream() {
            return top.flow_mut().skip_to(t);
        }
        // A file frame: the label index, built over several ticks; the line waits for it.
        let Some(index) = self.label_index() else {
            return Ok(());
        };
        let found = match index.find(t) {
            Some(at) => Some(at),
            None if index.overflowed => match self.searched(ScanGoal::Label(goto_label(t))) {
                Some(ScanFound::Label(at)) => at,
                _ => return Ok(()),
            },
            None => None,
        };
        let Some((at, depth)) = found else {
            return Err(DecodeError::new(
                codes::LABEL_NOT_FOUND,
                format!("label {} not found", goto_text(t)),
            ));
        };
        let top = self.top();
        top.seek(at);
        top.flow_mut().leave_to_depth(depth);
        Ok(())
    }

    /// The label index of the top frame's text, once built. `None`: its scan has begun (or
    /// goes on) and the line asking waits (`wait_line`); it is read again when the scan is
    /// done. A stream frame has none (its jumps go forward, line by line).
    pub(super) fn label_index(&mut self) -> Option<Arc<LabelIndex>> {
        let top = self.top();
        if let Some(i) = top.label_index() {
            return Some(i.clone());
        }
        let Some(p) = top.file() else {
            return Some(Arc::new(LabelIndex::default()));
        };
        let scan = LabelScan::new(p.text.clone(), ScanGoal::Index);
        self.begin_scan(scan);
        None
    }

    /// What a targeted scan for `goal` found: `None` while it runs (the line waits).
    pub(super) fn searched(&mut self, goal: ScanGoal) -> Option<ScanFound> {
        if let Some((g, _)) = &self.scan_found {
            if *g == goal {
                return self.scan_found.take().map(|(_, found)| found);
            }
        }
        if let Some(p) = self.top().file() {
            let scan = LabelScan::new(p.text.clone(), goal);
            self.begin_scan(scan);
        }
        None
    }

    fn begin_scan(&mut self, scan: LabelScan) {
        self.label_scans += 1;
        self.scan = Some(scan);
        self.wait_line = true;
    }
}
