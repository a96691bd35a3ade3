//! The event log: what happened in a channel, one JSON object a line (JSON Lines).
//!
//! The tick only pushes [`Event`] values into an [`EventBuffer`] (no text, no I/O); the
//! buffer's batch leaves through [`EventLog::emit`] to a writer thread that serialises and
//! writes in order. With logging off, [`EventBuffer::enabled`] is false and the channel skips
//! building events at all.
//!
//! The queue to the writer is bounded ([`MAX_QUEUED_BATCHES`]). When it is full (the log's
//! reader does not keep up: a pipe nobody reads), [`Backlog::Block`] makes the tick wait —
//! right in virtual time, where nothing is late — and [`Backlog::Drop`] (real time, `serve`)
//! drops the batch and counts it: the writer puts an `events_dropped` line into the log when
//! it catches up, and on stderr at the end. Memory stays bounded either way. The writer hands
//! the operating system whole lines only and reports a write error at once
//! ([`super::event_writer`]).

use std::fs::File;
use std::io::{self, Write};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, RecvTimeoutError, Sender};
use serde::Serialize;

use super::event_writer::LineSink;
use crate::vocab::event::CacheOp;
use crate::vocab::flush::FlushKind;
use crate::vocab::mode::{Mode, State};
use crate::vocab::techno::{SyncType, TechnoKind};
use crate::vocab::tick::Tick;

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

/// The event vocabulary (README "Stream interface, runtime, feeder and events"); the variant name in snake_case is the `ev` field.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "ev", rename_all = "snake_case")]
pub enum EventKind {
    /// Channel mode and state changed.
    State {
        mode: Mode,
        state: State,
    },
    /// A program started; `stream` when it reads from the stream interface.
    ProgramStart {
        prog: String,
        stream: bool,
    },
    /// A program ended; `end` is how.
    ProgramEnd {
        prog: String,
        end: ProgramEndKind,
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
    /// A stretch of refused stream writes is over (a write got through, or the log ended):
    /// `count` refusals with `code` since tick `first_tick`. Only the first of them has its
    /// own `write` and `warning` lines (a writer retrying every 250 µs would flood the log).
    WritesRefused {
        count: u64,
        code: Option<u32>,
        first_tick: u64,
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
    /// A file cache operation.
    Cache {
        op: CacheOp,
        file: Option<String>,
    },
    /// `#FLUSH` of the given kind (`plain`, `continue`, `wait`).
    Flush {
        kind: FlushKind,
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
    /// A technology function (M, H, S, T) handed to the PLC: it entered technology unit
    /// `unit` (`late`: a late-synchronisation unit) when execution reached its output point
    /// (TF5200 "Synchronisation types"). `value`: `M200=1200`'s 1200, an S word's speed.
    TechnoOutput {
        kind: TechnoKind,
        number: u32,
        #[serde(skip_serializing_if = "Option::is_none")]
        value: Option<i32>,
        sync: SyncType,
        unit: usize,
        #[serde(skip_serializing_if = "std::ops::Not::not")]
        late: bool,
        /// The block's line in its program.
        line: u32,
    },
    /// The PLC acknowledged it (or, without a PLC, its process time passed): `waited_s`
    /// since its output, channel time.
    TechnoAcknowledged {
        kind: TechnoKind,
        number: u32,
        waited_s: f64,
    },
    /// M00 (`m` 0) or M01 (`m` 1, M01 switch on) reached: the channel holds until the next
    /// start.
    ProgramStop {
        m: u32,
    },
}

/// How a program ended (`end` of `program_end`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum ProgramEndKind {
    /// M30: program end with return to its start.
    M30,
    /// M2: program end.
    M2,
    /// An NC reset ended it.
    #[serde(rename = "reset")]
    Reset,
}

impl ProgramEndKind {
    /// The end an M function programmed: the decoder ends a program only with M2 or M30.
    pub(crate) fn from_m(m: u32) -> Self {
        if m == 2 {
            ProgramEndKind::M2
        } else {
            ProgramEndKind::M30
        }
    }
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

/// Batches (one tick's events each) waiting for the writer at most; see [`Backlog`].
pub(crate) const MAX_QUEUED_BATCHES: usize = 1024;

/// With [`Backlog::Drop`], how long [`EventLog::finish`] waits for a writer that is stuck
/// on a reader that does not read before giving up on it.
pub(crate) const FINISH_TIMEOUT: Duration = Duration::from_secs(5);

/// What [`EventLog::emit`] does when [`MAX_QUEUED_BATCHES`] batches wait for the writer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Backlog {
    /// Wait for the writer (virtual time: the log is complete, the run slows down).
    Block,
    /// Drop the batch and count its events (real time: the cycle never waits for a reader).
    Drop,
}

/// A file's buffered lines reach the file at least this often, so a `tail -f` of the log
/// lags the channel by no more than this plus a tick.
pub(crate) const FLUSH_INTERVAL: Duration = Duration::from_millis(100);

/// When the writer thread hands its buffer to the operating system.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FlushPolicy {
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
    backlog: Backlog,
    /// Events dropped and not yet reported in the log.
    dropped: Arc<AtomicU64>,
}

impl EventLog {
    /// A sink that drops everything; [`EventLog::enabled`] is false.
    pub fn disabled() -> Self {
        EventLog { inner: None }
    }

    /// Write to a file (created or truncated); a named pipe is flushed at every batch.
    pub fn to_file(path: &Path) -> io::Result<Self> {
        let f = File::create(path)?;
        let (policy, trim) = if is_pipe(&f) {
            (FlushPolicy::EveryBatch, None)
        } else {
            (FlushPolicy::Interval, f.try_clone().ok())
        };
        let sink = LineSink::new(Box::new(f), trim, path.display().to_string());
        Ok(Self::to_sink(sink, policy))
    }

    /// Write to standard output, flushed at every batch (usually a pipe or a terminal).
    pub fn stdout() -> Self {
        let sink = LineSink::new(Box::new(io::stdout()), None, "on standard output".into());
        Self::to_sink(sink, FlushPolicy::EveryBatch)
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
    pub(crate) fn to_writer_with(w: Box<dyn Write + Send>, policy: FlushPolicy) -> Self {
        Self::to_sink(LineSink::new(w, None, "writer".into()), policy)
    }

    /// The writer thread taking batches to `sink`.
    fn to_sink(mut out: LineSink, policy: FlushPolicy) -> Self {
        let (tx, rx) = crossbeam_channel::bounded::<Vec<Event>>(MAX_QUEUED_BATCHES);
        let (recycle_tx, recycle_rx) = crossbeam_channel::bounded(RECYCLE_BATCHES);
        let dropped = Arc::new(AtomicU64::new(0));
        let dropped_w = Arc::clone(&dropped);
        let thread = std::thread::Builder::new()
            .name("ncchannel-events".into())
            .spawn(move || -> io::Result<u64> {
                let mut dropped_total = 0u64;
                let mut note_dropped = |out: &mut LineSink| {
                    let n = dropped_w.swap(0, Ordering::Relaxed);
                    if n > 0 {
                        dropped_total += n;
                        out.raw_line(&format!("{{\"ev\":\"events_dropped\",\"events\":{n}}}"));
                    }
                };
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
                                out.flush();
                            }
                            continue;
                        }
                        Err(RecvTimeoutError::Disconnected) => break,
                    };
                    note_dropped(&mut out);
                    // After a write error the sink only counts: the tick is never held up.
                    for ev in batch.drain(..) {
                        out.line(&ev);
                    }
                    // Hand the empty Vec back; if the tick has enough spares, let it go.
                    let _ = recycle_tx.try_send(batch);
                    let since = *dirty_since.get_or_insert_with(Instant::now);
                    if policy == FlushPolicy::EveryBatch || since.elapsed() >= FLUSH_INTERVAL {
                        out.flush();
                        dirty_since = None;
                    }
                }
                note_dropped(&mut out);
                if dropped_total > 0 {
                    let _ = writeln!(
                        io::stderr().lock(),
                        "ncchannel: event log: {dropped_total} events dropped (its reader did not keep up); the log marks where"
                    );
                }
                out.finish()
            });
        match thread {
            Ok(thread) => EventLog {
                inner: Some(Writer {
                    batches: tx,
                    recycled: recycle_rx,
                    thread,
                    backlog: Backlog::Block,
                    dropped,
                }),
            },
            // Without a thread there is no log; the run itself must not fail for it.
            Err(_) => EventLog::disabled(),
        }
    }

    /// The same log with `backlog` for a full queue (default [`Backlog::Block`]).
    pub(crate) fn with_backlog(mut self, backlog: Backlog) -> Self {
        if let Some(w) = &mut self.inner {
            w.backlog = backlog;
        }
        self
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
    pub(crate) fn emit(&mut self, events: &mut Vec<Event>) {
        if events.is_empty() {
            return;
        }
        match &self.inner {
            None => events.clear(),
            Some(w) => {
                let spare = w.recycled.try_recv().unwrap_or_default();
                let batch = std::mem::replace(events, spare);
                // The writer stays until the end, also after a write error (it then
                // counts what it cannot write, and `finish` reports it).
                match w.backlog {
                    Backlog::Block => {
                        let _ = w.batches.send(batch);
                    }
                    Backlog::Drop => {
                        if let Err(e) = w.batches.try_send(batch) {
                            let mut batch = e.into_inner();
                            w.dropped.fetch_add(batch.len() as u64, Ordering::Relaxed);
                            batch.clear();
                            *events = batch;
                        }
                    }
                }
            }
        }
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
                if w.backlog == Backlog::Drop {
                    // A writer stuck on a reader that never reads would hold the stop for
                    // ever; after FINISH_TIMEOUT it is left behind and the loss reported.
                    let until = Instant::now() + FINISH_TIMEOUT;
                    while !w.thread.is_finished() && Instant::now() < until {
                        std::thread::sleep(Duration::from_millis(10));
                    }
                    if !w.thread.is_finished() {
                        let queued = w.dropped.load(Ordering::Relaxed);
                        return Err(io::Error::other(format!(
                            "the log's reader did not read for {} s: the rest of the log was not written ({queued} events dropped besides)",
                            FINISH_TIMEOUT.as_secs()
                        )));
                    }
                }
                match w.thread.join() {
                    Ok(r) => r,
                    Err(_) => Err(io::Error::other("event writer thread panicked")),
                }
            }
        }
    }
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
            clock: crate::vocab::tick::Clock::Virtual,
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

    /// A writer that takes nothing until `open` is set, then keeps what it is given.
    struct Gate {
        open: Arc<std::sync::atomic::AtomicBool>,
        got: Arc<std::sync::Mutex<Vec<u8>>>,
    }

    impl Write for Gate {
        fn write(&mut self, b: &[u8]) -> io::Result<usize> {
            while !self.open.load(Ordering::Acquire) {
                std::thread::sleep(Duration::from_millis(1));
            }
            self.got
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
    fn a_reader_that_does_not_read_costs_counted_events_not_memory_or_the_tick() {
        let open = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let got = Arc::new(std::sync::Mutex::new(Vec::new()));
        let gate = Gate {
            open: Arc::clone(&open),
            got: Arc::clone(&got),
        };
        let mut log = EventLog::to_writer_with(Box::new(gate), FlushPolicy::EveryBatch)
            .with_backlog(Backlog::Drop);
        let tick = Tick {
            index: 0,
            period: Duration::from_millis(1),
            time: Duration::ZERO,
            clock: crate::vocab::tick::Clock::Virtual,
        };
        let batches = MAX_QUEUED_BATCHES * 3;
        for _ in 0..batches {
            // Would block for ever here with `Backlog::Block`: the gate is shut.
            let mut events = vec![Event::new(&tick, 1, EventKind::Interrupt { held: 0 })];
            log.emit(&mut events);
        }
        open.store(true, Ordering::Release);
        let lines = log
            .finish()
            .expect("the writer finishes once the reader reads");
        let text = String::from_utf8(got.lock().unwrap_or_else(|p| p.into_inner()).clone())
            .expect("utf-8");
        let written = text.matches("\"interrupt\"").count();
        let dropped: usize = text
            .lines()
            .filter_map(|l| l.strip_prefix(r#"{"ev":"events_dropped","events":"#))
            .filter_map(|n| n.trim_end_matches('}').parse::<usize>().ok())
            .sum();
        assert!(dropped > 0, "some batches were dropped");
        assert_eq!(written + dropped, batches, "every event written or counted");
        assert!(
            written <= MAX_QUEUED_BATCHES + 2,
            "the queue stayed bounded"
        );
        assert_eq!(lines as usize, text.lines().count());
    }
}
