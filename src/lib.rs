//! ncchannel: an emulated CNC channel of a TwinCAT 3 CNC / ISG kernel.
//!
//! Data flows one way through a tick: requests → stream → decoder → planner →
//! interpolator → events. Each room below owns one machine part; `vocab` is the floor of
//! words they share. See the README's architecture section for who may import whom.
//!
//! # Layout
//!
//! The public surface is what the `ncchannel` binary, the tests, the benches and the fuzz
//! targets drive; everything else is internal to the crate.
//!
//! - [`channel`]: one NC channel, the ISG mode and state machine around the parts it owns.
//!   Its door is the only way in: a request ([`channel::door::Op`]) goes in, a
//!   [`channel::door::Reply`] comes out, [`channel::door::Status`] is what a PLC reads.
//! - [`machine`]: the emulated controller as the runtime ticks it: its channels, the built-in
//!   stream feeders, and the requests other threads send it (it re-exports the door's words).
//! - [`runtime`]: the fixed-cycle loop that ticks a machine in real or virtual time and keeps
//!   cycle statistics.
//! - [`ads`]: ADS over TCP: the AMS/TCP codec, the CNC's ADS tasks, the [`ads::server`] that
//!   serves them, a [`ads::client`], and the index groups in [`ads::objects`].
//! - [`lang`]: the NC language: one line to a block ([`lang::parse`]), expressions, and the
//!   static program check ([`lang::check`]).
//! - [`params`]: the ISG parameter lists (start-up, channel, axes, tools) and runtime.toml,
//!   read and checked into a [`params::Config`]; [`channels`] turns one into channels.
//! - [`report`]: what a run tells the outside: the JSON Lines event log, the summary, plots.
//! - [`soak`]: scenario-driven long runs with a randomised client, injected faults and
//!   invariants.
//! - [`dnc`]: NC data received as one stream and split into programs by start/end markers.
//! - [`http`]: the live web view of `serve --http`: an embedded page fed by Server-Sent Events.
//! - [`cli`]: the subcommands of the `ncchannel` binary; `main.rs` only parses and dispatches.
//! - [`vocab`]: the words every room shares: time, modes and states, axes, `#FLUSH`, cache
//!   operations, ADS ids, cycle statistics.
//!
//! A few parts of internal rooms are re-exported at the root for tests and benches that
//! drive them without a channel around them: the program [`Feeder`] and [`StreamBuffer`],
//! the path planner ([`Motion`] over a [`BlockQueue`] of [`Move`]s), the arc construction
//! ([`arc_move`]), and a handful of decoder limits.
//!
//! Internal rooms: `bounded`, `decoder`, `diag`, `feeder`, `geometry`, `motion`, `queue`,
//! `setup`, `source`.

pub mod ads;
pub(crate) mod bounded;
pub mod channel;
pub mod cli;
pub(crate) mod decoder;
pub(crate) mod destination;
pub(crate) mod diag;
pub mod dnc;
pub(crate) mod feeder;
pub(crate) mod geometry;
pub mod http;
pub mod lang;
pub mod machine;
pub(crate) mod motion;
pub mod params;
pub(crate) mod queue;
pub mod report;
pub mod runtime;
pub(crate) mod setup;
pub mod soak;
pub(crate) mod source;
pub mod vocab;

/// Building channels from a checked parameter list.
pub use setup::{channel_settings, channels, SetupError};

/// Feeding a program to a channel's stream in packets, and the stream buffer itself.
pub use feeder::{Feeder, FeederError};
pub use source::store::FsLatency;
pub use source::stream::{
    StreamBuffer, StreamWriteError, MAX_PROGRAM_STREAM_INPUT_SIZE, MAX_PROGRAM_STREAM_SIZE,
};

/// The path planner and the block queue it reads, for driving motion without a decoder.
pub use motion::planner::JUNCTION_ACCEL_SHARE;
pub use motion::{AxisLimits, Motion, MotionNote, PlannerSettings};
pub use queue::{
    Action, BlockInfo, BlockQueue, CompSide, Move, MoveKind, PathMode, Plane, QueuedBlock,
    SplineKind,
};

/// Arcs from their programmed words (centre, radius, turns) to a queued move.
pub use geometry::arc::{arc_move, ArcError, ArcSpec};

pub use decoder::frame::MAX_LINE_BYTES;
/// Decoder limits and kinds that show through a channel's requests and replies.
pub use decoder::modal::DEFAULT_PATH_DEV_MM;
pub use decoder::vars::{VarClass, CLASS_BYTES};
pub use decoder::{
    SearchTarget, DECLARED_VALUES_PER_TICK, LABEL_SCAN_BYTES_PER_TICK, LABEL_SCAN_LINES_PER_TICK,
    LINE_BYTES_PER_TICK, MAX_INDEXED_LABELS,
};
pub use source::loader::{Loader, INLINE_READ_BYTES_PER_TICK};

/// Findings of a parameter-list check.
pub use diag::{Diagnostic, Severity};
