//! The data-streaming interface of one channel: a 4094-byte buffer that clients write whole
//! CR LF-terminated NC lines into and the decoder empties one program segment at a time.
//!
//! Facts from ISG FCT-C19 Data streaming: the buffer holds
//! [`MAX_PROGRAM_STREAM_SIZE`] bytes, one write carries at most
//! [`MAX_PROGRAM_STREAM_INPUT_SIZE`] bytes, packets queue in write order, and one read extracts
//! *all* data present as one segment. A write is accepted whole or rejected whole.
//!
//! The buffer only validates and stores; raising warning 11012 or error 21476 in the channel is
//! the caller's job, told apart by [`StreamWriteError`].

use std::sync::Arc;

use thiserror::Error;

/// Capacity of the stream buffer in bytes (`MAX_PROGRAM_STREAM_SIZE`).
pub const MAX_PROGRAM_STREAM_SIZE: usize = 4094;
/// Largest single write in bytes (`MAX_PROGRAM_STREAM_INPUT_SIZE`).
pub const MAX_PROGRAM_STREAM_INPUT_SIZE: usize = 992;

/// ISG error number for a stream line without a correct CR LF end marker.
pub use crate::lang::codes::NO_LINE_END as ERR_NO_LINE_END;
/// ISG warning number for a write the channel cannot accept now ("Error writing the object").
pub use crate::lang::codes::WRITE_REJECTED as WARN_WRITE_REJECTED;

/// Why a write was refused. In every case the buffer is left exactly as it was.
///
/// Validation runs in a fixed order so a packet that is wrong in several ways always gets the
/// same answer: size first (`Empty`, `TooLarge`), then line ends (`NoLineEnd`), then room
/// (`Full`). So a malformed packet raises 21476 even when the buffer is full: the client is
/// wrong whatever the fill level, and retrying it would never help.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum StreamWriteError {
    /// A write with no bytes: a writer mistake, no channel error.
    #[error("empty stream write")]
    Empty,
    /// More than 992 bytes in one write: a writer mistake, no channel error.
    #[error("stream write of {len} bytes exceeds the maximum of {MAX_PROGRAM_STREAM_INPUT_SIZE}")]
    TooLarge { len: usize },
    /// A LF without CR before it, a CR without LF after it, or a packet not ending in CR LF.
    /// `offset` is the byte in the packet where the line end is wrong (the packet length when
    /// the final CR LF is missing). The channel raises error 21476 and aborts streaming.
    #[error("error {ERR_NO_LINE_END}: streaming data does not contain a correct line end marker (packet byte {offset})")]
    NoLineEnd { offset: usize },
    /// The packet does not fit into the free room; the channel raises warning 11012 and the
    /// writer retries in a later cycle.
    #[error("warning {WARN_WRITE_REJECTED}: error writing the object (stream buffer has {free} bytes free)")]
    Full { free: usize },
}

impl StreamWriteError {
    /// The ISG number the channel raises for this rejection, if any (writer mistakes have none).
    pub fn isg_code(&self) -> Option<u32> {
        match self {
            StreamWriteError::Empty | StreamWriteError::TooLarge { .. } => None,
            StreamWriteError::NoLineEnd { .. } => Some(ERR_NO_LINE_END),
            StreamWriteError::Full { .. } => Some(WARN_WRITE_REJECTED),
        }
    }
}

/// What passed through the buffer, for the report and the `write` events.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StreamCounters {
    /// Writes accepted.
    pub writes_ok: u64,
    /// Writes refused because the buffer had no room (11012).
    pub writes_full: u64,
    /// Writes refused as malformed: empty, too large or without correct line ends.
    pub writes_invalid: u64,
    /// Bytes accepted.
    pub(crate) bytes_written: u64,
    /// Bytes handed out in segments.
    pub bytes_taken: u64,
    /// Segments handed out (takes that found data).
    pub segments: u64,
}

impl StreamCounters {
    /// All refused writes, whatever the reason.
    pub fn writes_rejected(&self) -> u64 {
        self.writes_full + self.writes_invalid
    }
}

/// The stream buffer of one channel.
///
/// Storage is one `Vec` with the full capacity reserved at construction; since a take moves
/// everything out at once there is never a wrapped tail, so a ring would buy nothing. Neither
/// `write` nor `take_segment` allocates.
#[derive(Debug, Clone)]
pub struct StreamBuffer {
    data: Vec<u8>,
    counters: StreamCounters,
    /// The last shared packet that passed the size and line-end checks and found no room. A
    /// client offers the same shared packet again until it fits (`machine::Offer`), and a
    /// full buffer refuses most attempts: its checks are not run again. Holding the `Arc`
    /// keeps those bytes alive and unchanged, so the same pointer means the same bytes.
    checked: Option<Arc<[u8]>>,
}

impl Default for StreamBuffer {
    fn default() -> Self {
        Self::new()
    }
}

impl StreamBuffer {
    /// An empty buffer with its 4094 bytes reserved.
    pub fn new() -> Self {
        StreamBuffer {
            data: Vec::with_capacity(MAX_PROGRAM_STREAM_SIZE),
            counters: StreamCounters::default(),
            checked: None,
        }
    }

    /// Offer one packet. Accepted whole or refused whole; see [`StreamWriteError`] for the
    /// order in which the checks run.
    pub fn write(&mut self, packet: &[u8]) -> Result<(), StreamWriteError> {
        let checked = check_packet(packet).and_then(|()| self.room_for(packet));
        self.count(packet, checked)
    }

    /// [`StreamBuffer::write`] of a shared packet, with the same answers. A packet offered
    /// again after it found no room (the same allocation) only has its room checked: its
    /// size and line ends passed before and cannot have changed.
    pub fn write_shared(&mut self, packet: &Arc<[u8]>) -> Result<(), StreamWriteError> {
        let known = self
            .checked
            .as_ref()
            .is_some_and(|c| Arc::ptr_eq(c, packet));
        let checked = if known {
            self.room_for(packet)
        } else {
            check_packet(packet).and_then(|()| self.room_for(packet))
        };
        if matches!(checked, Err(StreamWriteError::Full { .. })) {
            if !known {
                self.checked = Some(Arc::clone(packet));
            }
        } else {
            self.checked = None;
        }
        self.count(packet, checked)
    }

    /// `Full` when `packet` does not fit into the free room.
    fn room_for(&self, packet: &[u8]) -> Result<(), StreamWriteError> {
        let free = self.free();
        if packet.len() > free {
            Err(StreamWriteError::Full { free })
        } else {
            Ok(())
        }
    }

    /// Store a packet that passed its checks, count the outcome either way.
    fn count(
        &mut self,
        packet: &[u8],
        checked: Result<(), StreamWriteError>,
    ) -> Result<(), StreamWriteError> {
        match checked {
            Ok(()) => {
                self.data.extend_from_slice(packet);
                self.counters.writes_ok += 1;
                self.counters.bytes_written += packet.len() as u64;
                Ok(())
            }
            Err(e) => {
                match e {
                    StreamWriteError::Full { .. } => self.counters.writes_full += 1,
                    _ => self.counters.writes_invalid += 1,
                }
                Err(e)
            }
        }
    }

    /// Move all buffered data into `out` (cleared first) as one segment and return its length.
    ///
    /// `out` keeps its allocation between calls, so a caller that reuses one `Vec` of at least
    /// 4094 bytes' capacity never allocates here.
    pub fn take_segment(&mut self, out: &mut Vec<u8>) -> usize {
        out.clear();
        out.extend_from_slice(&self.data);
        let n = self.data.len();
        self.data.clear();
        if n > 0 {
            self.counters.segments += 1;
            self.counters.bytes_taken += n as u64;
        }
        n
    }

    /// Bytes waiting to be read.
    pub fn used(&self) -> usize {
        self.data.len()
    }

    /// Bytes a write may still add.
    pub fn free(&self) -> usize {
        MAX_PROGRAM_STREAM_SIZE - self.data.len()
    }

    /// True when nothing is buffered.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Drop all buffered data (NC reset). Counters are kept: they describe the whole run.
    /// Returns the number of bytes dropped, for the `discard` event.
    pub fn clear(&mut self) -> usize {
        let n = self.data.len();
        self.data.clear();
        n
    }

    /// What passed through so far.
    pub fn counters(&self) -> &StreamCounters {
        &self.counters
    }
}

/// Size and line-end checks of one packet, independent of the buffer's fill level.
fn check_packet(packet: &[u8]) -> Result<(), StreamWriteError> {
    if packet.is_empty() {
        return Err(StreamWriteError::Empty);
    }
    if packet.len() > MAX_PROGRAM_STREAM_INPUT_SIZE {
        return Err(StreamWriteError::TooLarge { len: packet.len() });
    }
    // Jump from line end to line end (memchr's SIMD search): every write of every channel
    // passes here, a byte-at-a-time loop was the largest single cost of a streamed program.
    let mut i = 0;
    while let Some(k) = memchr::memchr2(b'\r', b'\n', &packet[i..]) {
        let at = i + k;
        if packet[at] == b'\n' || packet.get(at + 1) != Some(&b'\n') {
            // A bare LF, or a CR not followed by LF (a CR as the very last byte means the
            // final LF is missing).
            return Err(StreamWriteError::NoLineEnd { offset: at });
        }
        i = at + 2;
    }
    if !packet.ends_with(b"\r\n") {
        return Err(StreamWriteError::NoLineEnd {
            offset: packet.len(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepts_lines_and_hands_them_out_as_one_segment() {
        let mut b = StreamBuffer::new();
        b.write(b"N10 X1\r\n").unwrap();
        b.write(b"N20 X2\r\nN30 X3\r\n").unwrap();
        assert_eq!(b.used(), 24);
        let mut out = Vec::new();
        assert_eq!(b.take_segment(&mut out), 24);
        assert_eq!(out, b"N10 X1\r\nN20 X2\r\nN30 X3\r\n");
        assert_eq!(b.used(), 0);
        assert_eq!(b.take_segment(&mut out), 0);
        assert!(out.is_empty());
        assert_eq!(b.counters().segments, 1);
    }

    #[test]
    fn a_shared_packet_offered_again_gets_the_same_answers() {
        let mut b = StreamBuffer::new();
        let big: Arc<[u8]> = Arc::from(
            vec![b'X'; 990]
                .into_iter()
                .chain(*b"\r\n")
                .collect::<Vec<u8>>(),
        );
        for _ in 0..4 {
            b.write_shared(&big).unwrap();
        }
        assert_eq!(
            b.write_shared(&big),
            Err(StreamWriteError::Full { free: 126 })
        );
        assert_eq!(
            b.write_shared(&big),
            Err(StreamWriteError::Full { free: 126 })
        );
        // A malformed packet is malformed whatever the fill level, on every attempt.
        let bad: Arc<[u8]> = Arc::from(&b"N10\nN20\r\n"[..]);
        for _ in 0..2 {
            assert_eq!(
                b.write_shared(&bad),
                Err(StreamWriteError::NoLineEnd { offset: 3 })
            );
        }
        let mut out = Vec::new();
        b.take_segment(&mut out);
        b.write_shared(&big).unwrap();
        assert_eq!(b.counters().writes_full, 2);
        assert_eq!(b.counters().writes_invalid, 2);
        assert_eq!(b.counters().writes_ok, 5);
    }

    #[test]
    fn line_end_offsets() {
        assert_eq!(
            check_packet(b"N10\nN20\r\n"),
            Err(StreamWriteError::NoLineEnd { offset: 3 })
        );
        assert_eq!(
            check_packet(b"N10\rN20\r\n"),
            Err(StreamWriteError::NoLineEnd { offset: 3 })
        );
        assert_eq!(
            check_packet(b"N10\r\nN20"),
            Err(StreamWriteError::NoLineEnd { offset: 8 })
        );
        assert_eq!(
            check_packet(b"N10\r"),
            Err(StreamWriteError::NoLineEnd { offset: 3 })
        );
        assert_eq!(check_packet(b"\r\n"), Ok(()));
    }
}
