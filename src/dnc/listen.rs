//! One TCP port taking DNC transfers (`ncchannel receive --listen`): each connection is one
//! transfer, received on its own thread with its own splitter and writer, at most
//! `max_concurrent` at once; the program numbers are shared so concurrent transfers never
//! take the same one.

use std::io;
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::AtomicU32;
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::Arc;

use super::transfer::{receive_stream, TransferLimits, TransferReport};
use super::writer::{ProgramWriter, ReceivedProgram, WriterConfig};
use super::{DncError, Markers, Splitter};

/// A transfer's outcome as the listener hands it on.
pub type TransferResult = Result<TransferReport, DncError>;

/// What every transfer a port accepts is split and filed with, and how many it takes.
#[derive(Debug, Clone)]
pub struct Listener {
    pub markers: Markers,
    pub writer: WriterConfig,
    /// The next program number, shared by every transfer.
    pub numbers: Arc<AtomicU32>,
    pub limits: TransferLimits,
    /// Stop accepting after this many connections (`None`: until `stop`).
    pub max_transfers: Option<usize>,
    /// Transfers received at once (at least one).
    pub max_concurrent: u16,
    /// Called for every program filed, on the transfer's thread, as it is filed.
    pub program_log: Option<fn(&ReceivedProgram)>,
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
            program_log: None,
        }
    }

    /// Accept transfers until `max_transfers` or until `stop()` says so after an accept (the
    /// connection that woke it is then not a transfer), then wait for the transfers in
    /// progress. `on_end` runs on each transfer's thread as it ends (a log line must not wait
    /// for the accept loop, which sleeps in `accept` until the next sender connects);
    /// `on_settled` gets each outcome on this thread, `on_accept_error` each failed accept
    /// (after which the loop pauses briefly, so a persistent failure cannot spin). Returns
    /// the connections accepted.
    pub fn serve(
        &self,
        listener: &TcpListener,
        stop: impl Fn() -> bool,
        on_end: impl Fn(Result<&TransferReport, &DncError>) + Send + Sync + 'static,
        mut on_settled: impl FnMut(TransferResult),
        mut on_accept_error: impl FnMut(&io::Error),
    ) -> usize {
        let on_end = Arc::new(on_end);
        let (done_tx, done) = mpsc::channel();
        let mut active = 0usize;
        let mut accepted = 0usize;
        let max_concurrent = usize::from(self.max_concurrent.max(1));
        while self.max_transfers.is_none_or(|m| accepted < m) {
            while active >= max_concurrent && settle_next(&done, &mut on_settled) {
                active -= 1;
            }
            while let Ok(r) = done.try_recv() {
                on_settled(r);
                active -= 1;
            }
            let (stream, peer) = match listener.accept() {
                Ok(s) => s,
                Err(e) => {
                    if !matches!(
                        e.kind(),
                        io::ErrorKind::Interrupted | io::ErrorKind::ConnectionAborted
                    ) {
                        on_accept_error(&e);
                        std::thread::sleep(std::time::Duration::from_millis(50));
                    }
                    continue;
                }
            };
            if stop() {
                break;
            }
            accepted += 1;
            match self.spawn_transfer(stream, peer, done_tx.clone(), Arc::clone(&on_end)) {
                Ok(_) => active += 1,
                Err(e) => {
                    let r = Err(DncError::io(peer.to_string(), e));
                    on_end(r.as_ref());
                    on_settled(r);
                }
            }
        }
        // The transfers in progress complete (each within its idle timeout).
        drop(done_tx);
        while active > 0 && settle_next(&done, &mut on_settled) {
            active -= 1;
        }
        accepted
    }

    /// One accepted connection received on its own thread; its outcome is sent on `tx`.
    fn spawn_transfer<F>(
        &self,
        stream: TcpStream,
        peer: SocketAddr,
        tx: Sender<TransferResult>,
        on_end: Arc<F>,
    ) -> io::Result<std::thread::JoinHandle<()>>
    where
        F: Fn(Result<&TransferReport, &DncError>) + Send + Sync + 'static,
    {
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
                let r = receive_stream(stream, peer, &limits, &mut splitter, &mut writer);
                on_end(r.as_ref());
                let _ = tx.send(r);
            })
    }
}

/// Wait for the next transfer to end and settle it; `false` when none is left to wait for.
fn settle_next(
    done: &Receiver<TransferResult>,
    on_settled: &mut impl FnMut(TransferResult),
) -> bool {
    match done.recv() {
        Ok(r) => {
            on_settled(r);
            true
        }
        Err(_) => false,
    }
}
