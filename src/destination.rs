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

/// Open `path` for a stream of writes, or standard output for `-`.
pub(crate) fn create(path: &Path) -> io::Result<Box<dyn Write + Send>> {
    if is_stdout(path) {
        Ok(Box::new(io::stdout()))
    } else {
        Ok(Box::new(std::fs::File::create(path)?))
    }
}
