//! The object table's backend over the real channels: each call becomes a request into the
//! runtime's fixed-cycle loop and waits for the answer of the tick that serves it.

use std::time::Duration;

use crossbeam_channel::{RecvTimeoutError, Sender};

use super::backend::{CncBackend, DeviceError, ErrorRecord, HmiOp, StreamFill, StreamWriteOutcome};
use crate::channel::CommandError;
use crate::machine::{Op, Reply, Request, Status};
use crate::source::stream::StreamWriteError;

/// How long a connection thread waits for the runtime. A tick answers within one period;
/// far longer means the runtime is stopped or hopelessly late, and the client hears "busy".
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(2);

pub struct ChannelBackend {
    requests: Sender<Request>,
    channels: u16,
    /// How long a call waits before answering "busy, not applied" ([`REPLY_TIMEOUT`]).
    reply_timeout: Duration,
}

impl ChannelBackend {
    pub fn new(requests: Sender<Request>, channels: u16) -> Self {
        ChannelBackend {
            requests,
            channels,
            reply_timeout: REPLY_TIMEOUT,
        }
    }

    /// The same backend answering "busy" after `timeout` instead of [`REPLY_TIMEOUT`].
    pub fn with_reply_timeout(mut self, timeout: Duration) -> Self {
        self.reply_timeout = timeout;
        self
    }

    /// One request, answered exactly once: by the runtime's reply when the runtime took the
    /// request's claim, or by "busy" (0x708, not applied) when this side took it first after
    /// `reply_timeout`. Once the runtime holds the claim its reply is waited for without a
    /// limit: it is being applied in the tick running now, and answering "busy" then would
    /// make a retrying client apply it twice.
    fn call(&self, ch: u16, op: Op) -> Result<Reply, DeviceError> {
        let (tx, rx) = crossbeam_channel::bounded(1);
        let (req, claim) = Request::new(u32::from(ch), op, tx);
        self.requests.send(req).map_err(|_| DeviceError::NotReady)?;
        let reply = match rx.recv_timeout(self.reply_timeout) {
            Ok(r) => Ok(r),
            Err(RecvTimeoutError::Timeout) if claim.take() => return Err(DeviceError::Busy),
            // The runtime has it: the answer comes when its serve returns.
            Err(RecvTimeoutError::Timeout) => rx.recv().map_err(|_| DeviceError::NotReady),
            // The runtime stopped and dropped the request unapplied.
            Err(RecvTimeoutError::Disconnected) => Err(DeviceError::NotReady),
        }?;
        match reply {
            Reply::NoChannel => Err(DeviceError::NotFound),
            r => Ok(r),
        }
    }

    fn status(&self, ch: u16) -> Result<Status, DeviceError> {
        match self.call(ch, Op::Status)? {
            Reply::Status(s) => Ok(*s),
            _ => Err(DeviceError::NotReady),
        }
    }

    fn command(&self, ch: u16, op: Op) -> Result<(), DeviceError> {
        match self.call(ch, op)? {
            Reply::Command(Ok(())) | Reply::Done => Ok(()),
            Reply::Command(Err(e)) => Err(command_error(&e)),
            _ => Err(DeviceError::NotReady),
        }
    }
}

fn command_error(e: &CommandError) -> DeviceError {
    match e {
        CommandError::InvalidValue(_) | CommandError::BadOverride(_) => DeviceError::InvalidValue,
        CommandError::Busy { .. } => DeviceError::Busy,
        CommandError::NoProgram | CommandError::StartFailed { .. } => DeviceError::NotReady,
    }
}

impl CncBackend for ChannelBackend {
    fn channel_count(&self) -> u16 {
        self.channels
    }

    fn stream_write(&self, ch: u16, data: &[u8]) -> StreamWriteOutcome {
        match self.call(ch, Op::WriteStream(data.to_vec())) {
            Ok(Reply::Stream(Ok(()))) => StreamWriteOutcome::Accepted,
            Ok(Reply::Stream(Err(e))) => match e {
                StreamWriteError::Full { .. } => StreamWriteOutcome::Full,
                StreamWriteError::Empty | StreamWriteError::TooLarge { .. } => {
                    StreamWriteOutcome::BadSize
                }
                StreamWriteError::NoLineEnd { .. } => StreamWriteOutcome::NoLineEnd,
            },
            Ok(_) => StreamWriteOutcome::Refused(DeviceError::NotReady),
            Err(e) => StreamWriteOutcome::Refused(e),
        }
    }

    fn mode_state(&self, ch: u16) -> Result<(i32, i32), DeviceError> {
        let s = self.status(ch)?;
        Ok((s.mode as i32, s.state as i32))
    }

    fn command_mode(&self, ch: u16, mode: i32) -> Result<(), DeviceError> {
        self.command(ch, Op::CommandMode(mode))
    }

    fn command_state(&self, ch: u16, state: i32) -> Result<(), DeviceError> {
        self.command(ch, Op::CommandState(state))
    }

    fn command_program(&self, ch: u16, name: &str) -> Result<(), DeviceError> {
        self.command(ch, Op::SetProgram(name.to_string()))
    }

    fn hold(&self, ch: u16) -> Result<(), DeviceError> {
        self.command(ch, Op::Hold)
    }

    fn resume(&self, ch: u16) -> Result<(), DeviceError> {
        self.command(ch, Op::Resume)
    }

    fn reset(&self, ch: u16) -> Result<(), DeviceError> {
        self.command(ch, Op::Reset)
    }

    fn last_error(&self, ch: u16) -> Result<String, DeviceError> {
        Ok(self
            .status(ch)?
            .last_error
            .map(|(code, msg)| format!("{code} {msg}"))
            .unwrap_or_default())
    }

    fn stream_fill(&self, ch: u16) -> Result<StreamFill, DeviceError> {
        let s = self.status(ch)?;
        Ok(StreamFill {
            used_bytes: s.stream_used as u32,
            free_bytes: s.stream_free as u32,
        })
    }

    /// Blocks that took effect since the channel started: monotonic across programs, so a
    /// client can watch progress (the decoder's line counter restarts with each program).
    fn block_counter(&self, ch: u16) -> Result<u64, DeviceError> {
        Ok(self.status(ch)?.blocks)
    }

    fn positions(&self, ch: u16) -> Result<Vec<f64>, DeviceError> {
        Ok(self
            .status(ch)?
            .positions
            .into_iter()
            .map(|(_, v)| v)
            .collect())
    }

    fn set_override(&self, ch: u16, percent: f64) -> Result<(), DeviceError> {
        self.command(ch, Op::SetOverride(percent))
    }

    fn read_ve(&self, ch: u16, name: &str) -> Result<f64, DeviceError> {
        match self.call(ch, Op::ReadExternal(name.to_string()))? {
            Reply::Value(Some(v)) => Ok(v),
            _ => Err(DeviceError::NotFound),
        }
    }

    fn write_ve(&self, ch: u16, name: &str, value: f64) -> Result<(), DeviceError> {
        match self.call(ch, Op::WriteExternal(name.to_string(), value))? {
            Reply::Value(Some(_)) => Ok(()),
            _ => Err(DeviceError::InvalidValue),
        }
    }

    fn view(&self, ch: u16) -> Result<Status, DeviceError> {
        self.status(ch)
    }

    fn hmi(&self, ch: u16, op: HmiOp) -> Result<(), DeviceError> {
        self.command(ch, Op::Hmi(op))
    }

    fn error_record(&self, ch: u16, index: u64) -> Result<ErrorRecord, DeviceError> {
        match self.call(ch, Op::ErrorRecord(index))? {
            Reply::ErrorRecord { total, record } => Ok(ErrorRecord {
                total,
                error: record,
            }),
            _ => Err(DeviceError::NotReady),
        }
    }
}
