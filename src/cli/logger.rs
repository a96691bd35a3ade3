//! The binary's logger: `log` records of ncchannel's modules as one stderr line each,
//! `<RFC 3339 UTC time> ncchannel ads: message`, written by a thread of its own, so a stderr
//! nobody reads (a supervisor's full pipe) never holds up the thread that logs.
//!
//! Why not env_logger: it writes in the caller's thread, so a full pipe would block the ADS
//! server's connection threads (and with them new clients and the stop); the server needs
//! neither filters from the environment nor styles. The queue is bounded
//! ([`QUEUE_LINES`]); a line that does not fit is dropped and counted, and the count is
//! written as a line of its own once the writer gets through again. The time is
//! `humantime`'s RFC 3339 form with milliseconds.

use std::io::Write;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, Instant, SystemTime};

use crossbeam_channel::{Receiver, Sender, TrySendError};
use log::{LevelFilter, Log, Metadata, Record};

/// Lines waiting for the writer at most (a few hundred KiB at the longest lines).
pub(crate) const QUEUE_LINES: usize = 1024;

struct StderrLogger;

static LOGGER: StderrLogger = StderrLogger;

/// The queue to the writer thread, and what has gone through it.
struct Queue {
    lines: Sender<String>,
    /// Lines dropped because the queue was full, not yet reported.
    dropped: AtomicU64,
    /// Lines queued and lines the writer has finished with (written or failed), for [`flush`].
    queued: AtomicU64,
    done: AtomicU64,
}

static QUEUE: OnceLock<Queue> = OnceLock::new();

impl Log for StderrLogger {
    fn enabled(&self, metadata: &Metadata<'_>) -> bool {
        metadata.level() <= log::Level::Info
    }

    fn log(&self, record: &Record<'_>) {
        if !self.enabled(record.metadata()) {
            return;
        }
        // "ncchannel::ads::server" -> "ads".
        let part = record.target().split("::").nth(1).unwrap_or("ncchannel");
        let time = humantime::format_rfc3339_millis(SystemTime::now());
        enqueue(format!("{time} ncchannel {part}: {}\n", record.args()));
    }

    fn flush(&self) {
        flush(Duration::from_millis(100));
    }
}

/// Queue one whole line (ending in `\n`); drop and count it when the queue is full.
fn enqueue(text: String) {
    let Some(q) = QUEUE.get() else {
        let _ = std::io::stderr().write_all(text.as_bytes());
        return;
    };
    match q.lines.try_send(text) {
        Ok(()) => {
            q.queued.fetch_add(1, Ordering::Release);
        }
        Err(TrySendError::Full(_)) => {
            q.dropped.fetch_add(1, Ordering::Relaxed);
        }
        // The writer is gone (it could not start): nothing can be written.
        Err(TrySendError::Disconnected(_)) => {}
    }
}

/// A line of the command's own (not a `log` record: no part), led by its RFC 3339 time,
/// through the same queue, for commands that must never wait for stderr (`serve`).
pub(crate) fn line(msg: std::fmt::Arguments<'_>) {
    let time = humantime::format_rfc3339_millis(SystemTime::now());
    enqueue(format!("{time} {msg}\n"));
}

/// Wait until every queued line is written, at most `within` (a reader that does not read
/// costs the caller no more than that).
pub(crate) fn flush(within: Duration) {
    let Some(q) = QUEUE.get() else { return };
    let until = Instant::now() + within;
    while q.done.load(Ordering::Acquire) < q.queued.load(Ordering::Acquire)
        && Instant::now() < until
    {
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// The writer: its own handle on stderr (a duplicate of the descriptor, so a write stuck on
/// a full pipe holds no lock anyone else takes), whole lines, the drop count first.
fn write_loop(rx: &Receiver<String>, q: &Queue) {
    let mut err: Box<dyn Write> = match own_stderr() {
        Some(f) => Box::new(f),
        None => Box::new(std::io::stderr()),
    };
    for text in rx.iter() {
        let dropped = q.dropped.swap(0, Ordering::Relaxed);
        if dropped > 0 {
            let time = humantime::format_rfc3339_millis(SystemTime::now());
            let _ = writeln!(
                err,
                "{time} ncchannel: {dropped} log lines dropped (stderr was not read)"
            );
        }
        let _ = err.write_all(text.as_bytes());
        q.done.fetch_add(1, Ordering::Release);
    }
}

#[cfg(unix)]
fn own_stderr() -> Option<std::fs::File> {
    use std::os::fd::AsFd;
    let fd = std::io::stderr().as_fd().try_clone_to_owned().ok()?;
    Some(std::fs::File::from(fd))
}

#[cfg(not(unix))]
fn own_stderr() -> Option<std::fs::File> {
    None
}

/// Install the logger and start its writer (once; a second call is a no-op).
pub fn init() {
    if log::set_logger(&LOGGER).is_err() {
        return;
    }
    let (tx, rx) = crossbeam_channel::bounded(QUEUE_LINES);
    let queue = QUEUE.get_or_init(|| Queue {
        lines: tx,
        dropped: AtomicU64::new(0),
        queued: AtomicU64::new(0),
        done: AtomicU64::new(0),
    });
    let started = std::thread::Builder::new()
        .name("ncchannel-log".into())
        .spawn(move || write_loop(&rx, queue));
    if started.is_ok() {
        log::set_max_level(LevelFilter::Info);
    }
}

/// The first stderr line of every serve, plain or `--soak` (`soak` is `soak FILE, ` or
/// empty), after its time as every serve line: where the server listens and which NetId it
/// answers, the route service's UDP address, the channels and the cycle. Tests and
/// supervisors parse it: the second word on is `listening on ADDR (…`.
pub(super) fn listening_line(
    server: &crate::ads::ServerHandle,
    net_id: Option<crate::vocab::ams::AmsNetId>,
    soak: &str,
    nch: u16,
    period: Duration,
) -> String {
    let net_id = net_id.unwrap_or(crate::vocab::ams::DEFAULT_NET_ID);
    let udp = server
        .route_service_addr()
        .map(|a| format!("route service UDP {a}, "))
        .unwrap_or_default();
    format!(
        "listening on {} (AMS NetId {net_id}, port 553, also as {}, {udp}{soak}{nch} channel(s), cycle {} µs)",
        server.local_addr(),
        crate::vocab::ams::AmsNetId::LOCAL,
        period.as_micros()
    )
}
