//! Motion: executes the queued blocks in channel time and reports where the axes are.
//!
//! This is the channel's first time model (Stage 2): every motion block takes its length over
//! its feed (G0: the slowest axis at its rapid rate), with no acceleration. The lookahead
//! planner and interpolator of Stage 5 replace its insides; its verbs stay.

use crate::lang::block::FlushKind;
use crate::queue::{Action, BlockInfo, BlockQueue, Move, MoveKind, Position, MAX_AXES};

/// Limits of one axis (runtime.toml `[[axes]]`).
#[derive(Debug, Clone, PartialEq)]
pub struct AxisLimits {
    /// Index into `queue::AXIS_LETTERS`.
    pub index: usize,
    /// Maximum velocity, mm/min.
    pub max_velocity_mm_per_min: f64,
    /// Maximum acceleration, mm/s².
    pub max_accel_mm_per_s2: f64,
    /// Rapid (G0) rate, mm/min.
    pub rapid_mm_per_min: f64,
    /// Software limits, mm.
    pub min_mm: f64,
    pub max_mm: f64,
}

/// What execution did this tick, in order, for the channel to report.
#[derive(Debug, Clone, PartialEq)]
pub enum MotionNote {
    /// A block took effect (started executing): its `block` event.
    Started(BlockInfo),
    Flush(FlushKind),
    /// The main program's end was reached: everything before it has run.
    End {
        m: u32,
        prog: std::sync::Arc<str>,
    },
}

#[derive(Debug, Clone)]
struct Active {
    kind: ActiveKind,
    /// Seconds this block takes at 100 % override.
    duration_s: f64,
    /// Seconds of it done.
    done_s: f64,
}

#[derive(Debug, Clone)]
enum ActiveKind {
    Move(Move),
    Dwell,
}

/// The executor of one channel.
#[derive(Debug)]
pub struct Motion {
    axes: Vec<AxisLimits>,
    active: Option<Active>,
    pos: Position,
    /// Feed override, percent (0–200).
    override_pct: f64,
    hold: bool,
    /// The program end was executed; nothing more runs until the next start.
    ended: bool,
    /// Path velocity of the last tick, mm/s (for plots and checks).
    velocity_mm_per_s: f64,
}

impl Motion {
    pub fn new(axes: Vec<AxisLimits>) -> Self {
        Motion {
            axes,
            active: None,
            pos: [0.0; MAX_AXES],
            override_pct: 100.0,
            hold: false,
            ended: false,
            velocity_mm_per_s: 0.0,
        }
    }

    pub fn position(&self) -> Position {
        self.pos
    }

    pub fn velocity_mm_per_s(&self) -> f64 {
        self.velocity_mm_per_s
    }

    /// Nothing in execution (the queue may still hold blocks).
    pub fn idle(&self) -> bool {
        self.active.is_none()
    }

    pub fn set_override(&mut self, pct: f64) {
        self.override_pct = pct.clamp(0.0, 200.0);
    }

    pub fn override_pct(&self) -> f64 {
        self.override_pct
    }

    pub fn set_hold(&mut self, hold: bool) {
        self.hold = hold;
    }

    /// A program starts: execution may run again.
    pub fn start(&mut self) {
        self.ended = false;
        self.hold = false;
    }

    /// Reset: stop at once where we are.
    pub fn reset(&mut self) {
        self.active = None;
        self.hold = false;
        self.ended = false;
        self.velocity_mm_per_s = 0.0;
    }

    /// Seconds a move takes at 100 % override.
    fn duration_s(&self, m: &Move) -> f64 {
        match m.kind {
            MoveKind::Rapid => {
                // Each axis at most at its rapid rate: the slowest one decides.
                let mut t: f64 = 0.0;
                for a in &self.axes {
                    let d = (m.end[a.index] - m.start[a.index]).abs();
                    if a.rapid_mm_per_min > 0.0 {
                        t = t.max(d / (a.rapid_mm_per_min / 60.0));
                    }
                }
                t
            }
            _ => {
                let feed = self.limited_feed(m);
                if feed <= 0.0 {
                    0.0
                } else {
                    m.length_mm() / (feed / 60.0)
                }
            }
        }
    }

    /// The programmed feed, lowered so no axis exceeds its maximum velocity on a line.
    fn limited_feed(&self, m: &Move) -> f64 {
        let len = m.length_mm();
        let mut feed = m.feed_mm_per_min;
        if len <= 0.0 {
            return feed;
        }
        if let MoveKind::Line = m.kind {
            for a in &self.axes {
                let share = (m.end[a.index] - m.start[a.index]).abs() / len;
                if share > 0.0 {
                    feed = feed.min(a.max_velocity_mm_per_min / share);
                }
            }
        } else {
            let vmax = self
                .axes
                .iter()
                .map(|a| a.max_velocity_mm_per_min)
                .fold(f64::INFINITY, f64::min);
            feed = feed.min(vmax);
        }
        feed
    }

    /// Advance channel time by `dt_s`: finish what runs, take new blocks from the queue.
    pub fn step(&mut self, dt_s: f64, queue: &mut BlockQueue, notes: &mut Vec<MotionNote>) {
        let start_pos = self.pos;
        if self.hold || self.ended {
            self.velocity_mm_per_s = 0.0;
            return;
        }
        let rate = self.override_pct / 100.0;
        // Channel seconds of program progress available this tick.
        let mut budget = dt_s * rate;
        let mut path_mm = 0.0;
        loop {
            if self.active.is_none() {
                if rate <= 0.0 {
                    break;
                }
                let Some(b) = queue.pop_front() else {
                    break;
                };
                if !b.silent {
                    notes.push(MotionNote::Started(b.info.clone()));
                }
                match b.action {
                    Action::None => continue,
                    Action::Flush(k) => {
                        notes.push(MotionNote::Flush(k));
                        continue;
                    }
                    Action::End { m } => {
                        notes.push(MotionNote::End {
                            m,
                            prog: b.info.prog,
                        });
                        self.ended = true;
                        break;
                    }
                    Action::Dwell { seconds } => {
                        self.active = Some(Active {
                            kind: ActiveKind::Dwell,
                            duration_s: seconds,
                            done_s: 0.0,
                        });
                    }
                    Action::Move(m) => {
                        let d = self.duration_s(&m);
                        self.active = Some(Active {
                            kind: ActiveKind::Move(m),
                            duration_s: d,
                            done_s: 0.0,
                        });
                    }
                }
            }
            let Some(a) = self.active.as_mut() else {
                break;
            };
            let left = a.duration_s - a.done_s;
            if budget <= 0.0 && left > 0.0 {
                break;
            }
            let take = left.min(budget).max(0.0);
            a.done_s += take;
            budget -= take;
            let finished = a.done_s >= a.duration_s - 1e-12;
            if let ActiveKind::Move(m) = &a.kind {
                let u = if a.duration_s > 0.0 {
                    a.done_s / a.duration_s
                } else {
                    1.0
                };
                let p = if finished { m.end } else { m.point_at(u) };
                if a.duration_s > 0.0 {
                    path_mm += m.length_mm() * take / a.duration_s;
                }
                self.pos = p;
            }
            if finished {
                self.active = None;
            } else {
                break;
            }
        }
        let _ = start_pos;
        self.velocity_mm_per_s = if dt_s > 0.0 { path_mm / dt_s } else { 0.0 };
    }

    /// Set the machine position (start-up, or after a reset moved nothing).
    pub fn set_position(&mut self, p: Position) {
        self.pos = p;
    }
}
