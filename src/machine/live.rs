//! What the live view (`serve --http`) needs of each channel beyond its status, recorded by
//! the machine from what every tick already produced: the path the interpolator moved since
//! the program started, decimated by a tolerance (not by time), and the stream bytes around
//! the executing block. The view's feed drains it through [`crate::machine::Op::DrainLive`].
//! `serve --http` turns the records on before the first tick (`Machine::record_live`), else
//! the first drain does, so a runtime without the view records nothing. A record turned on
//! while a program runs knows its path from then on and its stream lines from the next start.
//!
//! Memory is bounded: a channel keeps at most [`PENDING_POINTS`] path points and
//! [`STREAM_TEXT_BYTES`] of stream text between two drains (the feed drains every 50 ms);
//! what does not fit is counted, not kept. A tick's work here is constant: one position, at
//! most [`RUN_POINTS`] distance checks, no allocation once the buffers have grown.

use std::collections::VecDeque;

pub use crate::channel::live::{Executed, LiveDrain, PathPoint, StreamText};
use crate::channel::Channel;
use crate::vocab::axis::AXIS_LETTERS;
use crate::vocab::mode::State;
use crate::vocab::techno::{TechnoKind, TechnoSeq};
use crate::vocab::tick::Tick;

/// Largest distance, mm, of any interpolated position from the recorded polyline: an arc
/// of 10 mm radius keeps about 200 points a turn, a straight move two.
pub const PATH_TOLERANCE_MM: f64 = 0.01;
/// Path points a channel keeps between two drains; more are counted in
/// [`LiveDrain::points_lost`].
pub const PENDING_POINTS: usize = 8192;
/// Stream bytes a channel keeps: the last ones accepted, around and ahead of the
/// executing block.
pub const STREAM_TEXT_BYTES: usize = 256 * 1024;
/// Stream bytes a drain hands out before and after the executing block's line.
pub const STREAM_BACK_BYTES: usize = 4 * 1024;
pub const STREAM_AHEAD_BYTES: usize = 16 * 1024;

/// The online decimation, constant work a position: a run of positions from the last kept
/// point (the anchor) is extended while each new one lies within half the tolerance of the
/// run's line (the anchor's direction to the first position farther than the tolerance) and
/// no nearer to the anchor along it than the one before. Every position of the run then lies
/// within the tolerance of the segment from the anchor to the run's last position, which is
/// what is kept when the run ends.
#[derive(Debug, Default)]
struct Simplifier {
    anchor: Option<[f64; 3]>,
    /// Unit direction of the run's line, once a position left the anchor's tolerance.
    dir: Option<[f64; 3]>,
    /// The run's last position and how far along the line it is, mm.
    last: Option<[f64; 3]>,
    along_mm: f64,
    rapid: bool,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Simplifier {
    fn reset(&mut self) {
        *self = Simplifier::default();
    }

    /// Take the next position; a point that must be kept goes to `keep`.
    fn push(
        &mut self,
        p: [f64; 3],
        rapid: bool,
        tolerance_mm: f64,
        keep: &mut impl FnMut(PathPoint),
    ) {
        let Some(anchor) = self.anchor else {
            *self = Simplifier {
                anchor: Some(p),
                rapid,
                ..Simplifier::default()
            };
            keep(PathPoint { xyz_mm: p, rapid });
            return;
        };
        if self.last.unwrap_or(anchor) == p {
            return;
        }
        if let Some(last) = self.last {
            if rapid != self.rapid || !self.extends(anchor, p, tolerance_mm) {
                keep(PathPoint {
                    xyz_mm: last,
                    rapid: self.rapid,
                });
                self.anchor = Some(last);
                self.dir = None;
                self.last = None;
                self.along_mm = 0.0;
                return self.push(p, rapid, tolerance_mm, keep);
            }
        }
        self.rapid = rapid;
        self.last = Some(p);
        let d = sub(p, anchor);
        let len = dot(d, d).sqrt();
        match self.dir {
            Some(dir) => self.along_mm = dot(d, dir),
            None if len > tolerance_mm => {
                self.dir = Some([d[0] / len, d[1] / len, d[2] / len]);
                self.along_mm = len;
            }
            None => {}
        }
    }

    /// Does `p` extend the run within the tolerance?
    fn extends(&self, anchor: [f64; 3], p: [f64; 3], tolerance_mm: f64) -> bool {
        let d = sub(p, anchor);
        let Some(dir) = self.dir else {
            // Every position so far is within the tolerance of the anchor.
            return true;
        };
        let along = dot(d, dir);
        let off = sub(d, [dir[0] * along, dir[1] * along, dir[2] * along]);
        along >= self.along_mm && dot(off, off).sqrt() <= tolerance_mm / 2.0
    }

    /// The newest position not yet kept.
    fn tail(&self) -> Option<PathPoint> {
        self.last.map(|p| PathPoint {
            xyz_mm: p,
            rapid: self.rapid,
        })
    }
}

/// Decimate `points` again with `tolerance_mm` (the view's store when it reaches its cap).
pub fn simplify(points: &[PathPoint], tolerance_mm: f64) -> Vec<PathPoint> {
    let mut s = Simplifier::default();
    let mut out = Vec::with_capacity(points.len() / 2);
    for p in points {
        s.push(p.xyz_mm, p.rapid, tolerance_mm, &mut |k| out.push(k));
    }
    out.extend(s.tail());
    out
}

/// One channel's record.
#[derive(Debug, Default)]
pub struct ChannelRecord {
    on: bool,
    simplifier: Simplifier,
    pending: Vec<PathPoint>,
    points_lost: u64,
    program_starts: u64,
    started_tick: Option<u64>,
    stopped_tick: Option<u64>,
    running: bool,
    /// Stream bytes kept and the stream byte their first one is.
    text: VecDeque<u8>,
    text_from: u64,
    stream_start: u64,
    /// Bytes taken from the stream by the end of the last tick.
    taken_before: u64,
    /// `stream_start` is known: the record saw the present program start.
    stream_start_known: bool,
    /// The executing offset and the stream end of the last drain's text.
    sent: Option<(Option<u64>, u64)>,
    executed: Executed,
    /// Technology functions output by the end of the last tick, and the next sequence
    /// number not yet looked at.
    techno_output: u64,
    techno_next: TechnoSeq,
}

impl ChannelRecord {
    /// After the channel's tick: note a program start or stop, and the position.
    pub fn tick(&mut self, tick: &Tick, c: &Channel) {
        if !self.on {
            return;
        }
        let running = matches!(c.state(), State::Active | State::Hold);
        let (used, taken) = c.stream_fill();
        if running && !self.running {
            // A program started in this tick: a new path; the stream's byte 0 is the first
            // byte the buffer held before this tick's takes.
            self.program_starts += 1;
            self.started_tick = Some(tick.index);
            self.stopped_tick = None;
            self.simplifier.reset();
            self.pending.clear();
            let taken_now = taken.saturating_sub(self.taken_before);
            self.stream_start = c
                .stream_written()
                .saturating_sub(used as u64)
                .saturating_sub(taken_now);
            self.stream_start_known = true;
        } else if !running && self.running {
            self.stopped_tick = Some(tick.index);
        }
        self.running = running;
        self.taken_before = taken;
        self.follow_techno(c);
        let p = c.position();
        let pending = &mut self.pending;
        let lost = &mut self.points_lost;
        self.simplifier.push(
            [p[0], p[1], p[2]],
            c.executing_rapid(),
            PATH_TOLERANCE_MM,
            &mut |k| {
                if pending.len() < PENDING_POINTS {
                    pending.push(k);
                } else {
                    *lost += 1;
                }
            },
        );
    }

    /// Technology functions output this tick (still open in their units: acknowledgement
    /// comes a tick later at the earliest): the spindle and tool they set. Looked at only in
    /// a tick that output some, over the units (a fixed number).
    fn follow_techno(&mut self, c: &Channel) {
        let t = c.techno();
        let output = t.stats().output;
        if output == self.techno_output {
            return;
        }
        self.techno_output = output;
        let mut next = self.techno_next;
        let mut newest = [None::<TechnoSeq>; 3];
        for (_, _, f, _) in t.open_units() {
            if f.seq < self.techno_next {
                continue;
            }
            next = next.max(f.seq + 1);
            let (slot, newer) = match (f.kind, f.number) {
                (TechnoKind::M, 3..=5) => (0, newest[0].is_none_or(|s| f.seq > s)),
                (TechnoKind::S, _) => (1, newest[1].is_none_or(|s| f.seq > s)),
                (TechnoKind::T, _) => (2, newest[2].is_none_or(|s| f.seq > s)),
                _ => continue,
            };
            if !newer {
                continue;
            }
            newest[slot] = Some(f.seq);
            match (f.kind, f.number) {
                (TechnoKind::M, m) => self.executed.spindle_m(m),
                (TechnoKind::S, _) => self.executed.spindle_rpm = Some(f64::from(f.add_value)),
                _ => self.executed.tool = Some(f.number),
            }
        }
        self.techno_next = next;
    }

    /// A stream write the channel took: keep its bytes (the last [`STREAM_TEXT_BYTES`]).
    pub fn stream_written(&mut self, packet: &[u8], c: &Channel) {
        if !self.on {
            return;
        }
        let end = c.stream_written();
        let start = end.saturating_sub(packet.len() as u64);
        if self.text_from + self.text.len() as u64 != start {
            // A write the record did not see (before it was on): start afresh here.
            self.text.clear();
            self.text_from = start;
        }
        let room = STREAM_TEXT_BYTES.saturating_sub(packet.len());
        if self.text.len() > room {
            let drop = self.text.len() - room;
            self.text.drain(..drop);
            self.text_from += drop as u64;
        }
        let keep = packet.len().min(STREAM_TEXT_BYTES);
        self.text.extend(&packet[packet.len() - keep..]);
        if keep < packet.len() {
            self.text_from = end - keep as u64;
        }
    }

    /// Start recording (again nothing when on already).
    pub fn turn_on(&mut self, c: &Channel) {
        if self.on {
            return;
        }
        self.on = true;
        self.running = matches!(c.state(), State::Active | State::Hold);
        self.stream_start_known = !self.running;
        self.taken_before = c.stream_fill().1;
    }

    /// Hand out what was recorded since the last drain (and turn the record on).
    pub fn drain(&mut self, c: &Channel) -> LiveDrain {
        self.turn_on(c);
        let mut soft_limits_mm = [None; 3];
        for a in c.axis_limits() {
            if let Some(slot) = soft_limits_mm.get_mut(a.index) {
                *slot = Some((a.min_mm, a.max_mm));
            }
        }
        debug_assert_eq!(AXIS_LETTERS[0], b'X');
        LiveDrain {
            program_starts: self.program_starts,
            started_tick: self.started_tick,
            stopped_tick: self.stopped_tick,
            points: std::mem::take(&mut self.pending),
            tail: self.simplifier.tail(),
            points_lost: self.points_lost,
            stream: self.stream_text(c),
            soft_limits_mm,
            executed: self.executed,
        }
    }

    /// The stream text around the executing stream block, when it changed.
    fn stream_text(&mut self, c: &Channel) -> Option<StreamText> {
        let executing = c
            .active_block()
            .filter(|b| b.stream && self.stream_start_known)
            .map(|b| self.stream_start + b.offset);
        let end = self.text_from + self.text.len() as u64;
        if self.text.is_empty() || self.sent == Some((executing, end)) {
            return None;
        }
        self.sent = Some((executing, end));
        let centre = executing.unwrap_or(self.stream_start).max(self.text_from);
        let from = centre
            .saturating_sub(STREAM_BACK_BYTES as u64)
            .max(self.text_from);
        let to = centre.saturating_add(STREAM_AHEAD_BYTES as u64).min(end);
        let skip = usize::try_from(from - self.text_from).unwrap_or(usize::MAX);
        let take = usize::try_from(to.saturating_sub(from)).unwrap_or(0);
        let (used, _) = c.stream_fill();
        Some(StreamText {
            from,
            bytes: self.text.iter().skip(skip).take(take).copied().collect(),
            executing,
            read_to: c.stream_written().saturating_sub(used as u64),
            stream_start: self.stream_start,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn distance_to_segment(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
        let ab = sub(b, a);
        let ap = sub(p, a);
        let len2 = dot(ab, ab);
        let t = if len2 > 0.0 {
            (dot(ap, ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let d = sub(ap, [ab[0] * t, ab[1] * t, ab[2] * t]);
        dot(d, d).sqrt()
    }

    fn keep_all(points: &[([f64; 3], bool)]) -> Vec<PathPoint> {
        let mut s = Simplifier::default();
        let mut out = Vec::new();
        for &(p, r) in points {
            s.push(p, r, PATH_TOLERANCE_MM, &mut |k| out.push(k));
        }
        out.extend(s.tail());
        out
    }

    #[test]
    fn a_straight_move_keeps_its_ends_and_an_arc_its_shape() {
        let line: Vec<_> = (0..=100)
            .map(|i| ([f64::from(i) * 0.1, 0.0, 0.0], false))
            .collect();
        let kept = keep_all(&line);
        assert_eq!(kept.len(), 2, "{kept:?}");
        assert_eq!(kept.last().map(|p| p.xyz_mm[0]), Some(10.0));
        // A circle of radius 10 mm in 1000 samples: every sample within the tolerance.
        let circle: Vec<_> = (0..=1000)
            .map(|i| {
                let a = f64::from(i) / 1000.0 * std::f64::consts::TAU;
                ([10.0 * a.cos(), 10.0 * a.sin(), 0.0], false)
            })
            .collect();
        let kept = keep_all(&circle);
        assert!(kept.len() < 1000 / 3, "{}", kept.len());
        for (p, _) in &circle {
            let d = kept
                .windows(2)
                .map(|w| distance_to_segment(*p, w[0].xyz_mm, w[1].xyz_mm))
                .fold(f64::INFINITY, f64::min);
            assert!(d <= PATH_TOLERANCE_MM + 1e-9, "{d}");
        }
    }

    #[test]
    fn a_rapid_is_kept_apart_from_the_cut_after_it() {
        let mut pts: Vec<_> = (0..=10).map(|i| ([f64::from(i), 0.0, 0.0], true)).collect();
        pts.extend((11..=20).map(|i| ([f64::from(i), 0.0, 0.0], false)));
        let kept = keep_all(&pts);
        let corner = kept.iter().find(|p| p.xyz_mm[0] == 10.0).unwrap();
        assert!(corner.rapid);
        assert!(!kept.last().unwrap().rapid);
    }
}
