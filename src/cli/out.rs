//! Standard output for the commands' results, and their report files.
//!
//! `println!` panics when the reader of standard output has gone (`ncchannel check FILE |
//! head`: a panic message and exit 101). [`Stdout`] writes through one locked handle and
//! takes a reader that went away as the end of the output: nothing more is written and the
//! command finishes as a normal run would, with its own exit code. Any other write error is
//! kept and handed back by [`Stdout::finish`] for the command to report. Why this rather than
//! the default SIGPIPE action: docs/design-choices.md ("cli").

use std::fmt::Display;
use std::io::{self, Write};
use std::path::Path;

/// Is this the error of a write whose reader went away (a closed pipe)?
pub(crate) fn reader_gone(e: &io::Error) -> bool {
    e.kind() == io::ErrorKind::BrokenPipe
}

/// A command's standard output; see the module documentation.
pub(crate) struct Stdout {
    lock: io::StdoutLock<'static>,
    /// The reader has gone: the output ended there.
    gone: bool,
    /// The first write error other than the reader going away; nothing is written after it.
    failed: Option<io::Error>,
}

impl Stdout {
    pub fn new() -> Self {
        Self {
            lock: io::stdout().lock(),
            gone: false,
            failed: None,
        }
    }

    /// Write one line (unless the output has ended).
    pub fn line(&mut self, text: impl Display) {
        if self.gone || self.failed.is_some() {
            return;
        }
        if let Err(e) = writeln!(self.lock, "{text}") {
            self.end(e);
        }
    }

    /// Flush, and return the first write error other than the reader going away.
    pub fn finish(mut self) -> io::Result<()> {
        if !self.gone && self.failed.is_none() {
            if let Err(e) = self.lock.flush() {
                self.end(e);
            }
        }
        self.failed.map_or(Ok(()), Err)
    }

    /// Flush, and say a write error on stderr as `command`'s: the results are written, the
    /// exit code is the run's (a full disk under `> file` is reported, not a panic).
    pub fn finish_or_say(self, command: &str) {
        if let Err(e) = self.finish() {
            say(format_args!("{command}: standard output: {e}"));
        }
    }

    fn end(&mut self, e: io::Error) {
        if reader_gone(&e) {
            self.gone = true;
        } else {
            self.failed = Some(e);
        }
    }
}

impl Default for Stdout {
    fn default() -> Self {
        Self::new()
    }
}

/// A line on standard error, best effort. `eprintln!` panics when stderr is a closed pipe;
/// a message must never cost the run its event log or its exit code.
pub(crate) fn say(msg: std::fmt::Arguments<'_>) {
    let _ = writeln!(io::stderr().lock(), "{msg}");
}

/// A log line on standard error (something that happened while the command ran, as opposed
/// to a usage error or a summary), led by its RFC 3339 time in UTC (`humantime`), best effort.
pub(crate) fn log(msg: std::fmt::Arguments<'_>) {
    say(format_args!("{} {msg}", now()));
}

/// The time that leads every log line: now, RFC 3339 in UTC with milliseconds.
pub(crate) fn now() -> humantime::Rfc3339Timestamp {
    humantime::format_rfc3339_millis(std::time::SystemTime::now())
}

/// Write a report file whole or not at all (`crate::destination::replace`); false (after
/// saying why) when it could not be written.
pub(crate) fn write_report(command: &str, path: &Path, json: &str) -> bool {
    let text = format!("{json}\n");
    match crate::destination::replace(path, text.as_bytes()) {
        Err(e) if !reader_gone(&e) => {
            eprintln!("ncchannel {command}: --report {}: {e}", path.display());
            false
        }
        _ => true,
    }
}

/// At the start of a run, replace the report file it will write (if any, and not standard
/// output) with the `incomplete` placeholder `json`: a run killed before its end leaves that,
/// never the previous run's report. False (after saying why) when it cannot be written: the
/// run would not be able to write its report either.
pub(crate) fn mark_report_incomplete(command: &str, report: Option<&Path>, json: &str) -> bool {
    match report {
        Some(p) if !crate::destination::is_stdout(p) => write_report(command, p, json),
        _ => true,
    }
}
