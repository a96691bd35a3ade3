//! Where a command's output file goes: a path, or standard output for `-` (every output option
//! of every command says `-` the same way).

use std::io::{self, Write};
use std::path::Path;

/// Is `path` the `-` that names standard output?
pub(crate) fn is_stdout(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// Write `bytes` to `path`, or to standard output for `-`.
pub(crate) fn write(path: &Path, bytes: &[u8]) -> io::Result<()> {
    if is_stdout(path) {
        let mut out = io::stdout().lock();
        out.write_all(bytes)?;
        out.flush()
    } else {
        std::fs::write(path, bytes)
    }
}

/// Write `bytes` to `path` whole or not at all, or to standard output for `-`: into a
/// temporary file in `path`'s folder, synced, then renamed over `path` (`tempfile`'s
/// `persist`). A reader of `path` sees the old file or the new one, never part of one, even
/// when the writer is killed.
pub(crate) fn replace(path: &Path, bytes: &[u8]) -> io::Result<()> {
    if is_stdout(path) {
        return write(path, bytes);
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".ncchannel-").suffix(".tmp");
    // Readable as a file `std::fs::write` makes (0644 less the umask), not 0600: a report is
    // read by other users (a merge on a shared volume).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o644));
    }
    let mut tmp = builder.tempfile_in(dir)?;
    tmp.write_all(bytes)?;
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Open `path` for a stream of writes, or standard output for `-`.
pub(crate) fn create(path: &Path) -> io::Result<Box<dyn Write + Send>> {
    if is_stdout(path) {
        Ok(Box::new(io::stdout()))
    } else {
        Ok(Box::new(std::fs::File::create(path)?))
    }
}
