//! The event log: what happened in a channel, one JSON object a line (JSON Lines).
//!
//! The tick only pushes [`Event`] values into an [`EventBuffer`] (no text, no I/O); the
//! buffer's batch leaves through [`EventLog::emit`] to a writer thread that serialises and
//! writes in order. With logging off, [`EventBuffer::enabled`] is false and the channel skips
//! building events at all.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, TrySendError};
use serde::Serialize;

use crate::runtime::Tick;

/// One event: when, where, what. Serialises as `{"tick":…,"t":…,"ch":…,"ev":"…",…fields}`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Event {
    pub tick: u64,
    /// Channel time in seconds.
    pub t: f64,
    /// Channel number, 1-based.
    pub ch: u32,
    #[serde(flatten)]
    pub kind: EventKind,
}

/// The event vocabulary of DESIGN.md; the variant name in snake_case is the `ev` field.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "ev", rename_all = "snake_case")]
pub enum EventKind {
    /// Channel mode and state changed.
    State {
        mode: String,
        state: String,
    },
    /// A program started; `stream` when it reads from the stream interface.
    ProgramStart {
        prog: String,
        stream: bool,
    },
    /// A program ended; `end` is how (`M30`, `M2`, `M17`, `M29`, `reset`, `error`).
    ProgramEnd {
        prog: String,
        end: String,
    },
    /// A block that took effect: program, 1-based line, byte offset of the line in the
    /// program (stream: since stream start), block counter, block number (`N`), text.
    Block {
        prog: String,
        line: u64,
        offset: u64,
        counter: u64,
        n: Option<u64>,
        text: String,
    },
    /// A stream write: its length, whether accepted, the ISG code raised when not (if any).
    Write {
        bytes: u64,
        ok: bool,
        code: Option<u32>,
    },
    /// The decoder took a segment out of the stream buffer.
    Segment {
        bytes: u64,
    },
    /// Data dropped: the rest of a segment after a program end, or the buffer at reset.
    Discard {
        bytes: u64,
    },
    Warning {
        code: u32,
        msg: String,
    },
    Error {
        code: u32,
        msg: String,
        prog: Option<String>,
        line: Option<u64>,
    },
    /// Motion stopped for lack of stream data; `held`: blocks the lookahead window holds and
    /// may not release yet (0 when everything received has run).
    Interrupt {
        held: u64,
    },
    /// Motion resumed after an interrupt.
    Resume,
    /// A file cache operation (`load`, `refresh`, `clear`, `clear_all`, `hit`).
    Cache {
        op: String,
        file: Option<String>,
    },
    /// `#FLUSH` of the given kind (`plain`, `continue`, `wait`).
    Flush {
        kind: String,
    },
    /// Block search: the target and whether it was found.
    Search {
        target: String,
        found: bool,
    },
    /// `#MSG` (`save`: `#MSG SAVE`): an operator message from the NC program.
    Message {
        text: String,
        save: bool,
    },
    /// An H function decoded (0..=65535), for the PLC side.
    HFunction {
        h: u32,
    },
    /// M00 (`m` 0) or M01 (`m` 1, M01 switch on) reached: the channel holds until the next
    /// start.
    ProgramStop {
        m: u32,
    },
}

impl Event {
    pub fn new(tick: &Tick, ch: u32, kind: EventKind) -> Self {
        Event {
            tick: tick.index,
            t: tick.seconds(),
            ch,
            kind,
        }
    }

    /// The event as one JSON line (without the newline).
    pub fn to_json(&self) -> String {
        // Serialising plain strings, numbers and options cannot fail.
        serde_json::to_string(self).unwrap_or_default()
    }
}

/// Where the tick puts its events: a `Vec` reused from tick to tick, or nothing when logging
/// is off.
#[derive(Debug, Default)]
pub struct EventBuffer {
    enabled: bool,
    events: Vec<Event>,
}

impl EventBuffer {
    pub fn new(enabled: bool) -> Self {
        EventBuffer {
            enabled,
            events: Vec::new(),
        }
    }

    /// Whether events are wanted; check before building one with text in it.
    #[inline]
    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// Add one event (dropped when disabled).
    #[inline]
    pub fn push(&mut self, tick: &Tick, ch: u32, kind: EventKind) {
        if self.enabled {
            self.events.push(Event::new(tick, ch, kind));
        }
    }

    /// Events collected since the last drain.
    pub fn events(&self) -> &[Event] {
        &self.events
    }

    pub fn len(&self) -> usize {
        self.events.len()
    }

    pub fn is_empty(&self) -> bool {
        self.events.is_empty()
    }

    /// Hand the collected events to `log` (batch move, no serialisation here).
    pub fn flush_to(&mut self, log: &mut EventLog) {
        log.emit(&mut self.events);
    }
}

/// Batches in flight between the tick and the writer thread before the writer's recycled
/// `Vec`s run out and new ones are allocated.
const RECYCLE_BATCHES: usize = 16;

/// A file's buffered lines reach the file at least this often, so a `tail -f` of the log
/// lags the channel by no more than this plus a tick.
pub const FLUSH_INTERVAL: Duration = Duration::from_millis(100);

/// When the writer thread hands its buffer to the operating system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlushPolicy {
    /// After every batch (one tick's events): a pipe's reader sees each tick at once.
    EveryBatch,
    /// At most [`FLUSH_INTERVAL`] after an event was emitted (files: fewer writes).
    Interval,
}

/// The sink: a writer thread serialising batches of events as JSON Lines, in the order they
/// were emitted. Dropping it or calling [`EventLog::finish`] writes everything out and joins.
pub struct EventLog {
    inner: Option<Writer>,
}

struct Writer {
    batches: Sender<Vec<Event>>,
    recycled: Receiver<Vec<Event>>,
    thread: JoinHandle<io::Result<u64>>,
    dropped: Arc<Dropped>,
}

/// Batches (ticks) waiting for the writer at most. A reader that stops reading (a pipe nobody
/// drains) must neither block the cycle nor grow memory without bound: beyond this backlog
/// (about 4 s of ticks at 1 ms) batches are dropped, counted, and the log says so in a line
/// `{"ev":"events_dropped","count":N}` where the gap is.
pub const MAX_PENDING_BATCHES: usize = 4096;

/// Events dropped because the writer was behind: in all, and since the last marker line.
#[derive(Debug, Default)]
struct Dropped {
    total: AtomicU64,
    unmarked: AtomicU64,
}

impl EventLog {
    /// A sink that drops everything; [`EventLog::enabled`] is false.
    pub fn disabled() -> Self {
        EventLog { inner: None }
    }

    /// Write to a file (created or truncated); a named pipe is flushed at every batch.
    pub fn to_file(path: &Path) -> io::Result<Self> {
        let f = File::create(path)?;
        let policy = if is_pipe(&f) {
            FlushPolicy::EveryBatch
        } else {
            FlushPolicy::Interval
        };
        Ok(Self::to_writer_with(Box::new(f), policy))
    }

    /// Write to standard output, flushed at every batch (usually a pipe or a terminal).
    pub fn stdout() -> Self {
        Self::to_writer_with(Box::new(io::stdout()), FlushPolicy::EveryBatch)
    }

    /// `-` is standard output, anything else a file path (the `--events` option).
    pub fn open(target: &str) -> io::Result<Self> {
        if target == "-" {
            Ok(Self::stdout())
        } else {
            Self::to_file(Path::new(target))
        }
    }

    /// Write to any writer, buffered, on a thread of its own, flushed every
    /// [`FLUSH_INTERVAL`].
    pub fn to_writer(w: Box<dyn Write + Send>) -> Self {
        Self::to_writer_with(w, FlushPolicy::Interval)
    }

    /// Write to any writer, buffered, on a thread of its own, flushed as `policy` says.
    /// Whole lines only reach the writer: a stop (SIGINT/SIGTERM) that ends the run through
    /// [`EventLog::finish`] never leaves a cut line.
    pub fn to_writer_with(w: Box<dyn Write + Send>, policy: FlushPolicy) -> Self {
        let (tx, rx) = crossbeam_channel::bounded::<Vec<Event>>(MAX_PENDING_BATCHES);
        let (recycle_tx, recycle_rx) = crossbeam_channel::bounded(RECYCLE_BATCHES);
        let dropped = Arc::new(Dropped::default());
        let gap = Arc::clone(&dropped);
        let thread = std::thread::Builder::new()
            .name("ncchannel-events".into())
            .spawn(move || -> io::Result<u64> {
                let mut out = BufWriter::new(w);
                let mut lines = 0u64;
                // When the oldest unflushed line was written; None when all is flushed.
                let mut dirty_since: Option<Instant> = None;
                loop {
                    let wait = dirty_since.map_or(Duration::from_secs(3600), |t| {
                        FLUSH_INTERVAL.saturating_sub(t.elapsed())
                    });
                    let mut batch = match rx.recv_timeout(wait) {
                        Ok(b) => b,
                        Err(RecvTimeoutError::Timeout) => {
                            if dirty_since.take().is_some() {
                                out.flush()?;
                            }
                            continue;
                        }
                        Err(RecvTimeoutError::Disconnected) => break,
                    };
                    write_gap(&mut out, &gap)?;
                    for ev in batch.drain(..) {
                        serde_json::to_writer(&mut out, &ev).map_err(io::Error::other)?;
                        out.write_all(b"\n")?;
                        lines += 1;
                    }
                    // Hand the empty Vec back; if the tick has enough spares, let it go.
                    let _ = recycle_tx.try_send(batch);
                    let since = *dirty_since.get_or_insert_with(Instant::now);
                    if policy == FlushPolicy::EveryBatch || since.elapsed() >= FLUSH_INTERVAL {
                        out.flush()?;
                        dirty_since = None;
                    }
                }
                write_gap(&mut out, &gap)?;
                out.flush()?;
                Ok(lines)
            });
        match thread {
            Ok(thread) => EventLog {
                inner: Some(Writer {
                    batches: tx,
                    recycled: recycle_rx,
                    thread,
                    dropped,
                }),
            },
            // Without a thread there is no log; the run itself must not fail for it.
            Err(_) => EventLog::disabled(),
        }
    }

    /// Whether events are written anywhere.
    pub fn enabled(&self) -> bool {
        self.inner.is_some()
    }

    /// An [`EventBuffer`] matching this sink (disabled when the sink is).
    pub fn buffer(&self) -> EventBuffer {
        EventBuffer::new(self.enabled())
    }

    /// Move the events out of `events` to the writer, leaving `events` empty (with a recycled
    /// allocation when one is free). Cheap enough for the tick: a swap and a channel send.
    pub fn emit(&mut self, events: &mut Vec<Event>) {
        if events.is_empty() {
            return;
        }
        match &self.inner {
            None => events.clear(),
            Some(w) => {
                let spare = w.recycled.try_recv().unwrap_or_default();
                let batch = std::mem::replace(events, spare);
                // Never wait for the writer: a full backlog drops the batch (counted, and
                // marked in the log). The writer only goes away on an I/O error; then events
                // are lost, and `finish` reports the error.
                if let Err(TrySendError::Full(b)) = w.batches.try_send(batch) {
                    let n = b.len() as u64;
                    w.dropped.total.fetch_add(n, Ordering::Relaxed);
                    w.dropped.unmarked.fetch_add(n, Ordering::Relaxed);
                }
            }
        }
    }

    /// Events dropped so far because the log's reader was too slow (see
    /// [`MAX_PENDING_BATCHES`]).
    pub fn dropped(&self) -> u64 {
        self.inner
            .as_ref()
            .map_or(0, |w| w.dropped.total.load(Ordering::Relaxed))
    }

    /// Write out everything emitted so far, join the writer and return the lines written.
    pub fn finish(mut self) -> io::Result<u64> {
        self.shutdown()
    }

    fn shutdown(&mut self) -> io::Result<u64> {
        match self.inner.take() {
            None => Ok(0),
            Some(w) => {
                drop(w.batches);
                match w.thread.join() {
                    Ok(r) => r,
                    Err(_) => Err(io::Error::other("event writer thread panicked")),
                }
            }
        }
    }
}

/// The marker line of a gap: events dropped since the last marker, if any.
fn write_gap(out: &mut impl Write, dropped: &Dropped) -> io::Result<()> {
    let n = dropped.unmarked.swap(0, Ordering::Relaxed);
    if n > 0 {
        writeln!(out, "{{\"ev\":\"events_dropped\",\"count\":{n}}}")?;
    }
    Ok(())
}

#[cfg(unix)]
fn is_pipe(f: &File) -> bool {
    use std::os::unix::fs::FileTypeExt;
    f.metadata().is_ok_and(|m| m.file_type().is_fifo())
}

#[cfg(not(unix))]
fn is_pipe(_: &File) -> bool {
    false
}

impl Drop for EventLog {
    fn drop(&mut self) {
        let _ = self.shutdown();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn serialises_flat_with_ev_tag() {
        let tick = Tick {
            index: 3,
            period: Duration::from_millis(1),
            time: Duration::from_millis(3),
        };
        let e = Event::new(
            &tick,
            1,
            EventKind::Write {
                bytes: 12,
                ok: false,
                code: Some(11012),
            },
        );
        assert_eq!(
            e.to_json(),
            r#"{"tick":3,"t":0.003,"ch":1,"ev":"write","bytes":12,"ok":false,"code":11012}"#
        );
        let e = Event::new(&tick, 2, EventKind::Interrupt { held: 0 });
        assert_eq!(
            e.to_json(),
            r#"{"tick":3,"t":0.003,"ch":2,"ev":"interrupt","held":0}"#
        );
    }

    /// A writer whose reader does not read: blocked until the gate opens.
    struct Stalled {
        gate: crossbeam_channel::Receiver<()>,
        out: std::sync::Arc<std::sync::Mutex<Vec<u8>>>,
        opened: bool,
    }

    impl Write for Stalled {
        fn write(&mut self, b: &[u8]) -> io::Result<usize> {
            if !self.opened {
                let _ = self.gate.recv();
                self.opened = true;
            }
            self.out
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_reader_that_does_not_read_costs_bounded_memory_and_the_gap_is_marked() {
        let (open, gate) = crossbeam_channel::bounded(1);
        let out = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
        let w = Stalled {
            gate,
            out: std::sync::Arc::clone(&out),
            opened: false,
        };
        let mut log = EventLog::to_writer_with(Box::new(w), FlushPolicy::EveryBatch);
        let tick = Tick {
            index: 0,
            period: Duration::from_millis(1),
            time: Duration::ZERO,
        };
        let extra = 100;
        // One batch the writer holds while blocked, the backlog, then `extra` that cannot wait.
        for _ in 0..1 + MAX_PENDING_BATCHES + extra {
            let mut batch = vec![Event::new(&tick, 1, EventKind::Interrupt { held: 0 })];
            log.emit(&mut batch);
        }
        // The writer holds the first batch, or has not taken it yet.
        let dropped = log.dropped();
        // Open the gate before asserting: a failed assertion must not leave the writer
        // blocked while the log's drop waits for it.
        let _ = open.send(());
        let lines = log.finish().unwrap();
        assert!(
            (extra as u64..=extra as u64 + 1).contains(&dropped),
            "{dropped} dropped"
        );
        assert_eq!(lines + dropped, (1 + MAX_PENDING_BATCHES + extra) as u64);
        let text = String::from_utf8(out.lock().unwrap().clone()).unwrap();
        assert!(
            text.contains(&format!(r#"{{"ev":"events_dropped","count":{dropped}}}"#)),
            "the gap is marked"
        );
    }
}
