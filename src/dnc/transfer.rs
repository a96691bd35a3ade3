//! One transfer from a reader (file, standard input, a TCP connection) through the splitter
//! into the program writer, and the TCP port that takes transfers one after another like a
//! serial-over-IP DNC port.

use std::io::{self, Read};
use std::net::{SocketAddr, TcpStream};
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
    /// The transfer reached one of its [`TransferLimits`]; the rest was not read.
    LimitReached(Limit),
    /// The disk refused a program ([`super::Disposition::WriteFailed`] names it): the
    /// transfer stopped there and the rest was not taken.
    WriteFailed(String),
}

/// Which of the [`TransferLimits`] ended a transfer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Limit {
    #[error("more than {0} bytes")]
    Bytes(u64),
    #[error("more than {0} programs")]
    Programs(usize),
}

/// Bounds on one transfer, so one sender cannot fill the disk or hold the port for ever.
/// `None` is unbounded (a file or standard input the operator chose).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TransferLimits {
    /// A connection silent this long ends as [`TransferEnd::IdleTimeout`].
    pub idle_timeout: Option<Duration>,
    /// Bytes read at most; the program in progress at the limit is cut off.
    pub max_bytes: Option<u64>,
    /// Programs delivered at most; the next one is dropped and the transfer ends.
    pub max_programs: Option<usize>,
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

/// Receive one transfer to its end. A program the disk refuses (full, no permission) is lost,
/// never half filed, and ends the transfer as [`TransferEnd::WriteFailed`]; the programs filed
/// before it stay filed and are reported.
pub fn receive<R: Read>(
    input: R,
    splitter: &mut Splitter,
    writer: &mut ProgramWriter,
) -> Result<TransferReport, DncError> {
    receive_limited(input, &TransferLimits::default(), splitter, writer)
}

/// [`receive`] within `limits` (the idle timeout is the reader's own: a socket's read
/// timeout, set by the caller).
pub fn receive_limited<R: Read>(
    mut input: R,
    limits: &TransferLimits,
    splitter: &mut Splitter,
    writer: &mut ProgramWriter,
) -> Result<TransferReport, DncError> {
    let mut buf = vec![0u8; READ_CHUNK];
    let mut bytes: u64 = 0;
    writer.limit_programs(limits.max_programs);
    let end = loop {
        if let Some(max) = limits.max_programs.filter(|_| writer.over_limit()) {
            break TransferEnd::LimitReached(Limit::Programs(max));
        }
        match input.read(&mut buf) {
            Ok(0) => break TransferEnd::Complete,
            Ok(n) => {
                let allowed = limits
                    .max_bytes
                    .map_or(n, |m| n.min(usize::try_from(m - bytes).unwrap_or(n)));
                if let Err(e) = splitter.feed(&buf[..allowed], writer) {
                    return Ok(write_failed(splitter, writer, e));
                }
                bytes += allowed as u64;
                if allowed < n {
                    break TransferEnd::LimitReached(Limit::Bytes(bytes));
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
    let split = match split {
        Ok(s) => s,
        Err(e) => return Ok(write_failed(splitter, writer, e)),
    };
    writer.limit_programs(None);
    Ok(TransferReport {
        split,
        programs: writer.take_records(),
        end,
        peer: None,
    })
}

/// After a writer error: the transfer ends with what was filed and the program lost (the
/// writer's records), and both machines are reset so the next transfer starts clean.
fn write_failed(
    splitter: &mut Splitter,
    writer: &mut ProgramWriter,
    e: DncError,
) -> TransferReport {
    writer.discard_current();
    writer.limit_programs(None);
    let split = match splitter.abort(&mut Discard) {
        Ok(s) => s,
        Err(never) => match never {},
    };
    TransferReport {
        split,
        programs: writer.take_records(),
        end: TransferEnd::WriteFailed(e.to_string()),
        peer: None,
    }
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

/// One accepted TCP transfer within `limits`.
pub fn receive_stream(
    stream: TcpStream,
    peer: SocketAddr,
    limits: &TransferLimits,
    splitter: &mut Splitter,
    writer: &mut ProgramWriter,
) -> Result<TransferReport, DncError> {
    stream
        .set_read_timeout(limits.idle_timeout)
        .map_err(|e| DncError::io(peer.to_string(), e))?;
    let mut report = receive_limited(stream, limits, splitter, writer)?;
    report.peer = Some(peer);
    Ok(report)
}
