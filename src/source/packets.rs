//! NC text as a stream client writes it: lines ended by CR LF, sent in packets of whole lines
//! of at most a given size (ISG FCT-C19 Data streaming: one write carries at most
//! `MAX_PROGRAM_STREAM_INPUT_SIZE` = 992 bytes; a line is never split across writes).
//! The one packetiser of the crate: the built-in feeder, `ncchannel stream` and the soak's
//! feeder all cut text here.

use std::ops::Range;

/// A line longer than one packet can carry cannot be streamed as a whole line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line} is {bytes} bytes with CR LF; one packet carries at most {max}")]
pub struct LineTooLong {
    /// 1-based line number in the text.
    pub line: usize,
    /// The line's length with CR LF, bytes.
    pub bytes: usize,
    /// The packet size, bytes.
    pub max: usize,
}

/// The lines of `text`, numbered from 1, without their line end (LF or CR LF). A last line
/// without a line end is a line (a file without a final newline is common); a final line end
/// opens no empty line after it. A lone CR inside a line is kept (the channel then reports
/// 21476, as it would for any client sending it).
pub fn lines(text: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    let body = text.strip_suffix(b"\n").unwrap_or(text);
    // Line ends found by memchr (SIMD): files of millions of lines are cut here.
    let ends = memchr::memchr_iter(b'\n', body).chain(std::iter::once(body.len()));
    let mut start = 0;
    ends.take(if text.is_empty() { 0 } else { usize::MAX })
        .enumerate()
        .map(move |(i, end)| {
            let l = &body[start..end];
            start = end + 1;
            (i + 1, l.strip_suffix(b"\r").unwrap_or(l))
        })
}

/// Packs CR LF lines into packets of at most `max` bytes, all in one buffer: a packet is a
/// range of [`Packer::data`]. A counting packer ([`Packer::counting`]) copies nothing: for a
/// text already in CR LF lines, whose ranges are the text's own.
#[derive(Debug)]
pub(crate) struct Packer {
    data: Vec<u8>,
    /// Bytes packed so far (`data.len()` unless counting).
    end: usize,
    /// Start of the open packet.
    start: usize,
    max: usize,
    copy: bool,
}

impl Packer {
    /// `capacity`: the expected total, bytes (the text's length is a good guess).
    pub fn new(max: usize, capacity: usize) -> Self {
        Packer {
            data: Vec::with_capacity(capacity + capacity / 16 + 2),
            end: 0,
            start: 0,
            max,
            copy: true,
        }
    }

    /// A packer that only counts: its ranges point into a text that is its own output.
    pub fn counting(max: usize) -> Self {
        Packer {
            data: Vec::new(),
            end: 0,
            start: 0,
            max,
            copy: false,
        }
    }

    /// Add line `line_no` (its content without line end). Returns the packet the line closed
    /// because it did not fit into it.
    pub fn push(
        &mut self,
        line_no: usize,
        content: &[u8],
    ) -> Result<Option<Range<usize>>, LineTooLong> {
        let len = content.len() + 2;
        if len > self.max {
            return Err(LineTooLong {
                line: line_no,
                bytes: len,
                max: self.max,
            });
        }
        let closed = if self.end + len - self.start > self.max {
            self.close()
        } else {
            None
        };
        if self.copy {
            self.data.extend_from_slice(content);
            self.data.extend_from_slice(b"\r\n");
        }
        self.end += len;
        Ok(closed)
    }

    /// Close the open packet; `None` when it holds nothing.
    pub fn close(&mut self) -> Option<Range<usize>> {
        let end = self.end;
        let r = (end > self.start).then_some(self.start..end);
        self.start = end;
        r
    }

    /// The normalised text all packets point into (empty for a counting packer).
    pub fn data(&self) -> &[u8] {
        &self.data
    }

    pub(crate) fn into_data(self) -> Vec<u8> {
        self.data
    }
}

/// True when `text` is already what packing makes of it: every line ended by CR LF (the last
/// one too) and none starting with `skip` (a byte whose lines packing drops, the feeder's
/// form feed). Such a text can be packed by a counting [`Packer`] without a copy.
pub(crate) fn is_packed_form(text: &[u8], skip: u8) -> bool {
    if text.is_empty() {
        return true;
    }
    if !text.ends_with(b"\n") || text[0] == skip {
        return false;
    }
    memchr::memchr_iter(b'\n', text)
        .all(|at| at > 0 && text[at - 1] == b'\r' && text.get(at + 1).is_none_or(|&b| b != skip))
}

/// Cut `text` into packets of whole CR LF lines of at most `max` bytes each.
pub fn packets(text: &[u8], max: usize) -> Result<Vec<Vec<u8>>, LineTooLong> {
    let mut packer = Packer::new(max, text.len());
    let mut ranges = Vec::new();
    for (no, line) in lines(text) {
        ranges.extend(packer.push(no, line)?);
    }
    ranges.extend(packer.close());
    Ok(ranges
        .into_iter()
        .map(|r| packer.data()[r].to_vec())
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_take_lf_and_crlf_and_a_missing_final_line_end() {
        let l: Vec<(usize, &[u8])> = lines(b"a\r\nb\nc").collect();
        assert_eq!(l, vec![(1, &b"a"[..]), (2, b"b"), (3, b"c")]);
        assert_eq!(lines(b"a\n").count(), 1);
        assert_eq!(lines(b"").count(), 0);
        assert_eq!(lines(b"\n\n").count(), 2);
        assert_eq!(lines(b"\n").count(), 1);
    }

    #[test]
    fn packets_hold_whole_crlf_lines() {
        let p = packets(b"N10 X1\nN20 Y2\r\nN30 Z3", 992).unwrap();
        assert_eq!(p, vec![b"N10 X1\r\nN20 Y2\r\nN30 Z3\r\n".to_vec()]);
        let p = packets(b"AAAA\nBBBB\nCCCC\n", 12).unwrap();
        assert_eq!(p, vec![b"AAAA\r\nBBBB\r\n".to_vec(), b"CCCC\r\n".to_vec()]);
        assert_eq!(packets(b"", 992).unwrap(), Vec::<Vec<u8>>::new());
        assert_eq!(packets(b"\n\n", 992).unwrap(), vec![b"\r\n\r\n".to_vec()]);
        assert!(is_packed_form(b"A\r\nB\r\n", 0x0c));
        assert!(is_packed_form(b"", 0x0c));
        assert!(!is_packed_form(b"A\r\nB\n", 0x0c));
        assert!(!is_packed_form(b"A\r\nB", 0x0c));
        assert!(!is_packed_form(b"A\r\n\x0c 5\r\n", 0x0c));
        assert!(!is_packed_form(b"\n", 0x0c));
        let e = packets(b"ok\nTOO LONG LINE\n", 8).unwrap_err();
        assert_eq!(
            e,
            LineTooLong {
                line: 2,
                bytes: 15,
                max: 8
            }
        );
    }
}
