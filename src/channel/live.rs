//! What the live view's record of a channel hands out on a drain (`Op::DrainLive`, recorded
//! by the machine's `live` part): the path points, the stream text around the executing
//! block, and the spindle and tool of the executed functions. Defined beside the channel's
//! requests and replies, so the reply can carry it.

use crate::decoder::modal::Spindle;

/// One recorded point, machine coordinates X Y Z, mm; `rapid`: the segment from the point
/// before to this one was a rapid (G0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathPoint {
    pub xyz_mm: [f64; 3],
    pub rapid: bool,
}

/// Stream text around the executing block: `bytes` start at stream byte `from` (counted
/// from the channel's first accepted stream byte, as `bytes_written` counts them).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StreamText {
    pub from: u64,
    pub bytes: Vec<u8>,
    /// Where the executing block's line starts, `None` before the first stream block.
    pub executing: Option<u64>,
    /// Where the decoder has read to: bytes from here on still wait in the buffer.
    pub read_to: u64,
    /// Where the present stream started (its byte 0 in the block offsets).
    pub stream_start: u64,
}

/// What one drain hands the view.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LiveDrain {
    /// Counts program starts: a new value means the points begin a new program's path.
    pub program_starts: u64,
    /// Tick of the present program's start, if one has started.
    pub started_tick: Option<u64>,
    /// Tick at which the last program stopped running (end, error, reset), if it has.
    pub stopped_tick: Option<u64>,
    /// Path points since the last drain (of the present program).
    pub points: Vec<PathPoint>,
    /// The position the path has reached, not yet part of `points` (drawn to, not kept).
    pub tail: Option<PathPoint>,
    /// Points that did not fit between drains since the record began.
    pub points_lost: u64,
    /// Stream text, when it changed since the last drain.
    pub stream: Option<StreamText>,
    /// Software limits of X Y Z, mm (`None`: the axis is not configured).
    pub soft_limits_mm: [Option<(f64, f64)>; 3],
    /// What the executed technology functions set (M3/M4/M5, S, T), where one has run
    /// since the record began; the decoder's modal state runs ahead by the lookahead.
    pub executed: Executed,
}

/// The spindle and tool as the executed technology functions left them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Executed {
    pub spindle: Option<Spindle>,
    pub spindle_rpm: Option<f64>,
    pub tool: Option<u32>,
}

impl Executed {
    /// An executed spindle function: M3 clockwise, M4 counter-clockwise, M5 (any other) off.
    pub fn spindle_m(&mut self, m: u32) {
        self.spindle = Some(match m {
            3 => Spindle::Cw,
            4 => Spindle::Ccw,
            _ => Spindle::Off,
        });
    }
}
