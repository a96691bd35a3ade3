//! The built-in stream client: writes a file into a channel's stream interface as a real
//! client would, one packet attempt every few ticks, retrying a rejected packet.
//!
//! The file is cut into packets once, up front: whole lines only, LF normalised to CR LF, at
//! most `packet_max` bytes each. A line holding only a form feed (0x0C), optionally followed by
//! a tick count (`"\x0c 50"`), ends the current packet and pauses the feeder that many ticks;
//! the form-feed line itself is not sent. In raw mode the bytes go out exactly as they are,
//! cut every `packet_max` bytes, to provoke the channel's error handling.

use std::ops::Range;

use thiserror::Error;

use crate::source::packets::{is_packed_form, lines, LineTooLong, Packer};

/// Why a file cannot be fed.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum FeederError {
    /// A packet size of 0 can carry nothing.
    #[error("packet size must be at least 1 byte")]
    ZeroPacket,
    /// One line (with its CR LF) is longer than a packet; the feeder never splits a line.
    #[error(transparent)]
    LineTooLong(#[from] LineTooLong),
    /// A form-feed line whose rest is not a tick count.
    #[error("line {line}: a form-feed line may only hold a number of ticks to pause")]
    BadPause { line: usize },
}

/// One step of the feed: a packet to write or a pause in ticks.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Item {
    Packet(Range<usize>),
    Pause(u64),
}

/// Feeder totals.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FeederCounters {
    pub writes_ok: u64,
    pub writes_rejected: u64,
    /// Bytes accepted.
    pub bytes: u64,
}

/// The built-in feeder. Call [`Feeder::poll`] every tick; when it offers a packet, write it and
/// tell the outcome with [`Feeder::result`].
#[derive(Debug, Clone)]
pub struct Feeder {
    /// The text as it will be sent (normalised unless raw).
    data: Vec<u8>,
    items: Vec<Item>,
    /// Index of the next packet to send in `items` (pauses before it already applied).
    cursor: usize,
    every_ticks: u64,
    /// Ticks of pause before the first attempt.
    initial_pause: u64,
    /// The tick of the next attempt; `None` until the first poll fixes the time base.
    next_attempt: Option<u64>,
    /// The tick the outstanding packet was offered at.
    offered_at: Option<u64>,
    counters: FeederCounters,
}

impl Feeder {
    /// Cut `text` into packets of at most `packet_max` bytes, one attempt every `every_ticks`
    /// ticks (0 is taken as 1).
    pub fn new(
        text: Vec<u8>,
        packet_max: usize,
        every_ticks: u64,
        raw: bool,
    ) -> Result<Self, FeederError> {
        if packet_max == 0 {
            return Err(FeederError::ZeroPacket);
        }
        let (data, items) = if raw {
            let items = (0..text.len())
                .step_by(packet_max)
                .map(|s| Item::Packet(s..(s + packet_max).min(text.len())))
                .collect();
            (text, items)
        } else {
            cut_lines(text, packet_max)?
        };
        let mut f = Feeder {
            data,
            items,
            cursor: 0,
            every_ticks: every_ticks.max(1),
            initial_pause: 0,
            next_attempt: None,
            offered_at: None,
            counters: FeederCounters::default(),
        };
        f.initial_pause = f.skip_pauses();
        Ok(f)
    }

    /// Step over pauses at the cursor, returning their total ticks.
    fn skip_pauses(&mut self) -> u64 {
        let mut total = 0u64;
        while let Some(Item::Pause(n)) = self.items.get(self.cursor) {
            total = total.saturating_add(*n);
            self.cursor += 1;
        }
        total
    }

    /// The packet to attempt at tick `tick_index`, if it is time for one and any is left.
    pub fn poll(&mut self, tick_index: u64) -> Option<&[u8]> {
        let Some(Item::Packet(range)) = self.items.get(self.cursor) else {
            return None;
        };
        let next = *self
            .next_attempt
            .get_or_insert(tick_index.saturating_add(self.initial_pause));
        if tick_index < next {
            return None;
        }
        self.offered_at = Some(tick_index);
        Some(&self.data[range.clone()])
    }

    /// The outcome of the write of the packet last offered by [`Feeder::poll`]. Accepted: move
    /// on (through any pause after it). Rejected: offer the same packet at the next attempt.
    /// Without an outstanding packet this does nothing.
    pub fn result(&mut self, accepted: bool) {
        let Some(at) = self.offered_at.take() else {
            return;
        };
        let Some(Item::Packet(range)) = self.items.get(self.cursor) else {
            return;
        };
        let mut wait = self.every_ticks;
        if accepted {
            self.counters.writes_ok += 1;
            self.counters.bytes += range.len() as u64;
            self.cursor += 1;
            wait = wait.saturating_add(self.skip_pauses());
        } else {
            self.counters.writes_rejected += 1;
        }
        self.next_attempt = Some(at.saturating_add(wait));
    }

    /// Everything has been accepted.
    pub fn done(&self) -> bool {
        !matches!(self.items.get(self.cursor), Some(Item::Packet(_)))
    }

    /// Start over from the first packet (the bench feeds one text round and round). Counters
    /// keep counting.
    pub fn rewind(&mut self) {
        self.cursor = 0;
        self.offered_at = None;
        self.next_attempt = None;
        self.initial_pause = self.skip_pauses();
    }

    pub fn counters(&self) -> &FeederCounters {
        &self.counters
    }

    /// Packets the text was cut into.
    pub fn packets(&self) -> usize {
        self.items
            .iter()
            .filter(|i| matches!(i, Item::Packet(_)))
            .count()
    }

    /// Bytes that will be sent in all (after normalisation).
    pub fn total_bytes(&self) -> usize {
        self.items
            .iter()
            .map(|i| match i {
                Item::Packet(r) => r.len(),
                Item::Pause(_) => 0,
            })
            .sum()
    }
}

/// The form feed that starts a pause line (module header).
const PAUSE: u8 = 0x0c;

/// Normalise `text` to CR LF lines and cut it into packets of whole lines and pauses
/// (form-feed lines, see the module header). A text already in CR LF lines without pauses is
/// kept as it is, not copied: a streamed file is held once, not twice.
fn cut_lines(text: Vec<u8>, packet_max: usize) -> Result<(Vec<u8>, Vec<Item>), FeederError> {
    if is_packed_form(&text, PAUSE) {
        let mut packer = Packer::counting(packet_max);
        let mut items = Vec::new();
        for (line_no, content) in lines(&text) {
            items.extend(packer.push(line_no, content)?.map(Item::Packet));
        }
        items.extend(packer.close().map(Item::Packet));
        return Ok((text, items));
    }
    let mut packer = Packer::new(packet_max, text.len());
    let mut items = Vec::new();
    for (line_no, content) in lines(&text) {
        if let Some(after) = content.strip_prefix(&[PAUSE]) {
            let arg = std::str::from_utf8(after)
                .map_err(|_| FeederError::BadPause { line: line_no })?
                .trim();
            let ticks = if arg.is_empty() {
                0
            } else {
                arg.parse::<u64>()
                    .map_err(|_| FeederError::BadPause { line: line_no })?
            };
            items.extend(packer.close().map(Item::Packet));
            items.push(Item::Pause(ticks));
            continue;
        }
        items.extend(packer.push(line_no, content)?.map(Item::Packet));
    }
    items.extend(packer.close().map(Item::Packet));
    Ok((packer.into_data(), items))
}
