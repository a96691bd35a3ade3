//! Filing received programs: each program streams into a temporary file in the program
//! directory, is flushed to disk, and only then renamed to its final name, so a crash or a
//! broken transfer never leaves part of a program under a name the channel would run.
//!
//! The temporary file is the `tempfile` crate's `NamedTempFile`: it is removed when dropped
//! (a broken transfer, a writer error, the receiver stopping), and `persist_noclobber` gives
//! the final name only if nothing has it yet, atomically (no window between test and rename).
//! The writer holds a lock on it while it writes ([`temp_files`]), so a later run can tell the
//! files a killed receiver left from those of a receiver still running, in any PID namespace.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

use tempfile::NamedTempFile;

use super::error::DncError;
use super::splitter::{ProgramEnd, ProgramSink, ProgramStart};
use super::temp_files;

/// Numbered file names for programs whose data names none: `received_{n}.nc` gives
/// `received_001.nc`, `received_002.nc`, …; `{n:W}` sets the digits (default 3).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NameTemplate {
    prefix: String,
    suffix: String,
    width: usize,
}

impl Default for NameTemplate {
    fn default() -> Self {
        NameTemplate {
            prefix: "received_".into(),
            suffix: ".nc".into(),
            width: 3,
        }
    }
}

impl NameTemplate {
    pub fn parse(template: &str) -> Result<Self, DncError> {
        let bad = |reason| DncError::BadTemplate {
            template: template.to_string(),
            reason,
        };
        let open = template
            .find("{n")
            .ok_or_else(|| bad("no `{n}` placeholder"))?;
        let close = template[open..]
            .find('}')
            .map(|i| open + i)
            .ok_or_else(|| bad("unclosed `{n`"))?;
        let spec = &template[open + 2..close];
        let width = match spec.strip_prefix(':') {
            None if spec.is_empty() => 3,
            Some(w) => w
                .parse::<usize>()
                .ok()
                .filter(|w| (1..=9).contains(w))
                .ok_or_else(|| bad("the width in `{n:W}` must be 1 to 9"))?,
            None => return Err(bad("write `{n}` or `{n:W}`")),
        };
        let t = NameTemplate {
            prefix: template[..open].to_string(),
            suffix: template[close + 1..].to_string(),
            width,
        };
        if t.prefix.contains('{') || t.suffix.contains('{') {
            return Err(bad("only one `{n}` placeholder"));
        }
        if super::control_line::safe_name(t.render(1).as_bytes()).is_none() {
            return Err(bad(
                "the name must be one plain file name (letters, digits, `_`, `-`, `.`)",
            ));
        }
        Ok(t)
    }

    pub fn render(&self, n: u32) -> String {
        format!("{}{:0w$}{}", self.prefix, n, self.suffix, w = self.width)
    }
}

/// How the program files are placed.
#[derive(Debug, Clone)]
pub struct WriterConfig {
    /// The program directory; created when missing.
    pub(crate) out_dir: PathBuf,
    /// Replace an existing file of the same name (otherwise the existing file is kept and the
    /// received program dropped).
    pub overwrite: bool,
    /// Keep a cut-off program as `<final name>.partial` instead of dropping it.
    pub keep_partial: bool,
    pub template: NameTemplate,
}

impl WriterConfig {
    pub fn new(out_dir: impl Into<PathBuf>) -> Self {
        WriterConfig {
            out_dir: out_dir.into(),
            overwrite: false,
            keep_partial: false,
            template: NameTemplate::default(),
        }
    }
}

/// What became of one received program.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Disposition {
    /// Written under a new name.
    Written,
    /// Written over an existing file (`--overwrite`).
    Replaced,
    /// A file of that name existed; it was kept and the received program dropped.
    KeptExisting,
    /// The transfer stopped inside the program; nothing was kept.
    CutOffDropped,
    /// The transfer stopped inside the program; kept as `<name>.partial`.
    CutOffKept,
    /// The program could not be filed under its name (the name is taken by a directory, or a
    /// workpiece folder's name by a file); it was dropped and the transfer went on.
    NameUnusable,
    /// The transfer had delivered its limit of programs; this one was dropped and the
    /// transfer ended (`TransferLimits::max_programs`).
    OverLimit,
    /// The disk refused the program (full, file too large, no permission): it was lost and
    /// the transfer ended there (`reason` says why).
    WriteFailed,
}

/// One line of the receive log.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReceivedProgram {
    /// Where the program is (or would have been) filed.
    pub path: PathBuf,
    pub bytes: u64,
    /// Lines of the transfer the program came from (1-based).
    pub first_line: u64,
    pub last_line: u64,
    pub disposition: Disposition,
    /// Names from the data refused as unsafe.
    pub rejected_names: Vec<super::control_line::RejectedName>,
    /// Why the program was not filed ([`Disposition::NameUnusable`], [`Disposition::OverLimit`],
    /// [`Disposition::WriteFailed`]).
    pub reason: Option<String>,
}

impl ReceivedProgram {
    /// Is the program now on disk under its final name?
    pub(crate) fn is_filed(&self) -> bool {
        matches!(
            self.disposition,
            Disposition::Written | Disposition::Replaced
        )
    }
}

/// Called with every record as it is made.
type LogFn = Box<dyn FnMut(&ReceivedProgram)>;

/// How many taken numbered names are skipped at most when looking for a free one.
const MAX_NUMBER_PROBES: u32 = 100_000;

/// The program being received: its temporary file, removed on drop unless persisted, and a
/// buffered handle on the same file. Writes go through the plain `File`: an error then reads
/// as the disk's own ("No space left on device"), where tempfile's wrapper would add the
/// temporary path, which means nothing to the operator.
struct TempProgram {
    out: BufWriter<File>,
    file: NamedTempFile,
}

impl TempProgram {
    fn new(file: NamedTempFile) -> io::Result<Self> {
        let out = BufWriter::with_capacity(64 * 1024, file.as_file().try_clone()?);
        Ok(TempProgram { out, file })
    }
}

/// Files the programs the splitter delivers; see the module doc for the guarantees.
pub struct ProgramWriter {
    cfg: WriterConfig,
    current: Option<TempProgram>,
    /// The next number for a program the data names not; shared by the writers of
    /// concurrent transfers so no two pick the same one.
    next_number: Arc<AtomicU32>,
    records: Vec<ReceivedProgram>,
    log: Option<LogFn>,
    /// Programs this transfer may still deliver (`None`: no limit).
    programs_left: Option<usize>,
    /// A program was dropped because `programs_left` was 0.
    over_limit: bool,
    /// The disk refused the program being received: the error, kept until the program's end
    /// names it (the name lines may come after the failing write).
    failed: Option<io::Error>,
}

impl ProgramWriter {
    pub fn new(cfg: WriterConfig) -> Self {
        ProgramWriter {
            cfg,
            current: None,
            next_number: Arc::new(AtomicU32::new(1)),
            records: Vec::new(),
            log: None,
            programs_left: None,
            over_limit: false,
            failed: None,
        }
    }

    /// Deliver at most `max` more programs; the next ones are dropped as
    /// [`Disposition::OverLimit`]. `None` lifts the limit.
    pub(crate) fn limit_programs(&mut self, max: Option<usize>) {
        self.programs_left = max;
        self.over_limit = false;
    }

    /// Was a program dropped for the limit of [`ProgramWriter::limit_programs`]?
    pub(crate) fn over_limit(&self) -> bool {
        self.over_limit
    }

    /// Number unnamed programs from `numbers`, shared with other writers (concurrent
    /// transfers into one folder).
    pub(crate) fn with_numbers(mut self, numbers: Arc<AtomicU32>) -> Self {
        self.next_number = numbers;
        self
    }

    /// The counter [`ProgramWriter::with_numbers`] shares.
    pub fn numbers(&self) -> Arc<AtomicU32> {
        Arc::clone(&self.next_number)
    }

    /// Called for every program as soon as it is filed (or dropped).
    pub(crate) fn with_log(mut self, log: impl FnMut(&ReceivedProgram) + 'static) -> Self {
        self.log = Some(Box::new(log));
        self
    }

    pub fn config(&self) -> &WriterConfig {
        &self.cfg
    }

    /// The records since the last call.
    pub(crate) fn take_records(&mut self) -> Vec<ReceivedProgram> {
        std::mem::take(&mut self.records)
    }

    /// Drop a program still being written (the transfer was abandoned); dropping the
    /// temporary file removes it.
    pub(crate) fn discard_current(&mut self) {
        self.current = None;
        self.failed = None;
    }

    fn record(&mut self, r: ReceivedProgram) {
        if let Some(log) = self.log.as_mut() {
            log(&r);
        }
        self.records.push(r);
    }

    /// The next numbered name not yet on disk (or simply the next number with `overwrite`).
    /// Bounded: after [`MAX_NUMBER_PROBES`] taken names the next one is used anyway (and the
    /// existing file kept).
    fn numbered(&mut self) -> String {
        let mut probes = 0;
        loop {
            let n = self
                .next_number
                .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
                    Some(n.saturating_add(1))
                })
                .unwrap_or(u32::MAX);
            let name = self.cfg.template.render(n);
            probes += 1;
            if self.cfg.overwrite
                || probes >= MAX_NUMBER_PROBES
                || !self.cfg.out_dir.join(&name).exists()
            {
                return name;
            }
        }
    }

    fn file(&mut self, end: ProgramEnd) -> Result<(), DncError> {
        if let Some(e) = self.failed.take() {
            let (parent, name) = self.final_place(&end);
            return Err(self.lose(parent.join(name), &end, e));
        }
        let Some(tmp) = self.current.take() else {
            return Ok(());
        };
        if self.programs_left == Some(0) {
            // Gone before the record is logged: whoever reads the log finds no temporary file.
            drop(tmp);
            self.over_limit = true;
            let name = end.name.file_name().map_or_else(String::new, |(_, n)| n);
            self.record(ReceivedProgram {
                path: self.cfg.out_dir.join(name),
                bytes: end.bytes,
                first_line: end.first_line,
                last_line: end.last_line,
                disposition: Disposition::OverLimit,
                rejected_names: end.name.rejected.clone(),
                reason: Some("the transfer's limit of programs was reached".to_string()),
            });
            return Ok(());
        }
        if let Some(left) = self.programs_left.as_mut() {
            *left -= 1;
        }
        let (parent, name) = self.final_place(&end);
        let mut target = parent.join(&name);
        let tmp = match finish_temp(tmp) {
            Ok(t) => t,
            Err(e) => return Err(self.lose(target, &end, e)),
        };
        let mut record = ReceivedProgram {
            path: target.clone(),
            bytes: end.bytes,
            first_line: end.first_line,
            last_line: end.last_line,
            disposition: Disposition::Written,
            rejected_names: end.name.rejected.clone(),
            reason: None,
        };
        if !end.complete {
            if !self.cfg.keep_partial {
                drop(tmp);
                record.disposition = Disposition::CutOffDropped;
                self.record(record);
                return Ok(());
            }
            target = parent.join(format!("{name}.partial"));
            record.path = target.clone();
        }
        if parent.exists() && !parent.is_dir() {
            drop(tmp);
            record.disposition = Disposition::NameUnusable;
            record.reason = Some(format!("{} is a file, not a folder", parent.display()));
            self.record(record);
            return Ok(());
        }
        if let Err(e) = fs::create_dir_all(&parent) {
            return Err(self.lose(target, &end, e));
        }
        if target.is_dir() {
            drop(tmp);
            record.disposition = Disposition::NameUnusable;
            record.reason = Some(format!("{} is a folder", target.display()));
            self.record(record);
            return Ok(());
        }
        let placed = match place(tmp, &target, self.cfg.overwrite) {
            Ok(p) => p,
            Err(e) => return Err(self.lose(target, &end, e)),
        };
        record.disposition = match (placed, end.complete) {
            (Placed::Kept, _) => Disposition::KeptExisting,
            (_, false) => Disposition::CutOffKept,
            (Placed::New, true) => Disposition::Written,
            (Placed::Replaced, true) => Disposition::Replaced,
        };
        if placed != Placed::Kept {
            // The program is under its name, complete and synced; only the rename's own
            // durability is in doubt: it counts as filed, and the error stops the transfer.
            if let Err(e) = sync_dir(&parent) {
                self.record(record);
                return Err(DncError::io(&parent, e));
            }
        }
        self.record(record);
        Ok(())
    }

    /// Where the program of `end` goes: its folder and file name (a numbered name when the
    /// data names none).
    fn final_place(&mut self, end: &ProgramEnd) -> (PathBuf, String) {
        let (dir, name) = match end.name.file_name() {
            Some(n) => n,
            None => (None, self.numbered()),
        };
        let parent = match &dir {
            Some(d) => self.cfg.out_dir.join(d),
            None => self.cfg.out_dir.clone(),
        };
        (parent, name)
    }

    /// The disk refused the program of `end` (to be filed as `target`): record it as lost
    /// under the name it would have had, and stop the transfer with the error.
    fn lose(&mut self, target: PathBuf, end: &ProgramEnd, e: io::Error) -> DncError {
        self.current = None;
        self.record(ReceivedProgram {
            path: target.clone(),
            bytes: end.bytes,
            first_line: end.first_line,
            last_line: end.last_line,
            disposition: Disposition::WriteFailed,
            rejected_names: end.name.rejected.clone(),
            reason: Some(e.to_string()),
        });
        DncError::ProgramLost {
            path: target,
            next_line: end.last_line + 1,
            source: e,
        }
    }
}

/// Flush a finished program's temporary file to disk (an error drops the file).
fn finish_temp(tmp: TempProgram) -> io::Result<NamedTempFile> {
    tmp.out
        .into_inner()
        .map_err(io::IntoInnerError::into_error)?;
    tmp.file.as_file().sync_all()?;
    Ok(tmp.file)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Placed {
    New,
    Replaced,
    Kept,
}

/// Give the finished temporary file its name in one atomic step. Without `overwrite` the name
/// is created only if it does not exist yet; otherwise the existing file is kept and the
/// temporary file removed.
fn place(tmp: NamedTempFile, target: &Path, overwrite: bool) -> io::Result<Placed> {
    if overwrite {
        let existed = target.exists();
        tmp.persist(target).map_err(|e| e.error)?;
        return Ok(if existed {
            Placed::Replaced
        } else {
            Placed::New
        });
    }
    match tmp.persist_noclobber(target) {
        Ok(_) => Ok(Placed::New),
        Err(e) if e.error.kind() == io::ErrorKind::AlreadyExists => Ok(Placed::Kept),
        Err(e) => Err(e.error),
    }
}

/// Make the rename itself durable.
fn sync_dir(dir: &Path) -> io::Result<()> {
    #[cfg(unix)]
    {
        File::open(dir)?.sync_all()
    }
    #[cfg(not(unix))]
    {
        let _ = dir;
        Ok(())
    }
}

impl ProgramSink for ProgramWriter {
    type Error = DncError;

    /// A refused temporary file (a full disk) is not an error yet: the program's end names
    /// the program lost ([`ProgramWriter::lose`]).
    fn start(&mut self, _start: &ProgramStart) -> Result<(), DncError> {
        self.discard_current();
        let dir = &self.cfg.out_dir;
        match fs::create_dir_all(dir).and_then(|()| temp_files::create(dir)) {
            Ok(file) => match TempProgram::new(file) {
                Ok(t) => self.current = Some(t),
                Err(e) => self.failed = Some(e),
            },
            Err(e) => self.failed = Some(e),
        }
        Ok(())
    }

    /// A refused write drops the temporary file at once and swallows the rest of the
    /// program: its end, which knows the program's name, reports it lost.
    fn data(&mut self, bytes: &[u8]) -> Result<(), DncError> {
        if let Some(t) = self.current.as_mut() {
            if let Err(e) = t.out.write_all(bytes) {
                self.current = None;
                self.failed = Some(e);
            }
        }
        Ok(())
    }

    fn end(&mut self, end: ProgramEnd) -> Result<(), DncError> {
        self.file(end)
    }
}

impl Drop for ProgramWriter {
    fn drop(&mut self) {
        self.discard_current();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn template_numbers_and_checks() {
        let t = NameTemplate::default();
        assert_eq!(t.render(1), "received_001.nc");
        let t = NameTemplate::parse("prog{n:4}.mpf").unwrap();
        assert_eq!(t.render(12), "prog0012.mpf");
        assert!(NameTemplate::parse("plain.nc").is_err());
        assert!(NameTemplate::parse("../x{n}.nc").is_err());
        assert!(NameTemplate::parse("a/{n}.nc").is_err());
        assert!(NameTemplate::parse("{n:0}.nc").is_err());
        assert!(NameTemplate::parse("{n}{n}.nc").is_err());
    }
}
