//! The channels seen from other threads: one door, `call(channel, Op) → Reply`
//! ([`CncBackend`]), shared by the ADS object table and the web view, and its runtime
//! implementation ([`ChannelBackend`]): each call becomes a request into the fixed-cycle loop
//! and waits for the answer of the tick that serves it, answered exactly once — applied, or
//! busy and not applied (the claim, docs/exactly-once.md). [`Ticking`] runs a machine so on a
//! thread of its own.
//!
//! Channel numbers are 1-based everywhere here (`1..=channel_count()`). The `impl dyn
//! CncBackend` block holds the few translations of a [`Reply`] that callers share (a status,
//! a command's result); they are not part of the door, so a backend implements only the two
//! methods.

use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{RecvTimeoutError, Sender};

use super::{Machine, Op, Reply, Request, Status};
pub use crate::channel::door::{DeviceError, Source};
use crate::channel::CommandError;
use crate::runtime::{Clock, Runtime, StopHandle};

/// How long a connection thread waits for the runtime by default (runtime.toml
/// `ads.reply_timeout_ms`; `vocab::ams` says why 500 ms). A tick answers within one period;
/// far longer means the runtime is stopped or hopelessly late, and the client hears "busy".
pub(crate) use crate::vocab::ams::DEFAULT_REPLY_TIMEOUT as REPLY_TIMEOUT;

/// While the runtime has left a call unanswered, later calls wait at most this long: a
/// runtime that is back answers within a few periods. A request queued behind others on its
/// connection (a client that sends several at once) whose reply timeout, counted from its
/// arrival, has passed by its turn is answered "busy" without a call
/// ([`CncBackend::overdue`]), so every request in flight is answered within `reply_timeout`
/// (and at most one `STALLED_WAIT`) of its own arrival, not one `STALLED_WAIT` after the one
/// before it.
const STALLED_WAIT: Duration = Duration::from_millis(50);

pub struct ChannelBackend {
    requests: Sender<Request>,
    channels: u16,
    /// How long a call waits before answering "busy, not applied" ([`REPLY_TIMEOUT`]).
    reply_timeout: Duration,
    /// A call timed out and no reply has come since: the runtime is stalled (or stopped).
    stalled: AtomicBool,
}

impl ChannelBackend {
    pub fn new(requests: Sender<Request>, channels: u16) -> Self {
        ChannelBackend {
            requests,
            channels,
            reply_timeout: REPLY_TIMEOUT,
            stalled: AtomicBool::new(false),
        }
    }

    /// The same backend answering "busy" after `timeout` instead of [`REPLY_TIMEOUT`].
    pub fn with_reply_timeout(mut self, timeout: Duration) -> Self {
        self.reply_timeout = timeout;
        self
    }

    /// How long the next call waits for the runtime.
    fn wait_limit(&self) -> Duration {
        if self.stalled.load(Ordering::Relaxed) {
            self.reply_timeout.min(STALLED_WAIT)
        } else {
            self.reply_timeout
        }
    }
}

impl CncBackend for ChannelBackend {
    fn channel_count(&self) -> u16 {
        self.channels
    }

    /// One request, answered exactly once: by the runtime's reply when the runtime took the
    /// request's claim, or by "busy" (0x708, not applied) when this side took it first after
    /// `reply_timeout` ([`STALLED_WAIT`] while an earlier call is unanswered). Once the runtime holds the claim its reply is waited for without a
    /// limit: it is being applied in the tick running now, and answering "busy" then would
    /// make a retrying client apply it twice.
    /// Stalled, and `reply_timeout` has passed since `arrived`. A request still inside its
    /// reply timeout makes its call (at most [`STALLED_WAIT`]), so a runtime that is back is
    /// noticed even when `reply_timeout` is no longer than that wait.
    fn overdue(&self, arrived: Instant) -> bool {
        self.stalled.load(Ordering::Relaxed) && arrived.elapsed() >= self.reply_timeout
    }

    fn call(&self, ch: u16, op: Op) -> Result<Reply, DeviceError> {
        let (tx, rx) = crossbeam_channel::bounded(1);
        let (req, claim) = Request::new(u32::from(ch), op, tx);
        self.requests.send(req).map_err(|_| DeviceError::NotReady)?;
        let reply = match rx.recv_timeout(self.wait_limit()) {
            Ok(r) => {
                self.stalled.store(false, Ordering::Relaxed);
                Ok(r)
            }
            Err(RecvTimeoutError::Timeout) if claim.take() => {
                self.stalled.store(true, Ordering::Relaxed);
                return Err(DeviceError::Busy);
            }
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
}

/// A machine ticking in real time on a thread of its own, reached through the
/// [`ChannelBackend`] [`Ticking::start`] returns: the shape of `ncchannel serve`, for callers
/// that run the channels in-process (the ADS tests drive real channels through it).
pub struct Ticking {
    stop: StopHandle,
    thread: Option<JoinHandle<Machine>>,
}

impl Ticking {
    /// Start `machine` at `period` (real time) and give the backend that reaches its channels.
    pub fn start(machine: Machine, period: Duration) -> io::Result<(ChannelBackend, Ticking)> {
        let channels = u16::try_from(machine.channels().len()).unwrap_or(u16::MAX);
        let (mut rt, tx) = Runtime::new(machine, period, Clock::RealTime);
        let stop = rt.stop_handle();
        let thread = std::thread::Builder::new()
            .name("runtime".into())
            .spawn(move || {
                rt.run(None);
                rt.into_inner().0
            })?;
        Ok((
            ChannelBackend::new(tx, channels),
            Ticking {
                stop,
                thread: Some(thread),
            },
        ))
    }

    /// Stop at the next tick boundary and give the machine back (`None` if its thread
    /// panicked).
    pub fn stop(mut self) -> Option<Machine> {
        self.stop_and_join()
    }

    fn stop_and_join(&mut self) -> Option<Machine> {
        self.stop.stop();
        self.thread.take()?.join().ok()
    }
}

impl Drop for Ticking {
    fn drop(&mut self) {
        self.stop_and_join();
    }
}

/// The remote handle of the channels, shared by the ADS object table and the web view.
/// `ch` is 1-based.
pub trait CncBackend: Send + Sync + 'static {
    /// Number of channels; index groups exist for `1..=channel_count()`.
    fn channel_count(&self) -> u16;
    /// Apply `op` to channel `ch` and return the channel's answer. `Err` only when the
    /// request never reached the channel: [`DeviceError::Busy`] when it was not applied in
    /// time and never will be (docs/exactly-once.md), [`DeviceError::NotReady`] when the
    /// runtime is gone, [`DeviceError::NotFound`] for a channel that does not exist.
    fn call(&self, ch: u16, op: Op) -> Result<Reply, DeviceError>;
    /// Whether a request that reached the caller at `arrived` should be answered "busy"
    /// (0x708, not applied) without a call: the runtime is known to be stalled and the
    /// request's reply timeout, counted from its arrival, has passed. A backend that never
    /// stalls says no.
    fn overdue(&self, arrived: Instant) -> bool {
        let _ = arrived;
        false
    }
}

/// One entry of a channel's error history and how many errors it raised in all.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ErrorRecord {
    pub total: u64,
    /// ISG error number and text; `None` when that error is no longer kept.
    pub error: Option<(u32, String)>,
}

/// How a refused command maps onto a device error: a value the channel does not know is
/// invalid (ADS 0x706), a command its mode/state does not allow is refused (0x707: retrying
/// the same command cannot succeed until a reset or the program's end changes the state, so
/// it is not "busy, retry"), a start without a program or that failed is not ready (0x707).
fn command_error(e: &CommandError) -> DeviceError {
    match e {
        CommandError::InvalidValue(_) | CommandError::BadOverride(_) => DeviceError::InvalidValue,
        CommandError::Busy { .. } => DeviceError::Refused,
        CommandError::NoProgram | CommandError::StartFailed { .. } => DeviceError::NotReady,
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

    /// Write an external variable `V.E.<name>`.
    pub fn write_ve(&self, ch: u16, name: &str, value: f64) -> Result<(), DeviceError> {
        match self.call(ch, Op::WriteExternal(name.to_string(), value))? {
            Reply::Value(Some(_)) => Ok(()),
            _ => Err(DeviceError::InvalidValue),
        }
    }

    /// Read `V.E.<name>` (given without the `V.E.` prefix) with its declared type (numbers)
    /// or length (strings).
    pub(crate) fn read_ve_typed(
        &self,
        ch: u16,
        name: &str,
    ) -> Result<crate::channel::ExternalValue, DeviceError> {
        (&mut Live::new(self) as &mut dyn Source).read_ve_typed(ch, name)
    }

    /// Write a string into `V.E.<name>`.
    pub(crate) fn write_ve_str(&self, ch: u16, name: &str, text: &str) -> Result<(), DeviceError> {
        match self.call(ch, Op::WriteExternalStr(name.to_string(), text.to_string()))? {
            Reply::Value(Some(_)) => Ok(()),
            _ => Err(DeviceError::InvalidValue),
        }
    }

    /// The `index`-th error the channel raised (0 = first), if still kept.
    pub(crate) fn error_record(&self, ch: u16, index: u64) -> Result<ErrorRecord, DeviceError> {
        (&mut Live::new(self) as &mut dyn Source).error_record(ch, index)
    }
}

/// The read-only requests an encoder makes, translated once for every [`Source`].
impl dyn Source + '_ {
    /// Read `V.E.<name>` (given without the `V.E.` prefix) with its declared type (numbers)
    /// or length (strings).
    pub(crate) fn read_ve_typed(
        &mut self,
        ch: u16,
        name: &str,
    ) -> Result<crate::channel::ExternalValue, DeviceError> {
        match self.call(ch, Op::ReadExternalTyped(name.to_string()))? {
            Reply::External(Some(v)) => Ok(v),
            _ => Err(DeviceError::NotFound),
        }
    }

    /// The `index`-th error the channel raised (0 = first), if still kept.
    pub(crate) fn error_record(&mut self, ch: u16, index: u64) -> Result<ErrorRecord, DeviceError> {
        match self.call(ch, Op::ErrorRecord(index))? {
            Reply::ErrorRecord { total, record } => Ok(ErrorRecord {
                total,
                error: record,
            }),
            _ => Err(DeviceError::NotReady),
        }
    }
}

/// The runtime asked now as an encoder's [`Source`] (an ADS Read, the notifier thread): each
/// channel's status asked at most once per encoding.
pub struct Live<'b> {
    backend: &'b dyn CncBackend,
    statuses: Vec<Option<Box<Status>>>,
}

impl<'b> Live<'b> {
    pub fn new(backend: &'b dyn CncBackend) -> Self {
        Live {
            backend,
            statuses: Vec::new(),
        }
    }
}

impl Source for Live<'_> {
    fn channel_count(&self) -> u16 {
        self.backend.channel_count()
    }

    fn status(&mut self, ch: u16) -> Result<&Status, DeviceError> {
        let i = usize::from(ch)
            .checked_sub(1)
            .filter(|&i| i < usize::from(self.backend.channel_count()))
            .ok_or(DeviceError::NotFound)?;
        if self.statuses.len() <= i {
            self.statuses.resize_with(i + 1, || None);
        }
        if self.statuses[i].is_none() {
            match self.backend.call(ch, Op::Status)? {
                Reply::Status(s) => self.statuses[i] = Some(s),
                _ => return Err(DeviceError::NotReady),
            }
        }
        self.statuses[i].as_deref().ok_or(DeviceError::NotReady)
    }

    fn call(&mut self, ch: u16, op: Op) -> Result<Reply, DeviceError> {
        self.backend.call(ch, op)
    }
}
