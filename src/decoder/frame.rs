//! Decoder frames: one program level each (main program, subroutine, cycle, the stream), and
//! the incremental line readers behind them.
//!
//! A file frame holds its whole text in memory; a stream frame reads the channel's current
//! stream segment and pulls the next segment from the stream buffer only when it has decoded
//! the last line of the previous one (ISG FCT-C19 Data streaming §2.2: one read extracts all data present).

use std::collections::BTreeSet;
use std::sync::Arc;

use crate::lang::block::{GotoTarget, Label};
use crate::source::loader::PendingRead;
use crate::source::store::ProgramText;
use crate::source::stream::StreamBuffer;

use super::labels::LabelIndex;
pub(crate) use super::line::LinePos;
pub use super::line::MAX_LINE_BYTES;
use super::line::{cut_line, LineMeta, LineRead, LineTooLong};
use super::vars::VarSlot;

/// One open control structure of a frame.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum FlowEntry {
    /// `$IF`: `taken` once a branch has run, so later `$ELSEIF`/`$ELSE` branches are skipped.
    If { taken: bool },
    /// `$SWITCH`: the value cases compare against.
    Switch { value: f64 },
    /// `$FOR var = start, end, step`: the body starts at `body`.
    For {
        var: VarSlot,
        end: f64,
        step: f64,
        body: LinePos,
    },
    /// `$WHILE`: `head` is the `$WHILE` line itself (the condition is evaluated there).
    While { head: LinePos },
    /// `$DO` … `$ENDDO cond`.
    Do { body: LinePos },
    /// `$REPEAT` … `$UNTIL cond`.
    Repeat { body: LinePos },
}

impl FlowEntry {
    pub(crate) fn is_loop(&self) -> bool {
        matches!(
            self,
            FlowEntry::For { .. }
                | FlowEntry::While { .. }
                | FlowEntry::Do { .. }
                | FlowEntry::Repeat { .. }
        )
    }
}

/// What the skip machine is looking for.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum SkipUntil {
    /// A false `$IF`/`$ELSEIF`: the next `$ELSEIF` (evaluated), `$ELSE` or `$ENDIF`.
    IfBranch,
    /// A branch has run: the `$ENDIF`.
    IfEnd,
    /// `$SWITCH` looking for its case: a matching `$CASE`, `$DEFAULT` or `$ENDSWITCH`.
    Case,
    /// After `$BREAK` in a switch: the `$ENDSWITCH`.
    SwitchEnd,
    /// A false `$WHILE` or a `$BREAK` in a loop: past the loop's end statement.
    LoopExit,
    /// `$CONTINUE`: the loop's end statement, which is then evaluated.
    LoopContinue,
    /// A forward `$GOTO` (streams): the line with this label.
    Label(GotoTarget),
    /// A `%L name` section met while running the main program: up to its M17/M29, or to the
    /// next `%name` head when it has none.
    LocalSubroutine,
}

/// Skip state: what we look for and how deep inside skipped structures we are.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Skip {
    pub(crate) until: SkipUntil,
    /// Structures opened inside the skipped region and not yet closed.
    pub(crate) depth: u32,
}

impl Skip {
    pub(crate) fn new(until: SkipUntil) -> Self {
        Skip { until, depth: 0 }
    }
}

/// What kind of program level a frame is; decides which end blocks are allowed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FrameKind {
    Main,
    /// `L file`.
    Global,
    /// `L CYCLE [NAME=..]`.
    Cycle,
    /// `LL name`: a `%L name` section of the calling file.
    Local,
}

#[derive(Debug, Clone)]
pub(crate) enum Source {
    File(ProgramText),
    /// A file the loader is still reading (off the runtime thread): the frame's first line
    /// waits for it, as it waits for a simulated file-system read.
    Loading(PendingRead),
    Stream,
}

/// One program level.
#[derive(Debug)]
pub(crate) struct Frame {
    pub(crate) kind: FrameKind,
    pub(crate) source: Source,
    pub(crate) prog: Arc<str>,
    /// File frames: byte offset of the next line.
    pub(crate) pos: usize,
    /// File frames: lines read so far.
    pub(crate) line_no: u32,
    /// Open control structures, innermost last.
    pub(crate) flow: Vec<FlowEntry>,
    /// Set while lines are being skipped (false branch, forward jump, …).
    pub(crate) skip: Option<Skip>,
    /// Inside `#COMMENT BEGIN` … `#COMMENT END`.
    pub(crate) comment_block: bool,
    /// Inside `#VAR` … `#ENDVAR`.
    pub(crate) var_block: bool,
    /// Stream frames: labels already passed, to tell a backward jump (21477) from a forward
    /// one and to find labels defined twice (20836). Bounded by `MAX_SEEN_LABELS`; a B-tree
    /// for the reason `LabelIndex` is one.
    pub(crate) seen_labels: BTreeSet<Label>,
    /// File frames: label → position and structural depth, built on the first jump.
    pub(crate) label_index: Option<Arc<LabelIndex>>,
}

/// How many stream labels a frame remembers. A stream may run for days; a label passed more
/// than this many labels ago is treated as unknown (a jump to it waits forward for it).
pub(crate) const MAX_SEEN_LABELS: usize = 65_536;

/// A frame that held the last reference to a large file text lets the loader thread free it,
/// and its label tables with it: tens of thousands of labels take milliseconds to free.
impl Drop for Frame {
    fn drop(&mut self) {
        use crate::source::loader;
        if let Source::File(p) = &mut self.source {
            loader::release(std::mem::take(&mut p.text));
        }
        if let Some(index) = self.label_index.take() {
            let items = index.len();
            loader::release_table(index, items);
        }
        let seen = self.seen_labels.len();
        loader::release_table(std::mem::take(&mut self.seen_labels), seen);
    }
}

impl Frame {
    pub(crate) fn new(kind: FrameKind, source: Source, prog: Arc<str>) -> Self {
        Frame {
            kind,
            source,
            prog,
            pos: 0,
            line_no: 0,
            flow: Vec::new(),
            skip: None,
            comment_block: false,
            var_block: false,
            seen_labels: BTreeSet::new(),
            label_index: None,
        }
    }

    pub(crate) fn is_stream(&self) -> bool {
        matches!(self.source, Source::Stream)
    }

    pub(crate) fn line_pos(&self) -> LinePos {
        LinePos {
            pos: self.pos,
            line_no: self.line_no,
        }
    }

    pub(crate) fn seek(&mut self, at: LinePos) {
        self.pos = at.pos;
        self.line_no = at.line_no;
    }
}

/// Next line of a file frame.
pub(crate) fn read_file_line(frame: &mut Frame, out: &mut String) -> LineRead {
    let Source::File(p) = &frame.source else {
        return LineRead::Eof;
    };
    let start = frame.pos;
    match cut_line(&p.text, start, out, true) {
        Ok(Some(next)) => {
            frame.pos = next;
            frame.line_no += 1;
            LineRead::Line(LineMeta {
                line: frame.line_no,
                offset: start as u64,
            })
        }
        Ok(None) => LineRead::Eof,
        Err(LineTooLong) => LineRead::TooLong(LineMeta {
            line: frame.line_no + 1,
            offset: start as u64,
        }),
    }
}

/// The channel's reader of its stream interface: the current segment and where we are in it.
#[derive(Debug, Default)]
pub(crate) struct StreamReader {
    seg: Vec<u8>,
    /// Reused buffer the stream buffer empties into.
    scratch: Vec<u8>,
    pos: usize,
    /// Stream offset of `seg[0]`, bytes since stream start.
    seg_base: u64,
    line_no: u32,
    /// Segments extracted since stream start.
    pub(crate) segments: u64,
}

/// What reading the stream did besides returning a line, for the event log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum StreamNote {
    Segment { bytes: usize },
}

impl StreamReader {
    /// Start a new stream: forget everything read before.
    pub(crate) fn restart(&mut self) {
        self.seg.clear();
        self.pos = 0;
        self.seg_base = 0;
        self.line_no = 0;
        self.segments = 0;
    }

    /// Bytes of the current segment not yet decoded.
    pub(crate) fn remaining(&self) -> usize {
        self.seg.len() - self.pos
    }

    /// Next line; pulls a new segment from `buf` only when the current one is used up.
    pub(crate) fn next_line(
        &mut self,
        buf: &mut StreamBuffer,
        out: &mut String,
        note: &mut Option<StreamNote>,
    ) -> LineRead {
        loop {
            // A segment holds at most one buffer's worth of lines: never too long.
            if let Ok(Some(next)) = cut_line(&self.seg, self.pos, out, false) {
                let meta = LineMeta {
                    line: self.line_no + 1,
                    offset: self.seg_base + self.pos as u64,
                };
                self.line_no += 1;
                self.pos = next;
                return LineRead::Line(meta);
            }
            if buf.used() == 0 {
                return LineRead::Pending;
            }
            let consumed = self.pos;
            self.seg_base += consumed as u64;
            self.pos = 0;
            let bytes = if consumed == self.seg.len() {
                // The usual case: the segment is used up; the next one replaces it in place.
                buf.take_segment(&mut self.seg)
            } else {
                // An incomplete tail (impossible with CR LF-checked writes) stays, and the
                // next segment is appended after it.
                self.seg.drain(..consumed);
                let n = buf.take_segment(&mut self.scratch);
                self.seg.extend_from_slice(&self.scratch);
                n
            };
            self.segments += 1;
            *note = Some(StreamNote::Segment { bytes });
        }
    }

    /// Drop the rest of the current segment (program end inside a segment, ISG FCT-C19 Data streaming §2.2).
    /// Data still in the stream buffer stays. Returns the bytes dropped.
    pub(crate) fn discard_rest(&mut self) -> usize {
        let n = self.remaining();
        self.seg_base += self.seg.len() as u64;
        self.seg.clear();
        self.pos = 0;
        n
    }
}
