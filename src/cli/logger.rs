//! The binary's logger: `log` records of ncchannel's modules as one stderr line each,
//! `ncchannel ads: message` (the module under `ncchannel::` names the part).
//!
//! Why not env_logger: the server logs a handful of rate-limited lines (docs/ads-limits.md) and
//! needs neither filters from the environment nor timestamps (the event log has the ticks);
//! twenty lines keep the format the tests and the README show.

use std::io::Write;

use log::{LevelFilter, Log, Metadata, Record};

struct StderrLogger;

static LOGGER: StderrLogger = StderrLogger;

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
        let _ = writeln!(io_stderr(), "ncchannel {part}: {}", record.args());
    }

    fn flush(&self) {
        let _ = io_stderr().flush();
    }
}

fn io_stderr() -> std::io::StderrLock<'static> {
    std::io::stderr().lock()
}

/// Install the logger (once; a second call is a no-op).
pub fn init() {
    if log::set_logger(&LOGGER).is_ok() {
        log::set_max_level(LevelFilter::Info);
    }
}
