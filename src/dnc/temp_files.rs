//! The receiver's temporary program files: each is locked (`flock`, an exclusive advisory
//! lock) by the receiver that writes it for as long as it writes it, so
//! a later receiver removes only files whose lock it can take: their writer is gone.
//!
//! A name is `.ncchannel-receive-<run>-<random>.tmp` in the program directory, `<run>` being
//! this process's id and start time (only to tell a run's own files, [`remove_own`]). Whether a
//! file is stale never comes from the pid: a receiver in another PID namespace (a second
//! container sharing the folder), of another user or on another host sees the writer's lock,
//! not its pid. A file this process cannot open (another user's, mode 0600) or lock (a
//! filesystem without locks) is left alone. Across hosts this holds where the filesystem
//! carries `flock` to every client (NFS does; a mount with `local_lock=flock` or `nolock` does
//! not, and there receivers on different hosts must not share a folder).

use std::fs::{self, File};
use std::io;
use std::path::Path;
use std::sync::OnceLock;

use tempfile::NamedTempFile;

/// The start of every temporary file name.
const PREFIX: &str = ".ncchannel-receive-";
/// The end of every temporary file name.
const SUFFIX: &str = ".tmp";

/// What an attempt to lock a file found.
enum Lock {
    /// Taken: no one else holds it.
    Taken,
    /// Another open file (a running receiver) holds it.
    Held,
    /// The filesystem or platform refuses locks.
    Unavailable,
}

/// Try to take `file`'s exclusive lock without waiting (`flock`, released when the file is
/// closed, also when its process is killed).
#[cfg(unix)]
fn try_lock(file: &File) -> Lock {
    use rustix::fs::{flock, FlockOperation};
    match flock(file, FlockOperation::NonBlockingLockExclusive) {
        Ok(()) => Lock::Taken,
        Err(e) if e == rustix::io::Errno::WOULDBLOCK => Lock::Held,
        Err(_) => Lock::Unavailable,
    }
}

#[cfg(not(unix))]
fn try_lock(_file: &File) -> Lock {
    Lock::Unavailable
}

/// This run's tag: its process id and start time, so that a run's own files are told apart
/// from those of a receiver with the same pid in another PID namespace.
fn run_tag() -> &'static str {
    static TAG: OnceLock<String> = OnceLock::new();
    TAG.get_or_init(|| {
        let started_ns = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        format!("{}.{started_ns:x}", std::process::id())
    })
}

/// A new temporary file in `dir`, named for this run and locked by it until it is dropped or
/// renamed.
pub(crate) fn create(dir: &Path) -> io::Result<NamedTempFile> {
    // A cleaner may take the lock between the creation and ours and remove the file: then the
    // locked file is no longer the one at the path, and a new one is made.
    for _ in 0..8 {
        let file = tempfile::Builder::new()
            .prefix(&format!("{PREFIX}{}-", run_tag()))
            .suffix(SUFFIX)
            .tempfile_in(dir)
            .map_err(bare)?;
        match try_lock(file.as_file()) {
            Lock::Taken => {}
            Lock::Held => continue,
            // Without locks the file is still written; no cleaner can take it for stale.
            Lock::Unavailable => return Ok(file),
        }
        if same_file(file.as_file(), file.path())? {
            return Ok(file);
        }
    }
    Err(io::Error::other(
        "another receiver kept removing new temporary files",
    ))
}

/// Is `path` still the file `file` has open?
#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> io::Result<bool> {
    use std::os::unix::fs::MetadataExt;
    let open = file.metadata()?;
    match fs::symlink_metadata(path) {
        Ok(at_path) => Ok(open.dev() == at_path.dev() && open.ino() == at_path.ino()),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(e),
    }
}

#[cfg(not(unix))]
fn same_file(_file: &File, path: &Path) -> io::Result<bool> {
    Ok(path.exists())
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

/// The run tag in a temporary file name of ours, `None` for any other name.
fn owner(name: &str) -> Option<&str> {
    let rest = name.strip_prefix(PREFIX)?.strip_suffix(SUFFIX)?;
    let (tag, random) = rest.rsplit_once('-')?;
    if random.is_empty() || tag.is_empty() {
        return None;
    }
    Some(tag)
}

/// Remove `path` if its writer no longer holds its lock; whether it was removed.
fn remove_if_unlocked(path: &Path) -> io::Result<bool> {
    let file = match File::open(path) {
        Ok(f) => f,
        // Filed or removed meanwhile, or another user's: not ours to judge.
        Err(e)
            if matches!(
                e.kind(),
                io::ErrorKind::NotFound | io::ErrorKind::PermissionDenied
            ) =>
        {
            return Ok(false)
        }
        Err(e) => return Err(e),
    };
    match try_lock(&file) {
        Lock::Taken => {}
        Lock::Held => return Ok(false),
        // No locks on this filesystem: liveness cannot be known, so nothing is removed.
        Lock::Unavailable => return Ok(false),
    }
    // Holding the lock: the writer is gone. The path must still name the file locked.
    if !same_file(&file, path)? {
        return Ok(false);
    }
    match fs::remove_file(path) {
        Ok(()) => Ok(true),
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(false),
        Err(e) => Err(e),
    }
}

/// Remove the temporary files of ours in `dir` that `remove` picks (given the run tag and
/// the path); returns how many were removed. A missing `dir` has none.
fn remove_where(
    dir: &Path,
    mut remove: impl FnMut(&str, &Path) -> io::Result<bool>,
) -> io::Result<usize> {
    let entries = match fs::read_dir(dir) {
        Ok(rd) => rd,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(0),
        Err(e) => return Err(e),
    };
    let mut removed = 0;
    for entry in entries {
        let entry = entry?;
        let name = entry.file_name();
        let Some(tag) = name.to_str().and_then(owner) else {
            continue;
        };
        if entry.file_type()?.is_file() && remove(tag, &entry.path())? {
            removed += 1;
        }
    }
    Ok(removed)
}

/// At start: remove the files of receivers that no longer run (a second signal, SIGKILL, a
/// power loss): those whose lock can be taken, whatever their name's pid.
pub fn remove_stale(dir: &Path) -> io::Result<usize> {
    remove_where(dir, |_, path| remove_if_unlocked(path))
}

/// At an abandoned stop: remove this run's own files (a transfer thread that did not end in
/// time still holds one).
pub fn remove_own(dir: &Path) -> io::Result<usize> {
    let me = run_tag();
    remove_where(dir, |tag, path| {
        if tag != me {
            return Ok(false);
        }
        match fs::remove_file(path) {
            Ok(()) => Ok(true),
            // Its own transfer finished with it meanwhile.
            Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(false),
            Err(e) => Err(e),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_our_own_naming_is_recognised() {
        assert_eq!(owner(".ncchannel-receive-123-abcDEF.tmp"), Some("123"));
        assert_eq!(
            owner(".ncchannel-receive-123.18c2f-abcDEF.tmp"),
            Some("123.18c2f")
        );
        assert_eq!(owner(".ncchannel-receive-abcDEF.tmp"), None);
        assert_eq!(owner(".ncchannel-receive-123-.tmp"), None);
        assert_eq!(owner("PART.mpf"), None);
        assert_eq!(owner(".ncchannel-receive-123-abc.tmp.x"), None);
    }
}
