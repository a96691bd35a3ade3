//! The backplot's path and the streamed lines as the feed keeps and sends them: the channel's
//! path since its program started (from the machine's record, `machine::live`), kept whole
//! for pages that connect late within [`MAX_PATH_POINTS`], and the stream text around the
//! executing block cut into lines.

use serde::Serialize;

use crate::machine::live::{simplify, LiveDrain, PathPoint, StreamText, PATH_TOLERANCE_MM};

/// Points of one channel's path the feed keeps at most. When the path reaches it, the
/// whole path is decimated again with twice the tolerance (off the runtime's thread), so a
/// long program keeps its whole outline at a coarser tolerance rather than losing its start:
/// 200 000 points are some 6 MB of JSON for a page that connects.
pub const MAX_PATH_POINTS: usize = 200_000;

/// Streamed lines a `stream` event lists at most: a few executed, the rest ahead.
pub const MAX_STREAM_LINES: usize = 400;
/// Executed lines kept before the executing one.
const LINES_BEHIND: usize = 40;

/// A point as the page reads it: `[x, y, z, rapid]` (mm; rapid 1 for G0).
type WirePoint = (f64, f64, f64, u8);

fn wire(p: &PathPoint) -> WirePoint {
    (p.xyz_mm[0], p.xyz_mm[1], p.xyz_mm[2], u8::from(p.rapid))
}

/// One channel's path since its program started.
#[derive(Debug, Default)]
pub struct PathStore {
    program_starts: u64,
    points: Vec<PathPoint>,
    tail: Option<PathPoint>,
    tolerance_mm: f64,
    lost: u64,
    soft_limits_mm: [Option<(f64, f64)>; 3],
}

/// The `path` event: new points of a channel's path, or (`reset`) the whole path.
#[derive(Debug, Serialize)]
pub struct PathUpdate {
    pub ch: u16,
    /// The points replace what the page has (a new program, a page that just connected,
    /// or the path decimated again).
    pub reset: bool,
    pub program_starts: u64,
    pub points: Vec<WirePoint>,
    /// Where the axes are now, drawn to but not kept.
    pub tail: Option<WirePoint>,
    /// The largest distance of the interpolated path from the drawn one, mm.
    pub tolerance_mm: f64,
    /// Points that did not fit between two drains.
    pub lost: u64,
    pub soft_limits_mm: [Option<(f64, f64)>; 3],
}

impl PathStore {
    /// Add a drain; the update for the pages, when something changed.
    pub fn extend(&mut self, ch: u16, drain: &mut LiveDrain) -> Option<PathUpdate> {
        let mut reset = false;
        if drain.program_starts != self.program_starts {
            self.program_starts = drain.program_starts;
            self.points.clear();
            self.tolerance_mm = PATH_TOLERANCE_MM;
            reset = true;
        }
        if self.tolerance_mm == 0.0 {
            self.tolerance_mm = PATH_TOLERANCE_MM;
        }
        self.soft_limits_mm = drain.soft_limits_mm;
        self.lost = drain.points_lost;
        let fresh = std::mem::take(&mut drain.points);
        let moved = self.tail != drain.tail;
        self.tail = drain.tail;
        if fresh.is_empty() && !moved && !reset {
            return None;
        }
        self.points.extend_from_slice(&fresh);
        if self.points.len() > MAX_PATH_POINTS {
            while self.points.len() > MAX_PATH_POINTS / 2 {
                self.tolerance_mm *= 2.0;
                self.points = simplify(&self.points, self.tolerance_mm);
            }
            return Some(self.whole(ch));
        }
        Some(PathUpdate {
            ch,
            reset,
            program_starts: self.program_starts,
            points: fresh.iter().map(wire).collect(),
            tail: self.tail.as_ref().map(wire),
            tolerance_mm: self.tolerance_mm,
            lost: self.lost,
            soft_limits_mm: self.soft_limits_mm,
        })
    }

    /// The whole path, for a page that connects.
    pub fn whole(&self, ch: u16) -> PathUpdate {
        PathUpdate {
            ch,
            reset: true,
            program_starts: self.program_starts,
            points: self.points.iter().map(wire).collect(),
            tail: self.tail.as_ref().map(wire),
            tolerance_mm: self.tolerance_mm.max(PATH_TOLERANCE_MM),
            lost: self.lost,
            soft_limits_mm: self.soft_limits_mm,
        }
    }
}

/// How far a streamed line has got.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LineState {
    /// Executed.
    Done,
    /// The block executing now.
    Executing,
    /// Decoded, waiting for execution.
    Decoded,
    /// Still in the stream buffer.
    Buffered,
}

/// One streamed line.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StreamLine {
    /// Byte offset of the line since the stream started.
    pub offset: u64,
    pub text: String,
    pub state: LineState,
}

/// The `stream` event: a window of the executed and buffered stream.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StreamLines {
    pub ch: u16,
    pub lines: Vec<StreamLine>,
}

impl StreamLines {
    pub fn new(ch: u16, t: &StreamText) -> StreamLines {
        let mut lines = Vec::new();
        let mut start = t.from;
        for raw in t.bytes.split_inclusive(|&b| b == b'\n') {
            let at = start;
            start += raw.len() as u64;
            // A line cut at the window's start, a line of an earlier stream, or one not
            // ended yet: not listed.
            let whole = raw.ends_with(b"\n") && (at > t.from || at == t.stream_start);
            if !whole || at < t.stream_start {
                continue;
            }
            let state = match t.executing {
                Some(e) if at < e => LineState::Done,
                Some(e) if at == e => LineState::Executing,
                _ if at >= t.read_to => LineState::Buffered,
                _ => LineState::Decoded,
            };
            lines.push(StreamLine {
                offset: at - t.stream_start,
                text: String::from_utf8_lossy(raw)
                    .trim_end_matches(['\r', '\n'])
                    .to_string(),
                state,
            });
        }
        let executing = lines
            .iter()
            .position(|l| l.state != LineState::Done)
            .unwrap_or(lines.len());
        let first = executing.saturating_sub(LINES_BEHIND);
        lines.drain(..first);
        lines.truncate(MAX_STREAM_LINES);
        StreamLines { ch, lines }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stream_lines_know_how_far_they_got() {
        let text = b"N1 G01 X1\r\nN2 X2\r\nN3 X3\r\nN4 X4\r\n";
        let t = StreamText {
            from: 100,
            bytes: text.to_vec(),
            executing: Some(111),
            read_to: 124,
            stream_start: 100,
        };
        let l = StreamLines::new(1, &t);
        let states: Vec<_> = l.lines.iter().map(|l| (l.text.as_str(), l.state)).collect();
        assert_eq!(
            states,
            [
                ("N1 G01 X1", LineState::Done),
                ("N2 X2", LineState::Executing),
                ("N3 X3", LineState::Decoded),
                ("N4 X4", LineState::Buffered),
            ]
        );
        assert_eq!(l.lines[1].offset, 11);
    }

    #[test]
    fn a_path_over_its_cap_is_decimated_not_cut() {
        let mut store = PathStore::default();
        // A zigzag 4 µm high: kept point by point, straightened once decimated again.
        let mut drain = LiveDrain {
            program_starts: 1,
            points: (0..=MAX_PATH_POINTS)
                .map(|i| PathPoint {
                    xyz_mm: [i as f64 * 0.001, (i % 2) as f64 * 0.004, 0.0],
                    rapid: false,
                })
                .collect(),
            ..LiveDrain::default()
        };
        let u = store.extend(1, &mut drain).unwrap();
        assert!(u.reset);
        assert!(u.points.len() <= MAX_PATH_POINTS / 2, "{}", u.points.len());
        assert!(u.tolerance_mm > PATH_TOLERANCE_MM);
        // The start and the end are still there.
        assert_eq!(u.points.first().map(|p| p.0), Some(0.0));
        assert!(u.points.last().unwrap().0 > 199.0);
    }
}
