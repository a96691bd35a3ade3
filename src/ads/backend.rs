//! The seam between the ADS object table and whatever holds the channels.
//!
//! The object table never touches channel state: it decodes (group, offset, bytes), calls one
//! method here, and encodes the answer. The runtime implements this trait by sending a request
//! into its fixed-cycle loop and waiting for the reply (at most one tick); `MemoryBackend`
//! implements it with an in-memory stand-in channel. Calls come from the server's connection
//! threads and may block briefly.
//!
//! Channel numbers are 1-based everywhere in this trait (`1..=channel_count()`), as in the
//! index group `0x20100 + ch`; the object table never passes 0 or a number above the count.

use super::result::AdsResult;

#[cfg(doc)]
use crate::channel::{Mode, State};
pub use crate::machine::{HmiOp, Status};

/// Channel modes as the ADS objects carry them (SGN32): the numbers of [`Mode`], defined once
/// there.
pub mod mode {
    use crate::channel::Mode;
    pub const STANDBY: i32 = Mode::Standby as i32;
    pub const AUTOMATIC: i32 = Mode::Automatic as i32;
    pub const MDI: i32 = Mode::Mdi as i32;
    pub const MANUAL: i32 = Mode::Manual as i32;
}

/// Channel states as the ADS objects carry them: the numbers of [`State`].
pub mod state {
    use crate::channel::State;
    pub const DESELECTED: i32 = State::Deselected as i32;
    pub const SELECTED: i32 = State::Selected as i32;
    pub const READY: i32 = State::Ready as i32;
    pub const ACTIVE: i32 = State::Active as i32;
    pub const HOLD: i32 = State::Hold as i32;
    pub const ERROR: i32 = State::Error as i32;
}

/// How one stream write (offset 0x90) went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StreamWriteOutcome {
    /// The packet is in the stream buffer. ADS result 0.
    Accepted,
    /// The buffer cannot take it now; the channel raised warning 11012. ADS result 0x708.
    Full,
    /// Empty, or larger than 992 bytes (MAX_PROGRAM_STREAM_INPUT_SIZE). ADS result 0x705.
    BadSize,
    /// A line lacks CR LF; the channel raised error 21476 and aborted streaming. ADS 0x706.
    NoLineEnd,
    /// Refused for another reason (e.g. the channel is gone).
    Refused(DeviceError),
}

impl StreamWriteOutcome {
    pub fn result(self) -> AdsResult {
        match self {
            StreamWriteOutcome::Accepted => AdsResult::OK,
            StreamWriteOutcome::Full => AdsResult::BUSY,
            StreamWriteOutcome::BadSize => AdsResult::INVALID_SIZE,
            StreamWriteOutcome::NoLineEnd => AdsResult::INVALID_DATA,
            StreamWriteOutcome::Refused(e) => e.result(),
        }
    }
}

/// Why a channel request failed; each maps to one ADS result code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DeviceError {
    /// The channel cannot do that in its current mode/state (0x707).
    #[error("device not ready")]
    NotReady,
    /// Try again shortly (0x708).
    #[error("device busy")]
    Busy,
    /// The value is out of range or unknown, e.g. mode 9 or override 250 % (0x706).
    #[error("invalid parameter value")]
    InvalidValue,
    /// A named thing does not exist, e.g. an unknown V.E. variable (0x70C).
    #[error("not found")]
    NotFound,
}

impl DeviceError {
    pub fn result(self) -> AdsResult {
        match self {
            DeviceError::NotReady => AdsResult::NOT_READY,
            DeviceError::Busy => AdsResult::BUSY,
            DeviceError::InvalidValue => AdsResult::INVALID_DATA,
            DeviceError::NotFound => AdsResult::NOT_FOUND,
        }
    }
}

/// Fill level of a channel's stream buffer, in bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StreamFill {
    pub used_bytes: u32,
    pub free_bytes: u32,
}

/// What the ADS object table needs from the channels. Implemented by the runtime (and by
/// `MemoryBackend` for tests). `ch` is 1-based.
pub trait CncBackend: Send + Sync + 'static {
    /// Number of channels; index groups exist for `1..=channel_count()`.
    fn channel_count(&self) -> u16;
    /// Offer one packet (one or more whole CR LF lines) to the stream buffer.
    fn stream_write(&self, ch: u16, data: &[u8]) -> StreamWriteOutcome;
    /// Current (mode, state), ISG HLI numbers.
    fn mode_state(&self, ch: u16) -> Result<(i32, i32), DeviceError>;
    /// Command a mode (`mode::*`).
    fn command_mode(&self, ch: u16, mode: i32) -> Result<(), DeviceError>;
    /// Command a state (`state::*`; ACTIVE starts the selected program).
    fn command_state(&self, ch: u16, state: i32) -> Result<(), DeviceError>;
    /// Select the program the next ACTIVE starts.
    fn command_program(&self, ch: u16, name: &str) -> Result<(), DeviceError>;
    /// Feed hold (automatic stop).
    fn hold(&self, ch: u16) -> Result<(), DeviceError>;
    /// Resume after hold.
    fn resume(&self, ch: u16) -> Result<(), DeviceError>;
    /// Channel reset: back to READY, streaming off, stream buffer deleted.
    fn reset(&self, ch: u16) -> Result<(), DeviceError>;
    /// The last error message (e.g. "21476 Streaming data does not contain …"), "" if none.
    fn last_error(&self, ch: u16) -> Result<String, DeviceError>;
    /// Stream buffer fill level.
    fn stream_fill(&self, ch: u16) -> Result<StreamFill, DeviceError>;
    /// Blocks that took effect since the channel started (the ISG block counter).
    fn block_counter(&self, ch: u16) -> Result<u64, DeviceError>;
    /// Actual axis positions in mm, in the channel's axis order.
    fn positions(&self, ch: u16) -> Result<Vec<f64>, DeviceError>;
    /// Feed override in percent, 0..=200.
    fn set_override(&self, ch: u16, percent: f64) -> Result<(), DeviceError>;
    /// Read an external variable `V.E.<name>` (name given without the `V.E.` prefix).
    fn read_ve(&self, ch: u16, name: &str) -> Result<f64, DeviceError>;
    /// Write an external variable `V.E.<name>`.
    fn write_ve(&self, ch: u16, name: &str, value: f64) -> Result<(), DeviceError>;
    /// Everything the COM, GEO and HLI objects show of a channel, in one snapshot.
    fn view(&self, ch: u16) -> Result<Status, DeviceError>;
    /// An HMI command object (`mc_command_*_w`).
    fn hmi(&self, ch: u16, op: HmiOp) -> Result<(), DeviceError>;
    /// The `index`-th error the channel raised (0 = first), if still kept.
    fn error_record(&self, ch: u16, index: u64) -> Result<ErrorRecord, DeviceError>;
}

/// One entry of a channel's error history and how many errors it raised in all.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ErrorRecord {
    pub total: u64,
    /// ISG error number and text; `None` when that error is no longer kept.
    pub error: Option<(u32, String)>,
}
