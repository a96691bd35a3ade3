//! The object table's backend over the real channels: each call becomes a request into the
//! runtime's fixed-cycle loop and waits for the answer of the tick that serves it.

use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

use crossbeam_channel::{RecvTimeoutError, Sender};

use super::backend::{CncBackend, DeviceError};
use crate::machine::{Machine, Op, Reply, Request};
use crate::runtime::{Clock, Runtime, StopHandle};

/// How long a connection thread waits for the runtime by default (runtime.toml
/// `ads.reply_timeout_ms`; `vocab::ams` says why 500 ms). A tick answers within one period;
/// far longer means the runtime is stopped or hopelessly late, and the client hears "busy".
pub(crate) use crate::vocab::ams::DEFAULT_REPLY_TIMEOUT as REPLY_TIMEOUT;

/// While the runtime has left a call unanswered, later calls wait at most this long: a
/// runtime that is back answers within a few periods, and a connection's requests queued
/// behind each other (a client that sends several at once) are each answered "busy" within
/// `reply_timeout` + n × this, not n × `reply_timeout`.
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
