//! The event log's writer thread: serialises batches of events as JSON Lines and hands the
//! operating system whole lines only, so a log cut by SIGKILL parses to its last line.
//!
//! Lines collect in a buffer of complete lines and leave in one `write` call each flush (a
//! `BufWriter` flushes wherever its buffer fills, often inside a line). A write error — a full
//! disk, a file-size limit — is reported on standard error at once, a partial line it left in
//! a log file is cut off again, and the run goes on without events: the cycle never stops
//! or waits for its log. The events not logged are counted and reported when the log ends.

use std::fs::File;
use std::io::{self, Write};

/// The buffer of whole lines is written out when it holds this many bytes, whatever the
/// flush policy (bounded memory, large writes).
const FLUSH_BYTES: usize = 64 * 1024;

/// Where the lines go, and what became of them.
pub(crate) struct LineSink {
    out: Box<dyn Write + Send>,
    /// The log file itself, when it is one: after a failed write its partial line is cut off.
    file: Option<File>,
    /// The log's name in messages (`--events` target).
    name: String,
    /// Whole lines not yet written.
    pending: Vec<u8>,
    pending_lines: u64,
    /// Bytes of whole lines the log holds.
    committed: u64,
    /// Lines written.
    lines: u64,
    /// The first write error; nothing is written after it.
    failed: Option<io::Error>,
    /// Lines (events and markers) not written because of `failed`.
    lost: u64,
}

impl LineSink {
    pub(crate) fn new(out: Box<dyn Write + Send>, file: Option<File>, name: String) -> Self {
        LineSink {
            out,
            file,
            name,
            pending: Vec::with_capacity(FLUSH_BYTES),
            pending_lines: 0,
            committed: 0,
            lines: 0,
            failed: None,
            lost: 0,
        }
    }

    /// One value (an event) as one line of JSON. Generic over what it writes, so the writer
    /// needs nothing of the event vocabulary that uses it.
    pub(crate) fn line<T: serde::Serialize>(&mut self, value: &T) {
        if self.failed.is_some() {
            self.lost += 1;
            return;
        }
        let start = self.pending.len();
        // Serialising plain strings, numbers and options into a Vec cannot fail; if it did,
        // the half line is taken back.
        if serde_json::to_writer(&mut self.pending, value).is_err() {
            self.pending.truncate(start);
            return;
        }
        self.end_line();
    }

    /// A line of the log's own (`events_dropped`).
    pub(crate) fn raw_line(&mut self, line: &str) {
        if self.failed.is_some() {
            self.lost += 1;
            return;
        }
        self.pending.extend_from_slice(line.as_bytes());
        self.end_line();
    }

    fn end_line(&mut self) {
        self.pending.push(b'\n');
        self.pending_lines += 1;
        if self.pending.len() >= FLUSH_BYTES {
            self.flush();
        }
    }

    /// Hand the whole lines collected to the operating system, in one write call when it
    /// takes them whole (a regular file does, short of a full disk).
    pub(crate) fn flush(&mut self) {
        if self.failed.is_some() || self.pending.is_empty() {
            return;
        }
        let r = write_counted(&mut self.out, &self.pending);
        match r.and_then(|()| self.out.flush().map_err(|e| (self.pending.len(), e))) {
            Ok(()) => {
                self.committed += self.pending.len() as u64;
                self.lines += self.pending_lines;
            }
            Err((written, e)) => {
                // The whole lines that did go out count as written; a partial one does not.
                let whole = memchr::memrchr(b'\n', &self.pending[..written]).map_or(0, |i| i + 1);
                let lines = memchr::memchr_iter(b'\n', &self.pending[..whole]).count() as u64;
                self.committed += whole as u64;
                self.lines += lines;
                self.pending_lines -= lines;
                self.fail(written > whole, e);
            }
        }
        self.pending.clear();
        self.pending_lines = 0;
    }

    /// A write failed (`partial`: inside a line): cut the partial line off a log file, say so
    /// at once, and take no more lines.
    fn fail(&mut self, partial: bool, e: io::Error) {
        self.lost += self.pending_lines;
        let mut note = String::new();
        if partial {
            if let Some(f) = &self.file {
                // Shrinking needs no room on the disk.
                if let Err(t) = f.set_len(self.committed) {
                    note = format!(" (and its last line may be cut: {t})");
                }
            }
        }
        // A reader that went away (`--events - | head`) is no error worth a message.
        if e.kind() != io::ErrorKind::BrokenPipe {
            let _ = writeln!(
                io::stderr().lock(),
                "ncchannel: event log {}: {e}: it ends after {} lines{note}; the run goes on without it",
                self.name,
                self.lines
            );
        }
        self.failed = Some(e);
    }

    /// Lines written, or the error that ended the log with the count of lines it cost.
    pub(crate) fn finish(mut self) -> io::Result<u64> {
        self.flush();
        match self.failed {
            None => Ok(self.lines),
            Some(e) => Err(io::Error::new(
                e.kind(),
                format!(
                    "{}: {e}: the log ends after {} lines; {} more were not written",
                    self.name, self.lines, self.lost
                ),
            )),
        }
    }
}

/// `write_all` that says how many bytes went out before an error.
fn write_counted(out: &mut dyn Write, buf: &[u8]) -> Result<(), (usize, io::Error)> {
    let mut done = 0;
    while done < buf.len() {
        match out.write(&buf[done..]) {
            Ok(0) => return Err((done, io::ErrorKind::WriteZero.into())),
            Ok(n) => done += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err((done, e)),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::event::{Event, EventKind};
    use crate::vocab::tick::Tick;
    use std::sync::{Arc, Mutex};
    use std::time::Duration;

    /// Records every write call it gets; refuses everything after `room` bytes, taking the
    /// part that fits first (as a full disk does).
    struct Calls {
        calls: Arc<Mutex<Vec<Vec<u8>>>>,
        room: usize,
    }

    impl Write for Calls {
        fn write(&mut self, b: &[u8]) -> io::Result<usize> {
            let mut calls = self.calls.lock().unwrap_or_else(|p| p.into_inner());
            let used: usize = calls.iter().map(Vec::len).sum();
            let n = b.len().min(self.room - used);
            if n == 0 {
                return Err(io::Error::new(io::ErrorKind::StorageFull, "disk full"));
            }
            calls.push(b[..n].to_vec());
            Ok(n)
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    fn block(i: u64) -> Event {
        let tick = Tick {
            index: i,
            period: Duration::from_millis(1),
            time: Duration::from_millis(i),
            clock: crate::vocab::tick::Clock::Virtual,
        };
        Event::new(
            &tick,
            1,
            EventKind::Block {
                prog: "p.nc".into(),
                line: i,
                offset: 0,
                counter: i,
                n: None,
                text: "G01 X1 Y2 Z3 F1000".repeat(5),
            },
        )
    }

    #[test]
    fn every_write_call_carries_whole_lines() {
        let calls = Arc::new(Mutex::new(Vec::new()));
        let out = Calls {
            calls: Arc::clone(&calls),
            room: usize::MAX,
        };
        let mut sink = LineSink::new(Box::new(out), None, "test".into());
        // Far more than one flush's worth, so the size-triggered flushes happen too.
        for i in 0..5000 {
            sink.line(&block(i));
            if i % 700 == 0 {
                sink.flush();
            }
        }
        assert_eq!(sink.finish().expect("no error"), 5000);
        let calls = calls.lock().unwrap_or_else(|p| p.into_inner());
        assert!(calls.len() > 2, "{} calls", calls.len());
        for c in calls.iter() {
            assert_eq!(c.last(), Some(&b'\n'), "a write call ended inside a line");
            for line in c.split(|&b| b == b'\n').filter(|l| !l.is_empty()) {
                serde_json::from_slice::<serde_json::Value>(line).expect("a whole JSON line");
            }
        }
    }

    #[test]
    fn a_full_disk_ends_the_log_at_a_line_and_counts_the_rest() {
        let calls = Arc::new(Mutex::new(Vec::new()));
        let out = Calls {
            calls: Arc::clone(&calls),
            room: 100_000,
        };
        let mut sink = LineSink::new(Box::new(out), None, "test".into());
        for i in 0..3000 {
            sink.line(&block(i));
        }
        let e = sink.finish().expect_err("the disk filled");
        assert_eq!(e.kind(), io::ErrorKind::StorageFull);
        let text = e.to_string();
        let written: u64 = calls
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .concat()
            .split(|&b| b == b'\n')
            .filter(|l| !l.is_empty())
            .count() as u64;
        assert!(text.contains("more were not written"), "{text}");
        // Every event is either in a whole written line (a cut last one excepted) or counted.
        let after: u64 = text
            .split("; ")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .and_then(|n| n.parse().ok())
            .expect("a count");
        let whole: u64 = text
            .split("after ")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .and_then(|n| n.parse().ok())
            .expect("lines");
        assert_eq!(whole + after, 3000, "{text}");
        assert!(
            written == whole || written == whole + 1,
            "{written} {whole}"
        );
    }
}
