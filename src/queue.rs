//! The channel's block queue: decoded blocks on their way to motion, bounded for back-pressure.
//!
//! The decoder pushes only while the queue has room, so a channel that cannot move faster
//! stops pulling stream segments, the 4094-byte stream buffer fills, and a writer sees 11012 —
//! back-pressure by construction, as on the real channel.

use std::collections::VecDeque;
use std::sync::Arc;

use crate::vocab::techno::{OutputGroup, TechnoSeq};

use crate::vocab::axis::{Position, MAX_AXES};
use crate::vocab::flush::FlushKind;

/// Where a block came from, carried to the `block` event emitted when it takes effect.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockInfo {
    pub prog: Arc<str>,
    /// 1-based line number in its program (in a stream: since stream start).
    pub line: u32,
    /// Byte offset of the line in its program (in a stream: since stream start).
    pub offset: u64,
    /// ISG block counter: every decoded line counts, comments and each loop pass included.
    pub counter: u64,
    pub n: Option<u32>,
    /// The line's text, only when the event log wants it.
    pub text: Option<Box<str>>,
    pub stream: bool,
}

/// The working plane of arcs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    /// G17: X Y, tool axis Z.
    Xy,
    /// G18: Z X, tool axis Y.
    Zx,
    /// G19: Y Z, tool axis X.
    Yz,
}

impl Plane {
    /// Indices of the plane's first axis, second axis and normal (tool) axis.
    pub fn axes(self) -> (usize, usize, usize) {
        match self {
            Plane::Xy => (0, 1, 2),
            Plane::Zx => (2, 0, 1),
            Plane::Yz => (1, 2, 0),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MoveKind {
    /// G0: each axis at most its rapid rate.
    Rapid,
    /// G1 at the programmed feed.
    Line,
    /// G2 (cw) / G3 (ccw) in `plane` around `center` (plane coordinates, mm), optionally
    /// a helix along the plane's normal axis. `radius_mm` from the start point.
    Arc {
        plane: Plane,
        center: [f64; 2],
        radius_mm: f64,
        cw: bool,
        /// Swept angle, radians, always > 0 (a full circle is 2π).
        sweep_rad: f64,
    },
}

/// Tool radius compensation side (G40 / G41 / G42).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CompSide {
    /// G40.
    #[default]
    Off,
    /// G41: the tool left of the programmed path.
    Left,
    /// G42: the tool right of the programmed path.
    Right,
}

/// Spline type (`#SPLINE TYPE AKIMA|BSPLINE`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SplineKind {
    /// Through the programmed points.
    #[default]
    Akima,
    /// Within the control polygon of the programmed points.
    BSpline,
}

/// The decoder's cross-block modal state a motion block was programmed under: what motion
/// needs to plan across blocks (contouring, tool radius compensation, splines).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PathMode {
    /// Corner blending at this block's end (G261 modal, G61 this block): the largest deviation
    /// from the programmed corner, mm (`#CONTOUR MODE [DEV PATH_DEV=…]`); `None` = sharp corner.
    pub contour_dev_mm: Option<f64>,
    /// G40 / G41 / G42.
    pub comp: CompSide,
    /// D word: the tool data set whose radius compensates (0 = none).
    pub tool_offset: u32,
    /// G151 / `#SPLINE ON`: the spline type; `None` = G150 / `#SPLINE OFF`.
    pub spline: Option<SplineKind>,
}

/// One motion block: start and end positions and how to get there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    pub kind: MoveKind,
    pub start: Position,
    pub end: Position,
    /// Programmed path feed, mm/min (ignored for rapid moves).
    pub feed_mm_per_min: f64,
    /// Cross-block modal state at this block.
    pub path: PathMode,
}

/// The circle of an arc move, in its plane: what point, tangent and extent computations need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcGeom {
    /// The plane's first and second axis (indices into a `Position`).
    pub a: usize,
    pub b: usize,
    pub center: [f64; 2],
    pub(crate) radius_mm: f64,
    /// +1 counter-clockwise (G3), −1 clockwise (G2).
    pub dir: f64,
    /// Swept angle, radians (> 0).
    pub(crate) sweep_rad: f64,
    /// Angle of the start point around the centre, radians.
    pub(crate) start_rad: f64,
}

impl ArcGeom {
    /// Angle at fraction `u` (0..=1) of the sweep, radians.
    pub(crate) fn angle_at(&self, u: f64) -> f64 {
        self.start_rad + self.dir * self.sweep_rad * u
    }
}

impl Move {
    /// The circle, for an arc move.
    pub fn arc(&self) -> Option<ArcGeom> {
        let MoveKind::Arc {
            plane,
            center,
            radius_mm,
            cw,
            sweep_rad,
        } = self.kind
        else {
            return None;
        };
        let (a, b, _) = plane.axes();
        Some(ArcGeom {
            a,
            b,
            center,
            radius_mm,
            dir: if cw { -1.0 } else { 1.0 },
            sweep_rad,
            start_rad: (self.start[b] - center[1]).atan2(self.start[a] - center[0]),
        })
    }

    /// Path length in mm (axes' Euclidean length; arcs: helix length).
    pub(crate) fn length_mm(&self) -> f64 {
        match self.kind {
            MoveKind::Rapid | MoveKind::Line => {
                let mut s = 0.0;
                for i in 0..MAX_AXES {
                    let d = self.end[i] - self.start[i];
                    s += d * d;
                }
                s.sqrt()
            }
            MoveKind::Arc {
                plane,
                radius_mm,
                sweep_rad,
                ..
            } => {
                let (_, _, n) = plane.axes();
                let arc = radius_mm * sweep_rad;
                let h = self.end[n] - self.start[n];
                let mut other = 0.0;
                for i in 3..MAX_AXES {
                    let d = self.end[i] - self.start[i];
                    other += d * d;
                }
                (arc * arc + h * h + other).sqrt()
            }
        }
    }

    /// Position at fraction `u` (0..=1) of the path.
    pub(crate) fn point_at(&self, u: f64) -> Position {
        let u = u.clamp(0.0, 1.0);
        let mut p = self.start;
        for (pi, (s, e)) in p.iter_mut().zip(self.start.iter().zip(&self.end)) {
            *pi = s + (e - s) * u;
        }
        if let Some(c) = self.arc() {
            if u >= 1.0 {
                return self.end;
            }
            let ang = c.angle_at(u);
            p[c.a] = c.center[0] + c.radius_mm * ang.cos();
            p[c.b] = c.center[1] + c.radius_mm * ang.sin();
        }
        p
    }
}

/// What a decoded block does once it reaches execution.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Takes effect without motion: assignments, M/S/T functions, modal changes.
    None,
    /// Boxed: a queued block is moved at every hop, and a block without motion need not
    /// carry one (the 168-byte move inline made every queued block 240 bytes; it is 96).
    Move(Box<Move>),
    /// G4: wait, seconds.
    Dwell { seconds: f64 },
    /// `#FLUSH …`: release the held blocks (the planner's release rules, `motion::planner`).
    Flush(FlushKind),
    /// M00 (programmed stop) or M01 (optional stop): the axes come to rest, then the channel
    /// holds until the next start; M01 only while the operator's M01 switch is on.
    Stop { optional: bool },
    /// M30/M2 of the main program: the program ends when everything before it has run.
    End { m: u32 },
    /// A technology function step around the block's motion (always a silent part).
    Techno(TechnoStep),
    /// `#MSG SYN` / `#MSG SYN_ACK`: an operator message reported when execution reaches its
    /// block, not when it is decoded (TF5200 programming manual, "Programming a message
    /// (#MSG)": "synchronous with processing state in interpolator").
    Message(Box<SyncMessage>),
}

/// An operator message that waits for its block's execution, its values already formatted.
#[derive(Debug, Clone, PartialEq)]
pub struct SyncMessage {
    pub text: String,
    /// `#MSG SAVE …`: written to the report file as well.
    pub save: bool,
}

/// Where a block's technology functions meet its motion (TF5200 "Synchronisation types").
#[derive(Debug, Clone, PartialEq)]
pub enum TechnoStep {
    /// Hand these functions to the PLC when execution reaches this point.
    Output(Box<OutputGroup>),
    /// The axes stand until these functions are acknowledged.
    Wait(Box<[TechnoSeq]>),
}

#[derive(Debug, Clone, PartialEq)]
pub struct QueuedBlock {
    pub info: BlockInfo,
    pub action: Action,
    /// A second part of a block already reported (the program end after a block's move, the
    /// positioning move of a block search): no `block` event of its own.
    pub silent: bool,
}

/// Bounded FIFO between decoder and motion.
#[derive(Debug)]
pub struct BlockQueue {
    items: VecDeque<QueuedBlock>,
    capacity: usize,
}

impl BlockQueue {
    pub fn new(capacity: usize) -> Self {
        let capacity = capacity.max(1);
        BlockQueue {
            items: VecDeque::with_capacity(capacity),
            capacity,
        }
    }
    pub fn has_room(&self) -> bool {
        self.items.len() < self.capacity
    }
    pub fn len(&self) -> usize {
        self.items.len()
    }
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
    pub fn capacity(&self) -> usize {
        self.capacity
    }
    /// The decoder checks `has_room` before it reads a line; one line may queue up to three
    /// entries (dwell or move, program end, search positioning), so the capacity is soft by
    /// that much and no block is ever refused.
    pub fn push(&mut self, b: QueuedBlock) {
        self.items.push_back(b);
    }
    pub(crate) fn front(&self) -> Option<&QueuedBlock> {
        self.items.front()
    }
    pub(crate) fn pop_front(&mut self) -> Option<QueuedBlock> {
        self.items.pop_front()
    }
    pub fn iter(&self) -> impl Iterator<Item = &QueuedBlock> {
        self.items.iter()
    }
    pub fn clear(&mut self) {
        self.items.clear();
    }
}

#[cfg(all(test, target_pointer_width = "64"))]
mod tests {
    use super::{Action, QueuedBlock};

    /// A queued block is moved at every hop (decoder, queue, planner): a variant that grows
    /// makes every block, moving or not, carry it.
    #[test]
    fn a_queued_block_stays_small() {
        assert_eq!(std::mem::size_of::<Action>(), 24);
        assert_eq!(std::mem::size_of::<QueuedBlock>(), 96);
    }
}
