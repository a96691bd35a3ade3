//! One transfer from a reader (file, standard input, a TCP connection) through the splitter
//! into the program writer, and the TCP port that takes transfers one after another like a
//! serial-over-IP DNC port.

use std::io::{self, Read};
use std::net::{SocketAddr, TcpListener};
use std::time::Duration;

use super::error::DncError;
use super::splitter::{ProgramEnd, ProgramSink, ProgramStart, SplitSummary, Splitter};
use super::writer::{ProgramWriter, ReceivedProgram};

/// Read size: large enough for the splitter's fast path, small enough to stay in cache.
const READ_CHUNK: usize = 64 * 1024;

/// How a transfer ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TransferEnd {
    /// End of file, or the sender closed the connection.
    Complete,
    /// Nothing arrived for the idle time-out; the transfer counts as broken.
    IdleTimeout,
    /// A read failed (connection reset, device error).
    Broken(String),
}

/// One transfer's outcome.
#[derive(Debug, Clone)]
pub struct TransferReport {
    pub split: SplitSummary,
    pub programs: Vec<ReceivedProgram>,
    pub end: TransferEnd,
    /// The sender, for a TCP transfer.
    pub peer: Option<SocketAddr>,
}

impl TransferReport {
    /// Programs now on disk under their final names.
    pub fn filed(&self) -> usize {
        self.programs.iter().filter(|p| p.is_filed()).count()
    }
}

/// Receive one transfer to its end. The writer's errors (disk full, no permission) stop the
/// transfer with `Err`; the program being written is then dropped, never half filed.
pub fn receive<R: Read>(
    mut input: R,
    splitter: &mut Splitter,
    writer: &mut ProgramWriter,
) -> Result<TransferReport, DncError> {
    let mut buf = vec![0u8; READ_CHUNK];
    let end = loop {
        match input.read(&mut buf) {
            Ok(0) => break TransferEnd::Complete,
            Ok(n) => {
                if let Err(e) = splitter.feed(&buf[..n], writer) {
                    return Err(reset(splitter, writer, e));
                }
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e)
                if e.kind() == io::ErrorKind::WouldBlock || e.kind() == io::ErrorKind::TimedOut =>
            {
                break TransferEnd::IdleTimeout
            }
            Err(e) => break TransferEnd::Broken(e.to_string()),
        }
    };
    let split = match end {
        TransferEnd::Complete => splitter.finish(writer),
        _ => splitter.abort(writer),
    };
    let split = split.map_err(|e| reset(splitter, writer, e))?;
    Ok(TransferReport {
        split,
        programs: writer.take_records(),
        end,
        peer: None,
    })
}

/// After a writer error: forget the transfer so the next one starts clean.
fn reset(splitter: &mut Splitter, writer: &mut ProgramWriter, e: DncError) -> DncError {
    writer.discard_current();
    let _ = splitter.abort(&mut Discard);
    e
}

/// A sink that drops everything.
struct Discard;

impl ProgramSink for Discard {
    type Error = std::convert::Infallible;
    fn start(&mut self, _: &ProgramStart) -> Result<(), Self::Error> {
        Ok(())
    }
    fn data(&mut self, _: &[u8]) -> Result<(), Self::Error> {
        Ok(())
    }
    fn end(&mut self, _: ProgramEnd) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// Take TCP transfers one after another: each connection is one transfer, ended when the
/// sender closes it. Stops after `max_transfers` when given. `idle_timeout` ends a connection
/// that stays silent that long (as a broken transfer).
pub fn receive_connections(
    listener: &TcpListener,
    max_transfers: Option<usize>,
    idle_timeout: Option<Duration>,
    splitter: &mut Splitter,
    writer: &mut ProgramWriter,
    mut on_transfer: impl FnMut(&TransferReport),
) -> Result<usize, DncError> {
    let local = listener
        .local_addr()
        .map(|a| a.to_string())
        .unwrap_or_else(|_| "listener".to_string());
    let mut count = 0;
    while max_transfers.is_none_or(|m| count < m) {
        let (stream, peer) = match listener.accept() {
            Ok(s) => s,
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::Interrupted | io::ErrorKind::ConnectionAborted
                ) =>
            {
                continue
            }
            Err(e) => return Err(DncError::io(&local, e)),
        };
        stream
            .set_read_timeout(idle_timeout)
            .map_err(|e| DncError::io(peer.to_string(), e))?;
        let mut report = receive(stream, splitter, writer)?;
        report.peer = Some(peer);
        on_transfer(&report);
        count += 1;
    }
    Ok(count)
}
