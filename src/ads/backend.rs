//! The seam between the ADS object table and whatever holds the channels: one door,
//! `call(channel, Op) → Reply`.
//!
//! The object table never touches channel state: it decodes (group, offset, bytes), builds
//! one [`Op`], sends it through [`CncBackend::call`] and encodes the [`Reply`]. The channel
//! answers in its own vocabulary (`crate::machine`), the same one the runtime's other clients
//! (the feeder, the soak, the tests) use, so the objects cannot drift from the channel. The
//! runtime's backend is [`super::channel_backend::ChannelBackend`]: each call is a request
//! into the fixed-cycle loop, answered by the tick that serves it (at most one period later).
//! Calls come from the server's connection threads and may block briefly.
//!
//! Channel numbers are 1-based everywhere here (`1..=channel_count()`), as in the index group
//! `0x20100 + ch`; the object table never passes 0 or a number above the count.
//!
//! The `impl dyn CncBackend` block below holds the few translations of a [`Reply`] that the
//! objects share (a status, a command's result, a stream write's ADS result); they are not
//! part of the door, so a backend implements only the two methods.

use super::result::AdsResult;
use crate::channel::CommandError;
pub use crate::machine::{HmiOp, Op, Reply, Status};
use crate::source::stream::StreamWriteError;

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

/// What the ADS object table needs from the channels. `ch` is 1-based.
pub trait CncBackend: Send + Sync + 'static {
    /// Number of channels; index groups exist for `1..=channel_count()`.
    fn channel_count(&self) -> u16;
    /// Apply `op` to channel `ch` and return the channel's answer. `Err` only when the
    /// request never reached the channel: [`DeviceError::Busy`] when it was not applied in
    /// time and never will be (docs/exactly-once.md), [`DeviceError::NotReady`] when the
    /// runtime is gone, [`DeviceError::NotFound`] for a channel that does not exist.
    fn call(&self, ch: u16, op: Op) -> Result<Reply, DeviceError>;
}

/// One entry of a channel's error history and how many errors it raised in all.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ErrorRecord {
    pub total: u64,
    /// ISG error number and text; `None` when that error is no longer kept.
    pub error: Option<(u32, String)>,
}

/// How a refused command maps onto ADS: a value the channel does not know is 0x706, a
/// command its mode/state does not allow now is 0x708 (the same command succeeds once the
/// state changes), a start without a program or that failed 0x707.
fn command_error(e: &CommandError) -> DeviceError {
    match e {
        CommandError::InvalidValue(_) | CommandError::BadOverride(_) => DeviceError::InvalidValue,
        CommandError::Busy { .. } => DeviceError::Busy,
        CommandError::NoProgram | CommandError::StartFailed { .. } => DeviceError::NotReady,
    }
}

/// The ADS result of a stream write (offset 0x90): 0x708 when the buffer is full (the channel
/// raised warning 11012; retry), 0x705 for an empty or over-long packet (more than 992 bytes,
/// MAX_PROGRAM_STREAM_INPUT_SIZE), 0x706 for a line without CR LF (the channel raised 21476),
/// 0x707 when the channel refuses streaming outright (ERROR, or no streaming program).
fn stream_result(e: &StreamWriteError) -> AdsResult {
    match e {
        StreamWriteError::Full { .. } => AdsResult::BUSY,
        StreamWriteError::Empty | StreamWriteError::TooLarge { .. } => AdsResult::INVALID_SIZE,
        StreamWriteError::NoLineEnd { .. } => AdsResult::INVALID_DATA,
    }
}

impl dyn CncBackend {
    /// Everything the COM, GEO and HLI objects show of a channel, in one snapshot.
    pub fn status(&self, ch: u16) -> Result<Status, DeviceError> {
        match self.call(ch, Op::Status)? {
            Reply::Status(s) => Ok(*s),
            _ => Err(DeviceError::NotReady),
        }
    }

    /// A command whose answer is only "done" or why not.
    pub fn command(&self, ch: u16, op: Op) -> Result<(), DeviceError> {
        match self.call(ch, op)? {
            Reply::Command(Ok(())) | Reply::Done => Ok(()),
            Reply::Command(Err(e)) => Err(command_error(&e)),
            _ => Err(DeviceError::NotReady),
        }
    }

    /// Offer one packet (one or more whole CR LF lines) to the stream buffer.
    pub(crate) fn write_stream(&self, ch: u16, data: &[u8]) -> AdsResult {
        match self.call(ch, Op::WriteStream(std::sync::Arc::from(data))) {
            Ok(Reply::Stream(Ok(()))) => AdsResult::OK,
            Ok(Reply::Stream(Err(e))) => stream_result(&e),
            Ok(_) => AdsResult::NOT_READY,
            Err(e) => e.result(),
        }
    }

    /// Read an external variable `V.E.<name>` (name given without the `V.E.` prefix).
    pub(crate) fn read_ve(&self, ch: u16, name: &str) -> Result<f64, DeviceError> {
        match self.call(ch, Op::ReadExternal(name.to_string()))? {
            Reply::Value(Some(v)) => Ok(v),
            _ => Err(DeviceError::NotFound),
        }
    }

    /// Write an external variable `V.E.<name>`.
    pub fn write_ve(&self, ch: u16, name: &str, value: f64) -> Result<(), DeviceError> {
        match self.call(ch, Op::WriteExternal(name.to_string(), value))? {
            Reply::Value(Some(_)) => Ok(()),
            _ => Err(DeviceError::InvalidValue),
        }
    }

    /// The `index`-th error the channel raised (0 = first), if still kept.
    pub(crate) fn error_record(&self, ch: u16, index: u64) -> Result<ErrorRecord, DeviceError> {
        match self.call(ch, Op::ErrorRecord(index))? {
            Reply::ErrorRecord { total, record } => Ok(ErrorRecord {
                total,
                error: record,
            }),
            _ => Err(DeviceError::NotReady),
        }
    }
}
