//! One TCP port taking DNC transfers (`ncchannel receive --listen`): each connection is one
//! transfer, received on its own thread with its own splitter and writer, at most
//! `max_concurrent` at once; the program numbers are shared so concurrent transfers never
//! take the same one. A stop request ends the accepting at once and gives the transfers in
//! progress a bounded grace period; a second one cuts them immediately.

use std::collections::HashMap;
use std::io::{self, Read};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::stop::{StopLevel, StopRequest};
use super::transfer::{receive_limited, TransferLimits, TransferReport};
use super::writer::{ProgramWriter, ReceivedProgram, WriterConfig};
use super::{DncError, Markers, Splitter};

/// A transfer's outcome as the listener hands it on.
pub type TransferResult = Result<TransferReport, DncError>;

/// How long the transfers in progress may still run after a stop request (`--stop-grace`).
pub const DEFAULT_GRACE: Duration = Duration::from_secs(10);

/// After the transfers were cut, how long their threads get to drop their programs (a
/// thread stuck in a write to a hung disk is left behind; the caller removes its temporary
/// file, [`super::temp_files::remove_own`]).
const CUT_WAIT: Duration = Duration::from_secs(2);

/// How often the waits look at the stop request.
const STOP_POLL: Duration = Duration::from_millis(50);

/// What every transfer a port accepts is split and filed with, and how many it takes.
#[derive(Debug, Clone)]
pub struct Listener {
    pub markers: Markers,
    pub writer: WriterConfig,
    /// The next program number, shared by every transfer.
    pub numbers: Arc<AtomicU32>,
    pub limits: TransferLimits,
    /// Stop accepting after this many connections (`None`: until a stop request).
    pub max_transfers: Option<usize>,
    /// Transfers received at once (at least one).
    pub max_concurrent: u16,
    /// After a stop request, how long the transfers in progress may still run before they are
    /// cut (a sender trickling one byte now and then never reaches the idle timeout).
    pub grace: Duration,
    /// Called for every program filed, on the transfer's thread, as it is filed.
    pub program_log: Option<fn(&ReceivedProgram)>,
}

/// The transfers in progress: a handle on each one's connection, to cut it.
#[derive(Default)]
struct Active {
    /// `None` when the handle could not be cloned: that transfer still ends within its idle
    /// timeout and byte limit.
    streams: HashMap<u64, Option<TcpStream>>,
    /// Set before the connections are shut down: their readers then end as cut.
    cut: Arc<AtomicBool>,
}

impl Active {
    fn settle(
        &mut self,
        (id, r): (u64, TransferResult),
        on_settled: &mut impl FnMut(TransferResult),
    ) {
        self.streams.remove(&id);
        on_settled(r);
    }

    fn cut_all(&self) {
        self.cut.store(true, Ordering::Release);
        for s in self.streams.values().flatten() {
            let _ = s.shutdown(Shutdown::Both);
        }
    }
}

impl Listener {
    /// One transfer at a time, no limit on their number, numbers as a fresh writer counts.
    pub fn new(markers: Markers, writer: WriterConfig, limits: TransferLimits) -> Self {
        let numbers = ProgramWriter::new(writer.clone()).numbers();
        Listener {
            markers,
            writer,
            numbers,
            limits,
            max_transfers: None,
            max_concurrent: 1,
            grace: DEFAULT_GRACE,
            program_log: None,
        }
    }

    /// Accept transfers until `max_transfers` or a stop request (a request that comes while
    /// `accept` sleeps takes effect with the next connection: the caller wakes it with one),
    /// then wait for the transfers in progress: without a request for as long as they take
    /// (each within its idle timeout), after one for at most `grace`, after a second one not
    /// at all. `on_end` runs on each transfer's thread as it ends (a log line must not wait
    /// for the accept loop); `on_settled` gets each outcome on this thread, `on_accept_error`
    /// each failed accept (after which the loop pauses briefly, so a persistent failure cannot
    /// spin). Returns the connections accepted.
    pub fn serve(
        &self,
        listener: &TcpListener,
        stop: &StopRequest,
        on_end: impl Fn(Result<&TransferReport, &DncError>) + Send + Sync + 'static,
        mut on_settled: impl FnMut(TransferResult),
        mut on_accept_error: impl FnMut(&io::Error),
    ) -> usize {
        let on_end = Arc::new(on_end);
        let (done_tx, done) = mpsc::channel();
        let mut active = Active::default();
        let mut accepted = 0usize;
        let max_concurrent = usize::from(self.max_concurrent.max(1));
        let running = || stop.level() == StopLevel::Run;
        while self.max_transfers.is_none_or(|m| accepted < m) && running() {
            // A free slot, or a stop request while every slot is held.
            while active.streams.len() >= max_concurrent && running() {
                if let Ok(m) = done.recv_timeout(STOP_POLL) {
                    active.settle(m, &mut on_settled);
                }
            }
            while let Ok(m) = done.try_recv() {
                active.settle(m, &mut on_settled);
            }
            if !running() {
                break;
            }
            let (stream, peer) = match listener.accept() {
                Ok(s) => s,
                Err(e) => {
                    if !matches!(
                        e.kind(),
                        io::ErrorKind::Interrupted | io::ErrorKind::ConnectionAborted
                    ) {
                        on_accept_error(&e);
                        std::thread::sleep(STOP_POLL);
                    }
                    continue;
                }
            };
            // After a stop request, the connection that woke `accept` is not a transfer.
            if !running() {
                break;
            }
            accepted += 1;
            let id = accepted as u64;
            let handle = stream.try_clone().ok();
            let input = Cuttable {
                stream,
                cut: Arc::clone(&active.cut),
                stop: stop.clone(),
                grace: self.grace,
            };
            match self.spawn_transfer(id, input, peer, done_tx.clone(), Arc::clone(&on_end)) {
                Ok(()) => {
                    active.streams.insert(id, handle);
                }
                Err(e) => {
                    let r = Err(DncError::io(peer.to_string(), e));
                    on_end(r.as_ref());
                    on_settled(r);
                }
            }
        }
        drop(done_tx);
        self.drain(&done, &mut active, stop, &mut on_settled);
        accepted
    }
}

impl Listener {
    /// After the accepting: wait for the transfers in progress, cutting them when the stop
    /// request says so; threads that do not end within [`CUT_WAIT`] of the cut are left.
    fn drain(
        &self,
        done: &Receiver<(u64, TransferResult)>,
        active: &mut Active,
        stop: &StopRequest,
        on_settled: &mut impl FnMut(TransferResult),
    ) {
        let mut grace_end: Option<Instant> = None;
        let mut cut_at: Option<Instant> = None;
        while !active.streams.is_empty() {
            match done.recv_timeout(STOP_POLL) {
                Ok(m) => {
                    active.settle(m, on_settled);
                    continue;
                }
                Err(RecvTimeoutError::Disconnected) => break,
                Err(RecvTimeoutError::Timeout) => {}
            }
            let now = Instant::now();
            match cut_at {
                Some(t) if now >= t + CUT_WAIT => break,
                Some(_) => {}
                None => {
                    let due = match stop.level() {
                        StopLevel::Run => false,
                        StopLevel::Graceful => now >= *grace_end.get_or_insert(now + self.grace),
                        StopLevel::Now => true,
                    };
                    if due {
                        active.cut_all();
                        cut_at = Some(now);
                    }
                }
            }
        }
    }

    /// One accepted connection received on its own thread; its outcome is sent on `tx`.
    fn spawn_transfer<F>(
        &self,
        id: u64,
        input: Cuttable,
        peer: SocketAddr,
        tx: Sender<(u64, TransferResult)>,
        on_end: Arc<F>,
    ) -> io::Result<()>
    where
        F: Fn(Result<&TransferReport, &DncError>) + Send + Sync + 'static,
    {
        input.stream.set_read_timeout(self.limits.idle_timeout)?;
        let (markers, cfg, numbers, limits, log) = (
            self.markers.clone(),
            self.writer.clone(),
            Arc::clone(&self.numbers),
            self.limits,
            self.program_log,
        );
        std::thread::Builder::new()
            .name(format!("receive-{peer}"))
            .spawn(move || {
                let mut splitter = Splitter::new(markers);
                let mut writer = ProgramWriter::new(cfg).with_numbers(numbers);
                if let Some(log) = log {
                    writer = writer.with_log(log);
                }
                let r = receive_limited(input, &limits, &mut splitter, &mut writer).map(|mut r| {
                    r.peer = Some(peer);
                    r
                });
                on_end(r.as_ref());
                let _ = tx.send((id, r));
            })
            .map(drop)
    }
}

/// A transfer's connection that the listener can cut: once `cut` is set, every read fails
/// (the transfer ends as broken and its open program is dropped), whatever the shut-down
/// socket itself returns.
struct Cuttable {
    stream: TcpStream,
    cut: Arc<AtomicBool>,
    stop: StopRequest,
    grace: Duration,
}

/// The transfer is over: its connection ends now, although the listener still holds a handle
/// on it (the sender waits for this close to know its transfer was taken).
impl Drop for Cuttable {
    fn drop(&mut self) {
        let _ = self.stream.shutdown(Shutdown::Both);
    }
}

impl Read for Cuttable {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let r = self.stream.read(buf);
        if self.cut.load(Ordering::Acquire) {
            let why = if self.stop.level() == StopLevel::Now {
                "the receiver was stopped at once (a second stop signal)".to_string()
            } else {
                format!(
                    "the receiver stopped: its grace period of {:.1} s ended",
                    self.grace.as_secs_f64()
                )
            };
            return Err(io::Error::new(io::ErrorKind::ConnectionAborted, why));
        }
        r
    }
}
