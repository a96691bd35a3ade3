//! One line of NC text: where it starts, how it is cut from a program text or a stream
//! segment, and the bound on its length.

use super::error::DecodeError;
use crate::lang::block::Block;

/// Where a line starts, so loops and backward jumps in files can return to it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct LinePos {
    /// Byte offset of the line's first byte.
    pub(crate) pos: usize,
    /// Number of lines before it (the line's own number is `line_no + 1`).
    pub(crate) line_no: u32,
}

/// One line handed to the interpreter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct LineMeta {
    /// 1-based line number in its program (stream: since stream start).
    pub(crate) line: u32,
    /// Byte offset of the line (stream: since stream start).
    pub(crate) offset: u64,
}

/// A parsed block with its text and where its line stands: what a queued block's
/// `BlockInfo` is made from.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BlockAt<'a> {
    pub(crate) block: &'a Block,
    pub(crate) text: &'a str,
    pub(crate) meta: LineMeta,
}

/// The result of asking a frame for its next line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LineRead {
    Line(LineMeta),
    /// A stream frame with no complete line available yet: try again next tick.
    Pending,
    /// A file frame at its end.
    Eof,
    /// A file frame's next line is longer than [`MAX_LINE_BYTES`].
    TooLong(LineMeta),
}

/// Longest line of a program file, bytes. A block is at most `MAX_BLOCK_CHARS` (4000)
/// characters, so no useful line comes near it; the bound keeps the search for a line end, and
/// the copy of the line, from growing with a file that has no line ends.
pub const MAX_LINE_BYTES: usize = 16 * 1024;

/// A line longer than [`MAX_LINE_BYTES`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct LineTooLong;

impl LineTooLong {
    /// The error at 1-based line `line` of a file.
    pub(crate) fn error(self, line: u32) -> DecodeError {
        DecodeError::new(
            crate::lang::codes::SYNTAX,
            format!("line {line} is longer than {MAX_LINE_BYTES} bytes"),
        )
    }
}

/// Where the line starting at `pos` of `text` ends: the end of its text (without its line
/// end) and the offset after its line end, or `None` when no complete line is there. Looks at
/// most [`MAX_LINE_BYTES`] bytes ahead.
fn line_end(
    text: &[u8],
    pos: usize,
    at_eof_ok: bool,
) -> Result<Option<(usize, usize)>, LineTooLong> {
    let Some(rest) = text.get(pos..) else {
        return Ok(None);
    };
    if rest.is_empty() {
        return Ok(None);
    }
    let window = &rest[..rest.len().min(MAX_LINE_BYTES + 1)];
    let (len, next) = match memchr::memchr(b'\n', window) {
        Some(i) => (i, pos + i + 1),
        None if window.len() > MAX_LINE_BYTES => return Err(LineTooLong),
        None if at_eof_ok => (rest.len(), text.len()),
        None => return Ok(None),
    };
    let len = if rest[..len].ends_with(b"\r") {
        len - 1
    } else {
        len
    };
    Ok(Some((pos + len, next)))
}

/// Copy the line starting at `pos` of `text` into `out` (without its line end). Returns the
/// offset after the line end, or `None` when no complete line is there. Looks at most
/// [`MAX_LINE_BYTES`] bytes ahead.
pub(crate) fn cut_line(
    text: &[u8],
    pos: usize,
    out: &mut String,
    at_eof_ok: bool,
) -> Result<Option<usize>, LineTooLong> {
    let Some((end, next)) = line_end(text, pos, at_eof_ok)? else {
        return Ok(None);
    };
    let line = &text[pos..end];
    out.clear();
    match std::str::from_utf8(line) {
        Ok(s) => out.push_str(s),
        Err(_) => out.push_str(&String::from_utf8_lossy(line)),
    }
    Ok(Some(next))
}

/// [`cut_line`] over a text already known to be UTF-8 (a stream segment checked once when it
/// was taken): the line is copied without checking it again. A line end is ASCII, so it never
/// falls inside a character and the cut is a character boundary.
pub(crate) fn cut_str_line(
    text: &str,
    pos: usize,
    out: &mut String,
    at_eof_ok: bool,
) -> Result<Option<usize>, LineTooLong> {
    let Some((end, next)) = line_end(text.as_bytes(), pos, at_eof_ok)? else {
        return Ok(None);
    };
    out.clear();
    out.push_str(text.get(pos..end).unwrap_or_default());
    Ok(Some(next))
}
