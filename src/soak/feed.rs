//! The soak's stream client: packets of random size at random intervals with random pauses,
//! from the generated program or a streamed file, remembering which lines the channel now owes
//! (written, not yet executed) so the checker can demand each exactly once and in order.

use std::collections::VecDeque;

use serde::Deserialize;

use super::generator::{Generator, MAX_LINE_BYTES};
use super::rng::SplitMix64;
use crate::source::packets;
use crate::source::stream::MAX_PROGRAM_STREAM_INPUT_SIZE;

/// How the client writes (scenario `[feeder]`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FeederSpec {
    /// Packet size range, bytes; at most 992 (the stream object's input size).
    pub packet_bytes: [usize; 2],
    /// Ticks between write attempts.
    pub(crate) interval_ticks: [u64; 2],
    /// Chance per accepted packet that a pause follows.
    pub(crate) pause_chance: f64,
    /// Pause length range, ticks.
    pub(crate) pause_ticks: [u64; 2],
}

impl Default for FeederSpec {
    fn default() -> Self {
        FeederSpec {
            packet_bytes: [256, MAX_PROGRAM_STREAM_INPUT_SIZE],
            interval_ticks: [1, 1],
            pause_chance: 0.0,
            pause_ticks: [0, 0],
        }
    }
}

impl FeederSpec {
    pub fn check(&self) -> Result<(), String> {
        let [p0, p1] = self.packet_bytes;
        if !(MAX_LINE_BYTES <= p0 && p0 <= p1 && p1 <= MAX_PROGRAM_STREAM_INPUT_SIZE) {
            return Err(format!(
                "[feeder] packet_bytes must be [low, high] with {MAX_LINE_BYTES} <= low <= high <= {MAX_PROGRAM_STREAM_INPUT_SIZE}"
            ));
        }
        let [i0, i1] = self.interval_ticks;
        if !(1 <= i0 && i0 <= i1 && i1 <= 1_000_000) {
            return Err(
                "[feeder] interval_ticks must be [low, high] with 1 <= low <= high <= 1000000"
                    .into(),
            );
        }
        if !(0.0..=1.0).contains(&self.pause_chance) {
            return Err("[feeder] pause_chance must be in [0, 1]".into());
        }
        let [q0, q1] = self.pause_ticks;
        if q0 > q1 || q1 > 10_000_000 {
            return Err(
                "[feeder] pause_ticks must be [low, high] with low <= high <= 10000000".into(),
            );
        }
        Ok(())
    }
}

/// A line the channel owes: written and accepted, not yet executed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Owed {
    /// Byte offset since stream start.
    pub offset: u64,
    /// Its N, when the source numbers its lines (the generator does).
    pub n: Option<u32>,
    /// Every line of the generator yields a block; a file's comment lines do not.
    pub(crate) must_run: bool,
}

/// Where the lines come from.
#[derive(Debug, Clone)]
pub enum Source {
    Generated(Generator),
    /// A file's lines (each CR LF ended, ≤ 96 bytes), streamed from the top each epoch.
    File {
        lines: Vec<Vec<u8>>,
        next: usize,
    },
}

impl Source {
    /// Cut a file into CR LF lines for streaming; a line longer than a packet's minimum is an
    /// error (the feeder never splits a line).
    pub fn file(text: &[u8]) -> Result<Source, String> {
        if text.is_empty() {
            return Err("the file is empty".into());
        }
        let mut lines = Vec::new();
        for (no, l) in packets::lines(text) {
            if l.len() + 2 > MAX_LINE_BYTES {
                return Err(format!(
                    "line {no}: longer than {} bytes",
                    MAX_LINE_BYTES - 2
                ));
            }
            let mut v = l.to_vec();
            v.extend_from_slice(b"\r\n");
            lines.push(v);
        }
        if lines.is_empty() {
            return Err("the file holds no lines".into());
        }
        Ok(Source::File { lines, next: 0 })
    }

    fn new_epoch(&mut self) {
        match self {
            Source::Generated(g) => g.new_epoch(),
            Source::File { next, .. } => *next = 0,
        }
    }

    /// Append the next line to `out`; `None` when a file is used up.
    fn next_line(&mut self, out: &mut Vec<u8>) -> Option<(Option<u32>, bool)> {
        match self {
            Source::Generated(g) => Some((Some(g.next_line(out)), true)),
            Source::File { lines, next } => {
                let l = lines.get(*next)?;
                *next += 1;
                out.extend_from_slice(l);
                Some((None, false))
            }
        }
    }
}

/// Feeder totals.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FeedCounters {
    pub writes_ok: u64,
    pub writes_rejected: u64,
    /// Attempts skipped by a forced-rejection fault.
    pub(crate) writes_skipped: u64,
    pub bytes: u64,
    pub lines: u64,
    pub pauses: u64,
}

/// The soak client of one channel.
#[derive(Debug)]
pub struct SoakFeeder {
    spec: FeederSpec,
    rng: SplitMix64,
    source: Source,
    /// The packet being offered (kept until accepted, so a retry sends the same bytes).
    packet: Vec<u8>,
    /// Lines of `packet`: (offset in packet, N, must run).
    packet_lines: Vec<(usize, Option<u32>, bool)>,
    /// Stream bytes accepted this epoch.
    epoch_bytes: u64,
    next_attempt: u64,
    owed: VecDeque<Owed>,
    counters: FeedCounters,
}

impl SoakFeeder {
    pub fn new(spec: FeederSpec, rng: SplitMix64, source: Source) -> Self {
        SoakFeeder {
            spec,
            rng,
            source,
            packet: Vec::with_capacity(MAX_PROGRAM_STREAM_INPUT_SIZE),
            packet_lines: Vec::new(),
            epoch_bytes: 0,
            next_attempt: 0,
            owed: VecDeque::new(),
            counters: FeedCounters::default(),
        }
    }

    /// A new stream after a reset or program end: what was written is no longer owed, the
    /// packet in hand is dropped, offsets and numbering start over.
    pub(crate) fn new_epoch(&mut self, tick: u64) {
        self.owed.clear();
        self.packet.clear();
        self.packet_lines.clear();
        self.epoch_bytes = 0;
        self.source.new_epoch();
        self.next_attempt = tick;
    }

    /// The packet to write at `tick`, if an attempt is due.
    pub fn poll(&mut self, tick: u64) -> Option<&[u8]> {
        if tick < self.next_attempt {
            return None;
        }
        if self.packet.is_empty() {
            self.fill();
        }
        (!self.packet.is_empty()).then_some(self.packet.as_slice())
    }

    /// A forced rejection: the attempt due now is not made.
    pub fn skip(&mut self, tick: u64) {
        if tick >= self.next_attempt {
            self.counters.writes_skipped += 1;
            self.next_attempt = tick + self.interval();
        }
    }

    fn interval(&mut self) -> u64 {
        let [a, b] = self.spec.interval_ticks;
        self.rng.range(a, b)
    }

    fn fill(&mut self) {
        let [lo, hi] = self.spec.packet_bytes;
        let target = self.rng.range(lo as u64, hi as u64) as usize;
        let mut line = Vec::with_capacity(MAX_LINE_BYTES);
        while self.packet.len() + MAX_LINE_BYTES <= target {
            line.clear();
            let Some((n, must_run)) = self.source.next_line(&mut line) else {
                break;
            };
            self.packet_lines.push((self.packet.len(), n, must_run));
            self.packet.extend_from_slice(&line);
        }
    }

    /// The outcome of the write of the packet `poll` offered at `tick`.
    pub fn result(&mut self, tick: u64, accepted: bool) {
        if accepted {
            self.counters.writes_ok += 1;
            self.counters.bytes += self.packet.len() as u64;
            self.counters.lines += self.packet_lines.len() as u64;
            for &(off, n, must_run) in &self.packet_lines {
                self.owed.push_back(Owed {
                    offset: self.epoch_bytes + off as u64,
                    n,
                    must_run,
                });
            }
            self.epoch_bytes += self.packet.len() as u64;
            self.packet.clear();
            self.packet_lines.clear();
        } else {
            self.counters.writes_rejected += 1;
        }
        let mut wait = self.interval();
        if accepted && self.rng.chance(self.spec.pause_chance) {
            let [a, b] = self.spec.pause_ticks;
            wait += self.rng.range(a, b);
            self.counters.pauses += 1;
        }
        self.next_attempt = tick + wait;
    }

    /// Lines written and not yet executed, oldest first.
    pub(crate) fn owed_mut(&mut self) -> &mut VecDeque<Owed> {
        &mut self.owed
    }

    pub fn counters(&self) -> &FeedCounters {
        &self.counters
    }

    /// A streamed file has been sent in full this epoch.
    pub fn exhausted(&self) -> bool {
        matches!(&self.source, Source::File { lines, next } if *next >= lines.len())
            && self.packet.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::soak::generator::ProgramSpec;

    fn feeder(spec: FeederSpec) -> SoakFeeder {
        let g = Generator::new(ProgramSpec::default(), SplitMix64::new(5));
        SoakFeeder::new(spec, SplitMix64::new(6), Source::Generated(g))
    }

    #[test]
    fn accepted_packets_are_owed_line_by_line_at_their_stream_offsets() {
        let mut f = feeder(FeederSpec::default());
        let mut stream = Vec::new();
        for t in 0..5 {
            let p = f.poll(t).unwrap().to_vec();
            assert!(p.len() <= MAX_PROGRAM_STREAM_INPUT_SIZE && p.ends_with(b"\r\n"));
            stream.extend_from_slice(&p);
            f.result(t, true);
        }
        let owed: Vec<Owed> = f.owed_mut().iter().copied().collect();
        assert_eq!(owed.len() as u64, f.counters().lines);
        for (i, o) in owed.iter().enumerate() {
            let line = &stream[o.offset as usize..];
            let want = format!("N{} ", i + 1);
            assert!(line.starts_with(want.as_bytes()), "line {i}");
            assert_eq!(o.n, Some(i as u32 + 1));
        }
        f.new_epoch(10);
        assert!(f.owed_mut().is_empty());
        assert!(f.poll(10).unwrap().starts_with(b"N1 G90"));
    }

    #[test]
    fn a_rejected_packet_is_offered_again_unchanged_and_not_owed() {
        let mut f = feeder(FeederSpec {
            interval_ticks: [3, 3],
            ..FeederSpec::default()
        });
        let first = f.poll(0).unwrap().to_vec();
        f.result(0, false);
        assert!(f.poll(1).is_none(), "next attempt 3 ticks later");
        assert_eq!(f.poll(3).unwrap(), first.as_slice());
        assert!(f.owed_mut().is_empty());
        f.skip(6);
        assert_eq!(f.counters().writes_skipped, 1);
        assert!(f.poll(7).is_none());
    }

    #[test]
    fn files_are_cut_into_crlf_lines_and_long_lines_refused() {
        let Source::File { lines, .. } = Source::file(b"N1 X1\r\nN2 X2\n(c)\n").unwrap() else {
            panic!()
        };
        assert_eq!(
            lines,
            [
                b"N1 X1\r\n".to_vec(),
                b"N2 X2\r\n".to_vec(),
                b"(c)\r\n".to_vec()
            ]
        );
        let long = vec![b'X'; 200];
        assert!(Source::file(&long).is_err());
        assert!(Source::file(b"").is_err());
    }
}
