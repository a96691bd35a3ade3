//! Program store: finds NC programs through the channel's search paths and reads them into memory.
//!
//! The real channel reads a program from the file system when it is opened as main program or
//! called as a subroutine; that read is what the file cache (#CACHE) saves, so every open and
//! every byte read is counted here. The name in `streaming_prog_file` is not a file at all: it
//! opens the channel's stream interface instead, transparently (ISG FCT-C19 Data streaming §2.2).
//!
//! A slow drive or network share is modelled by [`FsLatency`]: every file-system read is
//! charged `per_open + per_kib × KiB` of channel time. The store never sleeps; it only adds the
//! charge to an account the decoder takes with [`ProgramStore::take_owed`] and turns into "the
//! read completes at channel time T" (decoding waits, motion keeps running what is queued).
//!
//! A tick reads files itself only up to `INLINE_READ_BYTES_PER_TICK`; a larger read goes to
//! the loader thread (`super::loader`) and the open answers [`Opened::Loading`].

use std::fs;
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use thiserror::Error;

use crate::bounded::BoundedReadError;
use crate::vocab::tick::Clock;

use super::loader::{Loader, PendingRead, Poll, INLINE_READ_BYTES_PER_TICK};

/// Largest program the store reads into memory (900110 beyond it). A bound, so a mistaken
/// path to a huge file cannot exhaust memory; real NC programs that large are streamed instead.
pub(crate) const MAX_PROGRAM_BYTES: u64 = 256 * 1024 * 1024;

/// Type bit of a search path: main programs.
pub(crate) const PATH_MAIN: u8 = 0x01;
/// Type bit of a search path: subroutines and cycles.
pub(crate) const PATH_SUB: u8 = 0x02;

/// One program search path (start-up list `pfad[i].prg[j]`, channel list `path[i].dir`).
#[derive(Debug, Clone, PartialEq)]
pub struct SearchDir {
    pub dir: PathBuf,
    /// `PATH_MAIN` | `PATH_SUB`.
    pub kinds: u8,
    /// 0 is searched first.
    pub priority: u32,
}

/// What a program is opened as; decides the search-path type bit and the error number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProgramKind {
    Main,
    Subroutine,
}

/// A program text in memory. Shared, because a cache entry and a running frame may hold the
/// same text: a cache refresh replaces the store's text, the running frame keeps the old one.
#[derive(Debug, Clone)]
pub struct ProgramText {
    /// The name as the program called it.
    pub name: Arc<str>,
    /// The file's bytes, as read (shared without a copy: a `Vec` read to its exact size).
    pub text: Arc<Vec<u8>>,
}

/// The result of opening a program name.
#[derive(Debug, Clone)]
pub enum Opened {
    File(ProgramText),
    /// A file too large for this tick's inline budget: the loader thread reads it; pick the
    /// text up with [`ProgramStore::finish_read`].
    Loading(PendingRead),
    /// The virtual streaming program: read from the stream interface.
    Stream {
        name: Arc<str>,
    },
}

#[derive(Debug, Error, Clone, PartialEq)]
pub enum StoreError {
    #[error("main program '{0}' not found")]
    MainNotFound(String),
    #[error("global subroutine '{0}' not found")]
    SubroutineNotFound(String),
    #[error("program '{name}' is {bytes} bytes, more than the {limit}-byte limit")]
    TooLarge {
        name: String,
        bytes: u64,
        limit: u64,
    },
    #[error("program '{name}' could not be read: {reason}")]
    Unreadable { name: String, reason: String },
    #[error("program name '{0}' is not allowed (absolute or leaving the search path)")]
    BadName(String),
}

impl StoreError {
    /// The ISG error number (TF5200 diagnosis list).
    pub fn code(&self) -> u32 {
        use crate::lang::codes;
        match self {
            StoreError::MainNotFound(_) => codes::MAIN_NOT_FOUND,
            StoreError::SubroutineNotFound(_) => codes::SUBROUTINE_NOT_FOUND,
            // No ISG number known for these: our own range (README, "Error numbers").
            StoreError::TooLarge { .. } => codes::PROGRAM_TOO_LARGE,
            StoreError::Unreadable { .. } => codes::PROGRAM_UNREADABLE,
            StoreError::BadName(_) => codes::PROGRAM_BAD_NAME,
        }
    }
}

/// Counters the report shows and the file cache beats.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StoreStats {
    /// File-system opens that found and read a program.
    pub opens: u64,
    /// Bytes read from the file system.
    pub bytes_read: u64,
    /// Simulated file-system latency charged for those reads (runtime.toml `fs_latency_us…`).
    pub latency: Duration,
    /// Of the opens, those the loader thread read (too large for the tick's inline budget).
    pub loaded_off_tick: u64,
    /// Most bytes of program files read inside one tick (at most
    /// `INLINE_READ_BYTES_PER_TICK`): the tick work file reads cost.
    pub max_tick_read_bytes: u64,
}

/// Simulated cost of a file-system read (runtime.toml `fs_latency_us`, `fs_latency_us_per_kib`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FsLatency {
    /// Charged once per file opened.
    pub(crate) per_open: Duration,
    /// Charged per KiB read, pro rata (a 512-byte file costs half of it).
    pub(crate) per_kib: Duration,
}

impl FsLatency {
    pub fn from_us(per_open_us: u64, per_kib_us: u64) -> Self {
        FsLatency {
            per_open: Duration::from_micros(per_open_us),
            per_kib: Duration::from_micros(per_kib_us),
        }
    }

    /// What reading a file of `bytes` costs.
    pub fn cost(&self, bytes: u64) -> Duration {
        // In ns: per_kib ≤ 10 s and bytes ≤ MAX_PROGRAM_BYTES keep this far below u128 limits.
        let per_kib_ns = self.per_kib.as_nanos() * u128::from(bytes) / 1024;
        self.per_open + Duration::from_nanos(u64::try_from(per_kib_ns).unwrap_or(u64::MAX))
    }

    pub fn is_zero(&self) -> bool {
        self.per_open.is_zero() && self.per_kib.is_zero()
    }
}

/// The channel's view of its programs.
#[derive(Debug, Clone)]
pub struct ProgramStore {
    dirs: Vec<SearchDir>,
    /// `streaming_prog_file`, lower-case; `None` = streaming off.
    streaming_prog: Option<String>,
    stats: StoreStats,
    latency: FsLatency,
    /// Latency charged and not yet taken by the decoder.
    owed: Duration,
    /// Bytes read inside the current tick.
    read_this_tick: u64,
    /// The clock of the current tick ([`ProgramStore::begin_tick`]): whether a read the
    /// loader has not finished is waited for (virtual time) or polled again next tick.
    clock: Clock,
    /// Wall time this tick waited for the loader with the clock stopped (virtual time).
    clock_stopped: Duration,
    /// Reads the files too large for the tick's inline budget.
    loader: Loader,
}

impl ProgramStore {
    pub fn new(mut dirs: Vec<SearchDir>, streaming_prog: Option<&str>) -> Self {
        dirs.sort_by_key(|d| d.priority);
        ProgramStore {
            dirs,
            streaming_prog: streaming_prog
                .filter(|s| !s.is_empty())
                .map(|s| s.to_ascii_lowercase()),
            stats: StoreStats::default(),
            latency: FsLatency::default(),
            owed: Duration::ZERO,
            read_this_tick: 0,
            clock: Clock::Virtual,
            clock_stopped: Duration::ZERO,
            loader: Loader::inline(),
        }
    }

    /// Read files too large for a tick's inline budget through `loader` (without one they
    /// are read in the tick).
    pub(crate) fn with_loader(mut self, loader: Loader) -> Self {
        self.loader = loader;
        self
    }

    /// The start of a tick: reads the loader has not finished meet this tick's clock.
    pub(crate) fn begin_tick(&mut self, clock: Clock) {
        self.clock = clock;
    }

    /// The wall time the reads of the tick waited for the loader with the clock stopped, and
    /// zero from now on (the channel hands it to the cycle, which reports it apart from the
    /// tick's work).
    pub(crate) fn take_clock_stopped(&mut self) -> Duration {
        std::mem::take(&mut self.clock_stopped)
    }

    /// Charge every file-system read with this simulated latency.
    pub(crate) fn with_latency(mut self, latency: FsLatency) -> Self {
        self.latency = latency;
        self
    }

    pub fn stats(&self) -> StoreStats {
        self.stats
    }

    /// Latency charged since the last call: the caller (the decoder) waits it out in channel
    /// time. Zero when no file was read or no latency is configured.
    pub(crate) fn take_owed(&mut self) -> Duration {
        std::mem::take(&mut self.owed)
    }

    pub fn search_dirs(&self) -> &[SearchDir] {
        &self.dirs
    }

    /// Whether the channel has a streaming program at all (`streaming_prog_file` set).
    pub(crate) fn streaming_enabled(&self) -> bool {
        self.streaming_prog.is_some()
    }

    /// The streaming program's name (`streaming_prog_file`, lower case), if streaming is on.
    pub(crate) fn streaming_program(&self) -> Option<&str> {
        self.streaming_prog.as_deref()
    }

    /// Whether `name` is the virtual streaming program (case-insensitive, as program names are).
    pub(crate) fn is_streaming_program(&self, name: &str) -> bool {
        self.streaming_prog
            .as_deref()
            .is_some_and(|s| s.eq_ignore_ascii_case(name))
    }

    /// Open a program by name: the stream if it is `streaming_prog_file`, else the first file
    /// found through the search paths of that kind, by priority, names case-insensitive. A
    /// file too large for what is left of this tick's inline budget is handed to the loader.
    pub fn open(&mut self, name: &str, kind: ProgramKind) -> Result<Opened, StoreError> {
        if self.is_streaming_program(name) {
            return Ok(Opened::Stream { name: name.into() });
        }
        self.open_file(name, kind)
    }

    /// Open a program file (never the stream): read here while this tick's inline budget
    /// lasts, else handed to the loader ([`Opened::Loading`]).
    pub(crate) fn open_file(
        &mut self,
        name: &str,
        kind: ProgramKind,
    ) -> Result<Opened, StoreError> {
        let path = self.find(name, kind)?;
        let bytes = std::fs::metadata(&path)
            .map_err(|e| StoreError::Unreadable {
                name: name.to_string(),
                reason: e.to_string(),
            })?
            .len();
        if bytes > MAX_PROGRAM_BYTES {
            return Err(StoreError::TooLarge {
                name: name.to_string(),
                bytes,
                limit: MAX_PROGRAM_BYTES,
            });
        }
        if self.read_this_tick + bytes > INLINE_READ_BYTES_PER_TICK {
            return Ok(Opened::Loading(self.loader.read(
                name,
                &path,
                MAX_PROGRAM_BYTES,
            )));
        }
        let text = read_bounded(&path, name)?;
        self.read_this_tick += text.len() as u64;
        Ok(Opened::File(self.opened(name, text)))
    }

    /// The text of a read handed to the loader, once it is there (`None`: not yet).
    pub(crate) fn finish_read(
        &mut self,
        pending: &PendingRead,
    ) -> Option<Result<ProgramText, StoreError>> {
        let (poll, waited) = pending.poll(self.clock);
        self.clock_stopped += waited;
        match poll {
            Poll::Waiting => None,
            Poll::Done(Ok(text)) => {
                self.stats.loaded_off_tick += 1;
                Some(Ok(self.opened(&pending.name, text)))
            }
            Poll::Done(Err(e)) => Some(Err(read_error(e, &pending.name))),
        }
    }

    /// The end of a tick: its inline reads are counted, the next tick's budget is whole.
    pub(crate) fn end_tick(&mut self) {
        self.stats.max_tick_read_bytes = self.stats.max_tick_read_bytes.max(self.read_this_tick);
        self.read_this_tick = 0;
    }

    /// A file read: counted, its latency charged.
    fn opened(&mut self, name: &str, text: Vec<u8>) -> ProgramText {
        self.stats.opens += 1;
        self.stats.bytes_read += text.len() as u64;
        if !self.latency.is_zero() {
            let cost = self.latency.cost(text.len() as u64);
            self.owed += cost;
            self.stats.latency += cost;
        }
        ProgramText {
            name: name.into(),
            text: Arc::new(text),
        }
    }

    /// Locate a program file without reading it.
    pub fn find(&self, name: &str, kind: ProgramKind) -> Result<PathBuf, StoreError> {
        let rel = checked_relative(name)?;
        let bit = match kind {
            ProgramKind::Main => PATH_MAIN,
            ProgramKind::Subroutine => PATH_SUB,
        };
        for d in self.dirs.iter().filter(|d| d.kinds & bit != 0) {
            if let Some(p) = find_case_insensitive(&d.dir, &rel) {
                return Ok(p);
            }
        }
        Err(match kind {
            ProgramKind::Main => StoreError::MainNotFound(name.to_string()),
            ProgramKind::Subroutine => StoreError::SubroutineNotFound(name.to_string()),
        })
    }
}

/// A program name may name a file below a search path, never outside it.
fn checked_relative(name: &str) -> Result<PathBuf, StoreError> {
    let p = Path::new(name);
    if name.is_empty() || name.contains('\0') {
        return Err(StoreError::BadName(name.to_string()));
    }
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::Normal(s) => out.push(s),
            Component::CurDir => {}
            _ => return Err(StoreError::BadName(name.to_string())),
        }
    }
    if out.as_os_str().is_empty() {
        return Err(StoreError::BadName(name.to_string()));
    }
    Ok(out)
}

/// Exact path first (the common case costs one stat), then a case-insensitive match of each
/// component, as the real kernel treats program names.
fn find_case_insensitive(dir: &Path, rel: &Path) -> Option<PathBuf> {
    let exact = dir.join(rel);
    if exact.is_file() {
        return Some(exact);
    }
    let mut cur = dir.to_path_buf();
    let comps: Vec<_> = rel.components().collect();
    for (i, c) in comps.iter().enumerate() {
        let want = c.as_os_str().to_string_lossy().to_lowercase();
        let last = i + 1 == comps.len();
        let entries = fs::read_dir(&cur).ok()?;
        let mut found = None;
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().to_lowercase() == want {
                let is_file = e
                    .file_type()
                    .map(|t| t.is_file() || t.is_symlink())
                    .unwrap_or(false);
                let is_dir = e.path().is_dir();
                if (last && is_file && e.path().is_file()) || (!last && is_dir) {
                    found = Some(e.path());
                    break;
                }
            }
        }
        cur = found?;
    }
    Some(cur)
}

fn read_bounded(path: &Path, name: &str) -> Result<Vec<u8>, StoreError> {
    crate::bounded::read_file(path, MAX_PROGRAM_BYTES).map_err(|e| read_error(e, name))
}

fn read_error(e: BoundedReadError, name: &str) -> StoreError {
    match e {
        BoundedReadError::TooLarge { bytes, limit } => StoreError::TooLarge {
            name: name.to_string(),
            bytes,
            limit,
        },
        BoundedReadError::Io(e) => StoreError::Unreadable {
            name: name.to_string(),
            reason: e.to_string(),
        },
        e @ BoundedReadError::NotRegular => StoreError::Unreadable {
            name: name.to_string(),
            reason: e.to_string(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn store(dir: &Path) -> ProgramStore {
        ProgramStore::new(
            vec![SearchDir {
                dir: dir.to_path_buf(),
                kinds: PATH_MAIN | PATH_SUB,
                priority: 0,
            }],
            Some("streaming.nc"),
        )
    }

    #[test]
    fn finds_names_case_insensitively_and_counts_opens() {
        let d = tempfile::tempdir().unwrap();
        fs::write(d.path().join("Laser_On.cyc"), "M17\r\n").unwrap();
        let mut s = store(d.path());
        match s.open("LASER_ON.CYC", ProgramKind::Subroutine).unwrap() {
            Opened::File(p) => assert_eq!(&*p.text, b"M17\r\n"),
            other => panic!("not read: {other:?}"),
        }
        assert_eq!(
            s.stats(),
            StoreStats {
                opens: 1,
                bytes_read: 5,
                latency: Duration::ZERO,
                loaded_off_tick: 0,
                max_tick_read_bytes: 0,
            }
        );
        assert_eq!(s.take_owed(), Duration::ZERO);
    }

    #[test]
    fn every_file_read_is_charged_its_latency_once() {
        let d = tempfile::tempdir().unwrap();
        fs::write(d.path().join("big.nc"), vec![b'x'; 2048]).unwrap();
        let mut s = store(d.path()).with_latency(FsLatency::from_us(200, 100));
        s.open("big.nc", ProgramKind::Main).unwrap();
        // 200 µs per open + 2 KiB × 100 µs.
        assert_eq!(s.take_owed(), Duration::from_micros(400));
        assert_eq!(s.take_owed(), Duration::ZERO, "taken once");
        // The stream is no file: no charge.
        s.open("streaming.nc", ProgramKind::Main).unwrap();
        assert_eq!(s.take_owed(), Duration::ZERO);
        // A failed open reads nothing and costs nothing.
        assert!(s.open("absent.nc", ProgramKind::Main).is_err());
        assert_eq!(s.take_owed(), Duration::ZERO);
        assert_eq!(s.stats().latency, Duration::from_micros(400));
        assert_eq!(
            FsLatency::from_us(0, 1024).cost(512),
            Duration::from_micros(512)
        );
    }

    #[test]
    fn streaming_program_is_virtual() {
        let d = tempfile::tempdir().unwrap();
        let mut s = store(d.path());
        assert!(matches!(
            s.open("Streaming.NC", ProgramKind::Main).unwrap(),
            Opened::Stream { .. }
        ));
        assert_eq!(s.stats().opens, 0);
    }

    #[test]
    fn not_found_numbers_and_type_bits() {
        let d = tempfile::tempdir().unwrap();
        fs::write(d.path().join("sub.nc"), "M17\r\n").unwrap();
        let mut s = ProgramStore::new(
            vec![SearchDir {
                dir: d.path().to_path_buf(),
                kinds: PATH_SUB,
                priority: 0,
            }],
            None,
        );
        assert_eq!(s.open("x.nc", ProgramKind::Main).unwrap_err().code(), 20368);
        assert_eq!(
            s.open("x.nc", ProgramKind::Subroutine).unwrap_err().code(),
            20369
        );
        // sub.nc exists, but only in a subroutine path.
        assert_eq!(
            s.open("sub.nc", ProgramKind::Main).unwrap_err().code(),
            20368
        );
        assert!(s.open("sub.nc", ProgramKind::Subroutine).is_ok());
    }

    #[test]
    fn priority_orders_the_search() {
        let a = tempfile::tempdir().unwrap();
        let b = tempfile::tempdir().unwrap();
        fs::write(a.path().join("p.nc"), "A\r\n").unwrap();
        fs::write(b.path().join("p.nc"), "B\r\n").unwrap();
        let mut s = ProgramStore::new(
            vec![
                SearchDir {
                    dir: a.path().into(),
                    kinds: 3,
                    priority: 1,
                },
                SearchDir {
                    dir: b.path().into(),
                    kinds: 3,
                    priority: 0,
                },
            ],
            None,
        );
        match s.open("p.nc", ProgramKind::Main).unwrap() {
            Opened::File(p) => assert_eq!(&*p.text, b"B\r\n"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn names_cannot_escape_the_search_path() {
        let d = tempfile::tempdir().unwrap();
        let mut s = store(d.path());
        for bad in ["../etc/passwd", "/etc/passwd", "", "a\0b"] {
            assert_eq!(
                s.open(bad, ProgramKind::Main).unwrap_err().code(),
                crate::lang::codes::PROGRAM_BAD_NAME,
                "{bad:?}"
            );
        }
    }
}
