//! The receiver's temporary program files: named after the process that writes them, so each
//! run can remove the ones a killed receiver left behind without touching a running one's.
//!
//! A name is `.ncchannel-receive-<pid>-<random>.tmp` in the program directory. A file whose
//! process no longer exists is stale: nothing will ever rename it. Liveness comes from
//! `/proc/<pid>` (Linux); elsewhere no file is taken for stale, and only a run's own files are
//! removed ([`remove_own`]). Receivers sharing a folder are assumed to run on one host (a pid
//! from another host's receiver would look dead).

use std::fs;
use std::io;
use std::path::Path;

use tempfile::NamedTempFile;

/// The start of every temporary file name.
const PREFIX: &str = ".ncchannel-receive-";
/// The end of every temporary file name.
const SUFFIX: &str = ".tmp";

/// A new temporary file in `dir`, named for this process.
pub(crate) fn create(dir: &Path) -> io::Result<NamedTempFile> {
    tempfile::Builder::new()
        .prefix(&format!("{PREFIX}{}-", std::process::id()))
        .suffix(SUFFIX)
        .tempfile_in(dir)
        .map_err(bare)
}

/// tempfile adds the temporary path to its errors; the operator is told the disk's own
/// words and the program's name instead.
fn bare(e: io::Error) -> io::Error {
    let os = e
        .get_ref()
        .and_then(|inner| inner.source())
        .and_then(|s| s.downcast_ref::<io::Error>())
        .and_then(io::Error::raw_os_error);
    os.map_or(e, io::Error::from_raw_os_error)
}

/// The process id in a temporary file name of ours, `None` for any other name.
fn owner(name: &str) -> Option<u32> {
    let rest = name.strip_prefix(PREFIX)?.strip_suffix(SUFFIX)?;
    let (pid, random) = rest.split_once('-')?;
    if random.is_empty() {
        return None;
    }
    pid.parse().ok()
}

/// Is process `pid` running on this host?
fn alive(pid: u32) -> bool {
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

/// Remove the temporary files of ours in `dir` whose writer's id `remove` picks; returns how
/// many were removed. A missing `dir` has none.
fn remove_where(dir: &Path, mut remove: impl FnMut(u32) -> bool) -> io::Result<usize> {
    let entries = match fs::read_dir(dir) {
        Ok(rd) => rd,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(0),
        Err(e) => return Err(e),
    };
    let mut removed = 0;
    for entry in entries {
        let entry = entry?;
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(owner) else {
            continue;
        };
        if remove(pid) && entry.file_type()?.is_file() {
            match fs::remove_file(entry.path()) {
                Ok(()) => removed += 1,
                // Its own receiver finished with it meanwhile.
                Err(e) if e.kind() == io::ErrorKind::NotFound => {}
                Err(e) => return Err(e),
            }
        }
    }
    Ok(removed)
}

/// At start: remove the files of receivers that no longer run (a second signal, SIGKILL, a
/// power loss). This process has written none yet, so a file with its own id is stale too.
pub fn remove_stale(dir: &Path) -> io::Result<usize> {
    let me = std::process::id();
    remove_where(dir, |pid| pid == me || !alive(pid))
}

/// At an abandoned stop: remove this process's own files (a transfer thread that did not end
/// in time still holds one).
pub fn remove_own(dir: &Path) -> io::Result<usize> {
    let me = std::process::id();
    remove_where(dir, |pid| pid == me)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_our_own_naming_is_recognised() {
        assert_eq!(owner(".ncchannel-receive-123-abcDEF.tmp"), Some(123));
        assert_eq!(owner(".ncchannel-receive-abcDEF.tmp"), None);
        assert_eq!(owner(".ncchannel-receive-123-.tmp"), None);
        assert_eq!(owner("PART.mpf"), None);
        assert_eq!(owner(".ncchannel-receive-123-abc.tmp.x"), None);
    }
}
