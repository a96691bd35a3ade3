//! The splitter: a state machine over received bytes, in chunks of any size, that cuts the
//! transfer into programs by start/end marker lines and SINUMERIK control lines.
//!
//! It does no I/O. Every program comes out as `start`, any number of `data` slices (the
//! program's bytes exactly as received, CR LF or LF kept), and `end` with the program's name
//! lines, so a writer can stream to a file without holding a program in memory. The only
//! buffer is the head of one unfinished line, at most [`LINE_WINDOW`] bytes: a longer line is
//! decided on its first [`LINE_WINDOW`] bytes and the rest streams through. Decisions depend
//! only on line contents, never on where a chunk ended, so every chunking gives the same files.

use memchr::memchr;

use super::control_line::{self, NameInfo};
use super::markers::{ChunkScan, Markers, Mode, LINE_WINDOW};

/// A program begins.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramStart {
    /// 0-based count of programs in this transfer.
    pub index: usize,
    /// 1-based line of the transfer where the program begins.
    pub line: u64,
}

/// A program is over.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramEnd {
    pub index: usize,
    /// 1-based lines of the transfer holding the program's first and last line.
    pub first_line: u64,
    pub last_line: u64,
    pub bytes: u64,
    /// `false` when the transfer stopped inside the program: an open start/end region at the
    /// end of data, or any open program when the transfer broke (read error, time-out).
    pub complete: bool,
    /// What the program's name lines said.
    pub name: NameInfo,
}

/// Where the splitter delivers programs.
pub trait ProgramSink {
    type Error;
    fn start(&mut self, start: &ProgramStart) -> Result<(), Self::Error>;
    /// The next bytes of the current program, in order.
    fn data(&mut self, bytes: &[u8]) -> Result<(), Self::Error>;
    fn end(&mut self, end: ProgramEnd) -> Result<(), Self::Error>;
}

/// Counts of one finished transfer.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SplitSummary {
    pub mode: Option<Mode>,
    /// Programs delivered (complete or not).
    pub programs: usize,
    /// Programs delivered with `complete == false`.
    pub cut_off: usize,
    /// Did a start marker occur (start-only and start/end mode)?
    pub(crate) start_found: bool,
    pub bytes_in: u64,
    /// Bytes outside every program (before the first start, between regions, blank lines
    /// between end-only blocks).
    pub bytes_ignored: u64,
    pub lines: u64,
}

impl SplitSummary {
    /// Start-only mode without a start marker: MMP discards everything and tells the operator.
    pub fn no_start_marker(&self) -> bool {
        matches!(self.mode, Some(Mode::StartOnly) | Some(Mode::StartEnd)) && !self.start_found
    }
}

/// What one line does to the program structure.
#[derive(Debug, Clone, Copy, Default)]
struct Action {
    end_before: bool,
    start_before: bool,
    include: bool,
    end_after: bool,
}

/// The tail of a long line whose head has been decided.
#[derive(Debug, Clone, Copy)]
struct Continuation {
    include: bool,
    end_after: bool,
}

#[derive(Debug, Default)]
struct Open {
    index: usize,
    first_line: u64,
    last_line: u64,
    bytes: u64,
    name: NameInfo,
}

/// Splits one transfer after another; [`Splitter::finish`] or [`Splitter::abort`] ends a
/// transfer and resets the machine for the next.
#[derive(Debug)]
pub struct Splitter {
    markers: Markers,
    mode: Mode,
    /// Head of an unfinished line, shorter than `LINE_WINDOW`.
    carry: Vec<u8>,
    continuation: Option<Continuation>,
    open: Option<Open>,
    /// 1-based number of the line being read.
    line: u64,
    summary: SplitSummary,
}

impl Splitter {
    pub fn new(markers: Markers) -> Self {
        let mode = markers.mode();
        Splitter {
            markers,
            mode,
            carry: Vec::new(),
            continuation: None,
            open: None,
            line: 1,
            summary: SplitSummary {
                mode: Some(mode),
                ..SplitSummary::default()
            },
        }
    }

    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// Feed the next received bytes.
    pub fn feed<S: ProgramSink>(&mut self, mut chunk: &[u8], sink: &mut S) -> Result<(), S::Error> {
        self.summary.bytes_in += chunk.len() as u64;
        loop {
            if chunk.is_empty() {
                return Ok(());
            }
            if let Some(cont) = self.continuation {
                // The tail of a long line goes where its head went.
                let (tail, done) = match memchr(b'\n', chunk) {
                    Some(i) => (&chunk[..=i], true),
                    None => (chunk, false),
                };
                self.take_bytes(tail, cont.include, sink)?;
                chunk = &chunk[tail.len()..];
                if done {
                    self.continuation = None;
                    self.line_done(cont.end_after, sink)?;
                }
                continue;
            }
            if !self.carry.is_empty() {
                let room = LINE_WINDOW - self.carry.len();
                let window = &chunk[..room.min(chunk.len())];
                let (piece, complete) = match memchr(b'\n', window) {
                    Some(i) => (&window[..=i], true),
                    None => (window, false),
                };
                self.carry.extend_from_slice(piece);
                chunk = &chunk[piece.len()..];
                if complete || self.carry.len() == LINE_WINDOW {
                    let line = std::mem::take(&mut self.carry);
                    let r = self.single_line(&line, complete, sink);
                    self.carry = line;
                    self.carry.clear();
                    r?;
                }
                continue;
            }
            return self.in_place(chunk, sink);
        }
    }

    /// The data ended normally (end of file, connection closed by the sender). In start/end
    /// mode an open region is a cut-off program (`complete == false`); in the other modes the
    /// last program runs to the end of the data and is complete.
    pub fn finish<S: ProgramSink>(&mut self, sink: &mut S) -> Result<SplitSummary, S::Error> {
        let complete = self.mode != Mode::StartEnd;
        self.close(complete, sink)
    }

    /// The transfer broke (read error, time-out): an open program is never complete.
    pub fn abort<S: ProgramSink>(&mut self, sink: &mut S) -> Result<SplitSummary, S::Error> {
        self.close(false, sink)
    }

    fn close<S: ProgramSink>(
        &mut self,
        complete: bool,
        sink: &mut S,
    ) -> Result<SplitSummary, S::Error> {
        if let Some(cont) = self.continuation.take() {
            // The data ended inside a long line: the line ends there.
            self.line_done(cont.end_after, sink)?;
        } else if !self.carry.is_empty() {
            // A last line without a line end is still a line.
            let line = std::mem::take(&mut self.carry);
            let r = self.single_line(&line, true, sink);
            self.carry = line;
            self.carry.clear();
            r?;
        }
        if self.open.is_some() {
            self.end_program(complete, sink)?;
        }
        let mut summary = self.summary;
        summary.lines = self.line - 1;
        self.line = 1;
        self.summary = SplitSummary {
            mode: Some(self.mode),
            ..SplitSummary::default()
        };
        Ok(summary)
    }

    /// Which markers to look for now: the search alternates in start/end mode.
    fn wants(&self) -> (bool, bool) {
        let open = self.open.is_some();
        match self.mode {
            Mode::StartOnly => (true, false),
            Mode::EndOnly => (false, true),
            Mode::StartEnd => (!open, open),
        }
    }

    /// The rules of SINUMERIK "Manage MyPrograms" (start/end markers) for one line, given the marker hits in its head.
    fn step(&self, head: &[u8], start_hit: bool, end_hit: bool) -> Action {
        let split = || {
            self.open
                .as_ref()
                .is_some_and(|o| o.name.has_sinumerik_line())
                && control_line::is_sinumerik_start(head)
        };
        let open = self.open.is_some();
        match self.mode {
            Mode::StartOnly if start_hit => Action {
                end_before: open,
                start_before: true,
                include: true,
                end_after: false,
            },
            Mode::StartOnly | Mode::StartEnd if !open => Action {
                start_before: start_hit,
                include: start_hit,
                ..Action::default()
            },
            Mode::EndOnly if !open => {
                if is_blank(head) {
                    Action::default()
                } else {
                    Action {
                        start_before: true,
                        include: true,
                        end_after: end_hit,
                        ..Action::default()
                    }
                }
            }
            _ => {
                let s = split();
                Action {
                    end_before: s,
                    start_before: s,
                    include: true,
                    end_after: end_hit,
                }
            }
        }
    }

    /// One line from the carry buffer (or the head of a long one when `complete` is false).
    fn single_line<S: ProgramSink>(
        &mut self,
        line: &[u8],
        complete: bool,
        sink: &mut S,
    ) -> Result<(), S::Error> {
        let head = &line[..line.len().min(LINE_WINDOW)];
        let (ws, we) = self.wants();
        let sh = ws && self.markers.start_in(head);
        let eh = we && self.markers.end_in(head);
        let a = self.step(head, sh, eh);
        self.open_close(a, sink)?;
        if a.include {
            self.note(head);
        }
        self.take_bytes(line, a.include, sink)?;
        if complete {
            self.line_done(a.end_after, sink)
        } else {
            self.continuation = Some(Continuation {
                include: a.include,
                end_after: a.end_after,
            });
            Ok(())
        }
    }

    /// The fast path: whole lines straight from the chunk, consecutive program lines handed
    /// to the sink as one slice.
    fn in_place<S: ProgramSink>(&mut self, buf: &[u8], sink: &mut S) -> Result<(), S::Error> {
        let mut start_scan = ChunkScan::new();
        let mut end_scan = ChunkScan::new();
        let mut pos = 0;
        // Program bytes `buf[span..pos]` not yet handed to the sink.
        let mut span: Option<usize> = None;
        while pos < buf.len() {
            let (le, complete) = match memchr(b'\n', &buf[pos..]) {
                Some(i) => (pos + i + 1, true),
                None => (buf.len(), false),
            };
            if !complete && le - pos < LINE_WINDOW {
                break;
            }
            let he = le.min(pos + LINE_WINDOW);
            let (ws, we) = self.wants();
            let sh = ws && start_scan.hit(&self.markers.start, self.markers.anchor, buf, pos, he);
            let eh = we && end_scan.hit(&self.markers.end, self.markers.anchor, buf, pos, he);
            let a = self.step(&buf[pos..he], sh, eh);
            if a.end_before || a.start_before || !a.include {
                if let Some(s) = span.take() {
                    sink.data(&buf[s..pos])?;
                }
            }
            self.open_close(a, sink)?;
            if a.include {
                self.note(&buf[pos..he]);
                if let Some(o) = self.open.as_mut() {
                    o.bytes += (le - pos) as u64;
                    o.last_line = self.line;
                }
                span.get_or_insert(pos);
            } else {
                self.summary.bytes_ignored += (le - pos) as u64;
            }
            pos = le;
            if complete {
                if a.end_after {
                    if let Some(s) = span.take() {
                        sink.data(&buf[s..pos])?;
                    }
                }
                self.line_done(a.end_after, sink)?;
            } else {
                self.continuation = Some(Continuation {
                    include: a.include,
                    end_after: a.end_after,
                });
            }
        }
        if let Some(s) = span {
            sink.data(&buf[s..pos])?;
        }
        self.carry.extend_from_slice(&buf[pos..]);
        Ok(())
    }

    fn open_close<S: ProgramSink>(&mut self, a: Action, sink: &mut S) -> Result<(), S::Error> {
        if a.end_before {
            self.end_program(true, sink)?;
        }
        if a.start_before {
            let index = self.summary.programs;
            self.summary.programs += 1;
            self.summary.start_found |= self.mode != Mode::EndOnly;
            self.open = Some(Open {
                index,
                first_line: self.line,
                ..Open::default()
            });
            sink.start(&ProgramStart {
                index,
                line: self.line,
            })?;
        }
        Ok(())
    }

    #[inline]
    fn note(&mut self, head: &[u8]) {
        if control_line::may_name(head) {
            if let Some(o) = self.open.as_mut() {
                o.name.note(head);
            }
        }
    }

    fn take_bytes<S: ProgramSink>(
        &mut self,
        bytes: &[u8],
        include: bool,
        sink: &mut S,
    ) -> Result<(), S::Error> {
        let line = self.line;
        match self.open.as_mut() {
            Some(o) if include => {
                o.bytes += bytes.len() as u64;
                o.last_line = line;
                sink.data(bytes)
            }
            _ => {
                self.summary.bytes_ignored += bytes.len() as u64;
                Ok(())
            }
        }
    }

    fn line_done<S: ProgramSink>(&mut self, end_after: bool, sink: &mut S) -> Result<(), S::Error> {
        let r = if end_after && self.open.is_some() {
            self.end_program(true, sink)
        } else {
            Ok(())
        };
        self.line += 1;
        r
    }

    fn end_program<S: ProgramSink>(
        &mut self,
        complete: bool,
        sink: &mut S,
    ) -> Result<(), S::Error> {
        let Some(o) = self.open.take() else {
            return Ok(());
        };
        if !complete {
            self.summary.cut_off += 1;
        }
        sink.end(ProgramEnd {
            index: o.index,
            first_line: o.first_line,
            last_line: o.last_line.max(o.first_line),
            bytes: o.bytes,
            complete,
            name: o.name,
        })
    }
}

/// A line of only white space and transfer padding (NUL, form feed, Ctrl-Z).
fn is_blank(head: &[u8]) -> bool {
    head.iter()
        .all(|&b| matches!(b, b' ' | b'\t' | b'\r' | b'\n' | 0x0C | 0x00 | 0x1A))
}
