//! The ADS side of the channels' remote handle ([`crate::machine::remote`]): the object
//! table never touches channel state; it decodes (group, offset, bytes), builds one [`Op`],
//! sends it through [`CncBackend::call`] and encodes the [`Reply`] and the [`DeviceError`]s as
//! ADS results. Calls come from the server's connection threads and may block briefly.
//!
//! Channel numbers are 1-based everywhere here, as in the index group `0x20100 + ch`; the
//! object table never passes 0 or a number above the count.

use super::result::AdsResult;
pub use crate::machine::remote::{CncBackend, DeviceError, ErrorRecord};
use crate::machine::StreamWriteError;
pub use crate::machine::{HmiOp, Op, Reply, Status};

impl From<DeviceError> for AdsResult {
    fn from(e: DeviceError) -> Self {
        match e {
            DeviceError::NotReady | DeviceError::Refused => AdsResult::NOT_READY,
            DeviceError::Busy => AdsResult::BUSY,
            DeviceError::InvalidValue => AdsResult::INVALID_DATA,
            DeviceError::NotFound => AdsResult::NOT_FOUND,
        }
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

/// Offer one packet (one or more whole CR LF lines) to channel `ch`'s stream buffer.
pub(crate) fn write_stream(backend: &dyn CncBackend, ch: u16, data: &[u8]) -> AdsResult {
    match backend.call(ch, Op::WriteStream(std::sync::Arc::from(data))) {
        Ok(Reply::Stream(Ok(()))) => AdsResult::OK,
        Ok(Reply::Stream(Err(e))) => stream_result(&e),
        Ok(_) => AdsResult::NOT_READY,
        Err(e) => e.into(),
    }
}

pub use crate::machine::remote::Live;
pub use crate::machine::watch::{Encode, Source};

/// An object's encoder as its table builds it: the bytes read from a [`Source`], or why not.
/// A Read runs it once on [`Live`]; a notification evaluated in the cycle runs it every due
/// tick ([`in_cycle`]).
pub(crate) type ObjectEncoder = Box<dyn Fn(&mut dyn Source) -> Result<Vec<u8>, AdsResult> + Send>;

/// The watch's encoder of an object's encoder: a failure is "nothing to send now".
pub(crate) fn in_cycle(e: ObjectEncoder) -> Encode {
    Box::new(move |s: &mut dyn Source| e(s).ok())
}
