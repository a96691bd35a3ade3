//! Decoder frames: one program level each (main program, subroutine, cycle, the stream), and
//! the incremental line readers behind them.
//!
//! A file frame holds its whole text in memory; a stream frame reads the channel's current
//! stream segment and pulls the next segment from the stream buffer only when it has decoded
//! the last line of the previous one (ISG FCT-C19 Data streaming §2.2: one read extracts all data present).

use std::sync::Arc;

use crate::source::loader::{self, PendingRead};
use crate::source::store::ProgramText;
use crate::source::stream::StreamBuffer;

use super::flow::Flow;
use super::labels::LabelIndex;
pub(crate) use super::line::LinePos;
pub use super::line::MAX_LINE_BYTES;
use super::line::{cut_line, cut_str_line, LineMeta, LineRead, LineTooLong};

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
    /// Main program, subroutine, cycle or local subroutine: which end blocks it allows.
    kind: FrameKind,
    /// Its text, the loader's read of it, or the stream.
    source: Source,
    /// The program's name.
    prog: Arc<str>,
    /// File frames: byte offset of the next line.
    pos: usize,
    /// File frames: lines read so far.
    line_no: u32,
    /// Its control flow: open structures, what is skipped, labels passed (`flow.rs`).
    flow: Flow,
    /// Inside `#COMMENT BEGIN` … `#COMMENT END`.
    comment_block: bool,
    /// Inside `#VAR` … `#ENDVAR`.
    var_block: bool,
    /// File frames: label → position and structural depth, built on the first jump.
    label_index: Option<Arc<LabelIndex>>,
}

impl Frame {
    /// Whether dropping this frame could cost a tick milliseconds: it holds the last
    /// reference to a large file text, a large label index, or many labels passed. The reader
    /// that owns it then lets the loader thread free it (`Reader::release`).
    pub(crate) fn is_heavy(&self) -> bool {
        matches!(&self.source, Source::File(p) if loader::is_heavy_text(&p.text))
            || self
                .label_index
                .as_ref()
                .is_some_and(|i| loader::is_heavy_table(i.len()))
            || self.flow.is_heavy()
    }

    pub(crate) fn new(kind: FrameKind, source: Source, prog: Arc<str>) -> Self {
        Frame {
            kind,
            source,
            prog,
            pos: 0,
            line_no: 0,
            flow: Flow::default(),
            comment_block: false,
            var_block: false,
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

    pub(crate) fn kind(&self) -> FrameKind {
        self.kind
    }

    /// The program's name.
    pub(crate) fn prog(&self) -> &Arc<str> {
        &self.prog
    }

    /// Lines read so far (file frames).
    pub(crate) fn line_no(&self) -> u32 {
        self.line_no
    }

    /// Its text, when it is a file whose text is there.
    pub(crate) fn file(&self) -> Option<&ProgramText> {
        match &self.source {
            Source::File(p) => Some(p),
            _ => None,
        }
    }

    /// The loader's read of its file, while it is not done.
    pub(crate) fn loading(&self) -> Option<&PendingRead> {
        match &self.source {
            Source::Loading(p) => Some(p),
            _ => None,
        }
    }

    /// The loader's read is done: the frame reads `text`.
    pub(crate) fn loaded(&mut self, text: ProgramText) {
        self.source = Source::File(text);
    }

    pub(crate) fn flow(&self) -> &Flow {
        &self.flow
    }

    pub(crate) fn flow_mut(&mut self) -> &mut Flow {
        &mut self.flow
    }

    /// Inside `#COMMENT BEGIN` … `#COMMENT END`.
    pub(crate) fn in_comment_block(&self) -> bool {
        self.comment_block
    }

    pub(crate) fn set_comment_block(&mut self, on: bool) {
        self.comment_block = on;
    }

    /// Inside `#VAR` … `#ENDVAR`.
    pub(crate) fn in_var_block(&self) -> bool {
        self.var_block
    }

    pub(crate) fn set_var_block(&mut self, on: bool) {
        self.var_block = on;
    }

    /// The label index of its text, once built.
    pub(crate) fn label_index(&self) -> Option<&Arc<LabelIndex>> {
        self.label_index.as_ref()
    }

    pub(crate) fn set_label_index(&mut self, index: Arc<LabelIndex>) {
        self.label_index = Some(index);
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
///
/// A segment is checked for UTF-8 once, when it is taken: a valid one is kept as `text` and
/// its lines are cut without checking each again; one that is not stays as bytes in `seg`,
/// each line read as [`cut_line`] reads a file's.
#[derive(Debug, Default)]
pub(crate) struct StreamReader {
    /// The current segment, when it is not UTF-8 (else empty: `text` holds it).
    seg: Vec<u8>,
    /// The current segment, when it is UTF-8 (else empty).
    text: String,
    /// Reused buffer the stream buffer empties into.
    scratch: Vec<u8>,
    pos: usize,
    /// Stream offset of the segment's first byte, bytes since stream start.
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
        self.text.clear();
        self.pos = 0;
        self.seg_base = 0;
        self.line_no = 0;
        self.segments = 0;
    }

    /// Length of the current segment, bytes (one of `seg` and `text` is empty).
    fn seg_len(&self) -> usize {
        self.seg.len() + self.text.len()
    }

    /// Bytes of the current segment not yet decoded.
    pub(crate) fn remaining(&self) -> usize {
        self.seg_len() - self.pos
    }

    /// The next complete line of the current segment into `out`: the offset after it.
    fn cut(&self, out: &mut String) -> Option<usize> {
        // A segment holds at most one buffer's worth of lines: never too long.
        let cut = if self.seg.is_empty() {
            cut_str_line(&self.text, self.pos, out, false)
        } else {
            cut_line(&self.seg, self.pos, out, false)
        };
        cut.ok().flatten()
    }

    /// Next line; pulls a new segment from `buf` only when the current one is used up.
    pub(crate) fn next_line(
        &mut self,
        buf: &mut StreamBuffer,
        out: &mut String,
        note: &mut Option<StreamNote>,
    ) -> LineRead {
        loop {
            if let Some(next) = self.cut(out) {
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
            // Back to bytes (no copy: the string's buffer), the new segment in, checked once.
            if self.seg.is_empty() {
                self.seg = std::mem::take(&mut self.text).into_bytes();
            }
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
            match String::from_utf8(std::mem::take(&mut self.seg)) {
                Ok(text) => self.text = text,
                Err(e) => self.seg = e.into_bytes(),
            }
            self.segments += 1;
            *note = Some(StreamNote::Segment { bytes });
        }
    }

    /// Drop the rest of the current segment (program end inside a segment, ISG FCT-C19 Data streaming §2.2).
    /// Data still in the stream buffer stays. Returns the bytes dropped.
    pub(crate) fn discard_rest(&mut self) -> usize {
        let n = self.remaining();
        self.seg_base += self.seg_len() as u64;
        self.seg.clear();
        self.text.clear();
        self.pos = 0;
        n
    }
}

#[cfg(test)]
mod tests {
    use super::{LineMeta, LineRead, StreamReader};
    use crate::source::stream::StreamBuffer;

    /// Every line of the stream with its number and offset, one segment per packet.
    fn lines(packets: &[&[u8]]) -> Vec<(String, LineMeta)> {
        let mut buf = StreamBuffer::new();
        let mut r = StreamReader::default();
        let mut out = Vec::new();
        let mut line = String::new();
        for p in packets {
            buf.write(p).unwrap();
            let mut note = None;
            while let LineRead::Line(meta) = r.next_line(&mut buf, &mut line, &mut note) {
                out.push((line.clone(), meta));
            }
        }
        out
    }

    #[test]
    fn stream_lines_keep_their_text_and_byte_offsets_whether_a_segment_is_utf8_or_not() {
        // A segment in UTF-8 (a comment with ä) and one with a byte that is not (0xE4, ä in
        // Latin-1): the same lines, numbers and byte offsets, the stray byte replaced.
        let got = lines(&[
            "N10 P1=1 (Maß ä)\r\nN20 P2=2\r\n".as_bytes(),
            b"N30 P3=3 (\xE4)\r\nN40 P4=4\r\n",
        ]);
        let want = [
            ("N10 P1=1 (Maß ä)", 1, 0),
            ("N20 P2=2", 2, 20),
            ("N30 P3=3 (\u{FFFD})", 3, 30),
            ("N40 P4=4", 4, 44),
        ];
        assert_eq!(got.len(), want.len(), "{got:?}");
        for ((text, meta), (w_text, w_line, w_offset)) in got.iter().zip(want) {
            assert_eq!(text, w_text);
            assert_eq!((meta.line, meta.offset), (w_line, w_offset));
        }
    }
}
