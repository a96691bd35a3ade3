//! Window entries and the motion-block data the planner's parts share: `Segment`, `Junction`,
//! `Entry`, `EntryKind`.

use crate::queue::{BlockInfo, Move, SyncMessage};
use crate::vocab::axis::MAX_AXES;
use crate::vocab::flush::FlushKind;
use crate::vocab::techno::{OutputGroup, TechnoSeq};

/// A motion block with what the plan needs of it.
#[derive(Debug, Clone)]
pub(crate) struct Segment {
    pub(crate) mv: Move,
    /// Path length, mm.
    pub(crate) length_mm: f64,
    /// Programmed path velocity at 100 % override (G0: the rapid limit), mm/s.
    pub(crate) programmed_mm_per_s: f64,
    /// Highest path velocity the axes allow on this block, whatever the override, mm/s.
    pub(crate) limit_mm_per_s: f64,
    /// Path acceleration limit the profile uses, mm/s²: on a line the axis limits less what
    /// the junctions at its two ends claim (`JunctionRule::link` in planner/junction.rs).
    pub(crate) accel_mm_per_s2: f64,
    /// Path acceleration with every axis' full limit projected on the block, mm/s².
    pub(crate) full_accel_mm_per_s2: f64,
    /// Per axis, the acceleration the junction at this block's end claims for its velocity
    /// jump, mm/s² (the default reserve until the next block is known).
    pub(crate) end_claim_mm_per_s2: [f64; MAX_AXES],
    /// Junction with the previous motion block: `None` = the motion stops before this block.
    pub(crate) junction: Option<Junction>,
    /// Planned velocity at the block end, mm/s.
    pub(crate) exit_mm_per_s: f64,
}

impl Segment {
    /// The velocity this block aims for at `override_pct`, mm/s.
    pub(crate) fn cruise_mm_per_s(&self, override_pct: f64) -> f64 {
        (self.programmed_mm_per_s * override_pct / 100.0).min(self.limit_mm_per_s)
    }
}

/// What limits the velocity at the start of a block coming from the previous one (its limits
/// are computed in planner/junction.rs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Junction {
    /// maxᵢ |Δtᵢ| / budgetᵢ, s²/mm: velocity ≤ dt / k and ≤ √(L / k).
    pub(crate) k_s2_per_mm: f64,
    /// Per axis, the change of the unit tangent |t2ᵢ − t1ᵢ| (the velocity jump per mm/s).
    pub(crate) jump: [f64; MAX_AXES],
    /// Per axis, the previous block's tangential acceleration at the junction, mm/s².
    pub(crate) prev_load_mm_per_s2: [f64; MAX_AXES],
    /// Per axis, the acceleration this junction claims from the blocks on both sides, mm/s².
    pub(crate) claim_mm_per_s2: [f64; MAX_AXES],
    /// Both blocks are straight: the budget rule applies (else the fixed reserve).
    pub(crate) straight: bool,
    /// The shorter of the two blocks, mm.
    pub(crate) short_mm: f64,
    /// The previous block's length, mm.
    pub(crate) prev_length_mm: f64,
    /// The previous block's programmed velocity, mm/s.
    pub(crate) prev_programmed_mm_per_s: f64,
    /// The previous block's limit velocity, mm/s.
    pub(crate) prev_limit_mm_per_s: f64,
}

/// What a window entry does.
#[derive(Debug, Clone)]
pub(crate) enum EntryKind {
    Move(Box<Segment>),
    Dwell {
        seconds: f64,
    },
    /// Takes effect without motion (assignments, M/S/T functions, modal changes).
    Plain,
    /// M00 / M01: the axes at rest, then the channel holds (if the stop applies).
    Stop {
        optional: bool,
    },
    Flush(FlushKind),
    /// Hand technology functions to the PLC (no stop of its own).
    TechnoOutput(Box<OutputGroup>),
    /// Stand until these technology functions are acknowledged.
    TechnoWait(Box<[TechnoSeq]>),
    /// `#MSG SYN`: report the message when execution reaches it; the motion goes on as over
    /// a plain block.
    Message(Box<SyncMessage>),
    End {
        m: u32,
        prog: std::sync::Arc<str>,
    },
}

impl EntryKind {
    /// The motion stops before anything after this entry runs.
    pub(crate) fn is_barrier(&self) -> bool {
        matches!(
            self,
            EntryKind::Dwell { .. }
                | EntryKind::TechnoWait(_)
                | EntryKind::Stop { .. }
                | EntryKind::End { .. }
                | EntryKind::Flush(FlushKind::Stop | FlushKind::Wait)
        )
    }
}

/// One block in the window.
#[derive(Debug, Clone)]
pub(crate) struct Entry {
    /// Taken when the `block` event is emitted (`None` for silent second parts).
    pub(crate) info: Option<BlockInfo>,
    pub(crate) kind: EntryKind,
    /// A motion entry that counts towards the lookahead (a programmed block; not a contour
    /// blend, not the second and later pieces of a spline segment).
    pub(crate) counted: bool,
}
