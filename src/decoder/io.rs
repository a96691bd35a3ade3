//! The channel's parts the decoder reads from and writes to during one step.

use std::time::Duration;

use crate::queue::BlockQueue;
use crate::source::cache::Cache;
use crate::source::store::ProgramStore;
use crate::source::stream::StreamBuffer;

/// The channel's parts the decoder reads from and writes to during one step.
pub struct DecoderIo<'a> {
    pub stream: &'a mut StreamBuffer,
    pub store: &'a mut ProgramStore,
    pub cache: &'a mut Cache,
    pub queue: &'a mut BlockQueue,
    /// Motion has nothing left to do (for `#FLUSH WAIT`).
    pub(crate) motion_idle: bool,
    /// Keep each block's text for the event log (and report cache hits: events are on).
    pub(crate) want_text: bool,
    /// Channel time at the start of this tick.
    pub now: Duration,
    /// Length of this tick: decoding stops for the tick once simulated file-system latency
    /// has used it up.
    pub period: Duration,
}
