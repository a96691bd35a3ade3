//! The shipped set built into the binary: `params/` (parameter lists, runtime.toml, soak
//! scenarios) and `nc/` (the demo and example programs), for an installed binary run outside
//! the repository, and for `ncchannel init DIR`.
//!
//! The lists name their files by relative paths (`pfad[0].prg[0] ../nc`, a scenario's
//! `params = "startup.lis"`), so the set is used as files: written once into a cache folder
//! named by the set's hash, then read by the same loader as any installation. Nothing is
//! interpreted from memory that a user could not also read from disk.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use include_dir::{include_dir, Dir, DirEntry};

/// `params/` as shipped.
static PARAMS: Dir<'static> = include_dir!("$CARGO_MANIFEST_DIR/params");
/// `nc/` as shipped.
static NC: Dir<'static> = include_dir!("$CARGO_MANIFEST_DIR/nc");

/// The two top folders of the set and their names under a target folder.
const FOLDERS: [(&str, &Dir<'static>); 2] = [("params", &PARAMS), ("nc", &NC)];

/// The start-up list every command reads unless told otherwise, relative to the current folder.
pub const DEFAULT_STARTUP_LIST: &str = "params/startup.lis";

/// Environment variable naming the start-up list when `--params` is not given.
pub const PARAMS_ENV: &str = "NCCHANNEL_PARAMS";

#[derive(Debug, thiserror::Error)]
pub enum ShippedError {
    #[error("{path}: already exists; `init` writes only into a folder without params/ and nc/")]
    Exists { path: PathBuf },
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: io::Error },
}

fn io_at(path: &Path) -> impl FnOnce(io::Error) -> ShippedError + '_ {
    move |source| ShippedError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Every file of the set: its path relative to the target folder (`params/startup.lis`) and
/// its bytes.
fn files() -> Vec<(PathBuf, &'static [u8])> {
    fn walk(dir: &'static Dir<'static>, top: &Path, out: &mut Vec<(PathBuf, &'static [u8])>) {
        for entry in dir.entries() {
            match entry {
                DirEntry::Dir(d) => walk(d, top, out),
                DirEntry::File(f) => out.push((top.join(f.path()), f.contents())),
            }
        }
    }
    let mut out = Vec::new();
    for (name, dir) in FOLDERS {
        walk(dir, Path::new(name), &mut out);
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

/// FNV-1a over every path and content: names the cache folder, so a binary with other
/// shipped files never reads an older copy.
fn set_hash() -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for (path, bytes) in files() {
        for b in path
            .to_string_lossy()
            .bytes()
            .chain([0])
            .chain(bytes.iter().copied())
        {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

/// Write the set under `root` (which must exist), each file created new.
fn write_set(root: &Path) -> Result<usize, ShippedError> {
    let files = files();
    for (rel, bytes) in &files {
        let path = root.join(rel);
        if let Some(parent) = path.parent() {
            fs::create_dir_all(parent).map_err(io_at(parent))?;
        }
        fs::write(&path, bytes).map_err(io_at(&path))?;
    }
    Ok(files.len())
}

/// `ncchannel init DIR`: write `DIR/params/` and `DIR/nc/` to edit. Refused, with nothing
/// written, when either exists; the set is written into a temporary folder inside `DIR` and
/// moved into place, so an interrupted `init` leaves no half set under the final names.
pub fn init(dir: &Path) -> Result<usize, ShippedError> {
    for (name, _) in FOLDERS {
        let path = dir.join(name);
        if path.exists() {
            return Err(ShippedError::Exists { path });
        }
    }
    fs::create_dir_all(dir).map_err(io_at(dir))?;
    let staging = tempfile::Builder::new()
        .prefix(".ncchannel-init-")
        .tempdir_in(dir)
        .map_err(io_at(dir))?;
    let count = write_set(staging.path())?;
    for (name, _) in FOLDERS {
        let to = dir.join(name);
        fs::rename(staging.path().join(name), &to).map_err(io_at(&to))?;
    }
    Ok(count)
}

/// The folder the set is read from when the current folder has none: the user's cache
/// (`$XDG_CACHE_HOME`, else `$HOME/.cache`, else the temporary folder), `ncchannel/set-<hash>`.
fn cache_root() -> PathBuf {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME")
                .filter(|v| !v.is_empty())
                .map(|h| PathBuf::from(h).join(".cache"))
        })
        .unwrap_or_else(std::env::temp_dir);
    base.join("ncchannel")
        .join(format!("set-{:016x}", set_hash()))
}

/// The cached copy of the set, written on first use. Concurrent first uses each write a
/// private copy and move it into place; the loser of the race removes its own and reads the
/// winner's, so no process ever reads a half-written set. When the cache folder cannot be
/// written (a read-only home, a container without one), the set is written into a private
/// temporary folder for this process instead ([`private_copy`]), with one line that says so.
pub fn cached() -> Result<PathBuf, ShippedError> {
    if let Some(dir) = PRIVATE_COPY
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .as_ref()
    {
        return Ok(dir.path().to_path_buf());
    }
    let root = cache_root();
    match write_cache(&root) {
        Ok(root) => Ok(root),
        Err(e) => {
            let copy = private_copy()?;
            log::warn!(
                "{e}: the cache folder cannot be written; the set built into ncchannel is read from a private copy for this run ({}), removed at exit",
                copy.display()
            );
            Ok(copy)
        }
    }
}

fn write_cache(root: &Path) -> Result<PathBuf, ShippedError> {
    if root.is_dir() {
        return Ok(root.to_path_buf());
    }
    let parent = root.parent().unwrap_or(Path::new("."));
    fs::create_dir_all(parent).map_err(io_at(parent))?;
    let staging = tempfile::Builder::new()
        .prefix(".set-")
        .tempdir_in(parent)
        .map_err(io_at(parent))?;
    write_set(staging.path())?;
    let staged = staging.keep();
    if let Err(e) = fs::rename(&staged, root) {
        let _ = fs::remove_dir_all(&staged);
        if !root.is_dir() {
            return Err(ShippedError::Io {
                path: root.to_path_buf(),
                source: e,
            });
        }
    }
    Ok(root.to_path_buf())
}

/// The process's own copy of the set when the cache cannot be written: a new folder in the
/// temporary folder, readable by this user only (`tempfile`), written once per process and
/// removed by [`remove_private_copy`] when the command ends.
static PRIVATE_COPY: std::sync::Mutex<Option<tempfile::TempDir>> = std::sync::Mutex::new(None);

fn private_copy() -> Result<PathBuf, ShippedError> {
    let mut held = PRIVATE_COPY.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(dir) = held.as_ref() {
        return Ok(dir.path().to_path_buf());
    }
    let tmp = std::env::temp_dir();
    let dir = tempfile::Builder::new()
        .prefix("ncchannel-set-")
        .tempdir_in(&tmp)
        .map_err(io_at(&tmp))?;
    write_set(dir.path())?;
    let path = dir.path().to_path_buf();
    *held = Some(dir);
    Ok(path)
}

/// Remove the private copy of the set, if this process wrote one (the command has ended).
pub fn remove_private_copy() {
    let taken = PRIVATE_COPY
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .take();
    drop(taken);
}

/// Whether `rel` (like `params/soak/stream_resets.toml` or `nc/demo.nc`) is a file of the set.
pub fn holds(rel: &Path) -> bool {
    files().iter().any(|(p, _)| p == rel)
}

/// Where a shipped file named relative to the current folder is read from: the path itself
/// when it exists (a clone, or a folder made by `init`), else the cached copy of the set when
/// the set holds it, else the path unchanged for the caller to report as missing.
pub fn locate(path: &Path) -> Result<PathBuf, ShippedError> {
    if path.exists() || path.is_absolute() || !holds(&normal(path)) {
        return Ok(path.to_path_buf());
    }
    let root = cached()?;
    static SAID: std::sync::Once = std::sync::Once::new();
    SAID.call_once(|| log::info!(
        "{}: not in the current folder; reading the copy built into ncchannel ({}); `ncchannel init DIR` writes the set out to edit",
        path.display(),
        root.display()
    ));
    Ok(root.join(normal(path)))
}

/// `./params/x` → `params/x`: the set's own form of a relative path.
fn normal(path: &Path) -> PathBuf {
    path.components()
        .filter(|c| !matches!(c, std::path::Component::CurDir))
        .collect()
}

/// The start-up list a command reads: `--params` if given, then `$NCCHANNEL_PARAMS` (clap
/// fills both into `given`), then `./params/startup.lis`, then the shipped set.
pub fn startup_list(given: Option<&Path>) -> Result<PathBuf, ShippedError> {
    match given {
        Some(p) => Ok(p.to_path_buf()),
        None => locate(Path::new(DEFAULT_STARTUP_LIST)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_set_holds_the_lists_the_demo_and_the_scenarios() {
        for f in [
            "params/startup.lis",
            "params/runtime.toml",
            "params/soak/stream_resets.toml",
            "nc/demo.nc",
        ] {
            assert!(holds(Path::new(f)), "{f}");
        }
        assert!(!holds(Path::new("params/nosuch.lis")));
    }

    #[test]
    fn init_writes_the_set_and_refuses_a_second_time() {
        let dir = tempfile::tempdir().unwrap();
        let n = init(dir.path()).unwrap();
        assert_eq!(n, files().len());
        assert_eq!(
            fs::read(dir.path().join("nc/demo.nc")).unwrap(),
            NC.get_file("demo.nc").unwrap().contents()
        );
        assert!(matches!(init(dir.path()), Err(ShippedError::Exists { .. })));
        // Nothing but the two folders: the staging folder is gone.
        let mut names: Vec<_> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        names.sort();
        assert_eq!(names, ["nc", "params"]);
    }

    #[test]
    fn locate_keeps_an_existing_or_unknown_path() {
        assert_eq!(
            locate(Path::new("no/such/file.lis")).unwrap(),
            PathBuf::from("no/such/file.lis")
        );
        assert_eq!(
            normal(Path::new("./params/x.lis")),
            PathBuf::from("params/x.lis")
        );
    }
}
