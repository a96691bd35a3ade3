//! Reading a whole file with a size bound: every file ncchannel reads whole (NC programs,
//! stream files, scenarios) comes from outside, so none may make it allocate without limit.

use std::io::Read;
use std::path::Path;

/// Why a bounded read failed.
#[derive(Debug, thiserror::Error)]
pub(crate) enum BoundedReadError {
    #[error(transparent)]
    Io(#[from] std::io::Error),
    #[error("not a regular file (a FIFO, device or directory is not read)")]
    NotRegular,
    #[error("{bytes} bytes, more than the limit of {limit} bytes")]
    TooLarge { bytes: u64, limit: u64 },
}

/// The file's bytes, or [`BoundedReadError::TooLarge`] when it holds more than `limit` bytes.
/// The size is checked before reading (no allocation for a file that is too large) and again
/// while reading (the file may grow in between: at most `limit + 1` bytes are ever read).
/// A FIFO, device or directory is refused ([`BoundedReadError::NotRegular`]) without waiting:
/// the file is opened without blocking, so a FIFO with no writer does not hold the open.
pub(crate) fn read_file(path: &Path, limit: u64) -> Result<Vec<u8>, BoundedReadError> {
    let f = open_regular(path)?;
    let len = f.metadata()?.len();
    if len > limit {
        return Err(BoundedReadError::TooLarge { bytes: len, limit });
    }
    let mut buf = Vec::with_capacity(len as usize);
    f.take(limit.saturating_add(1)).read_to_end(&mut buf)?;
    if buf.len() as u64 > limit {
        return Err(BoundedReadError::TooLarge {
            bytes: buf.len() as u64,
            limit,
        });
    }
    Ok(buf)
}

/// `path` opened for reading if it is a regular file; never waits on a FIFO's writer.
pub(crate) fn open_regular(path: &Path) -> Result<std::fs::File, BoundedReadError> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(rustix::fs::OFlags::NONBLOCK.bits() as i32);
    }
    let f = options.open(path)?;
    if !f.metadata()?.is_file() {
        return Err(BoundedReadError::NotRegular);
    }
    Ok(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn within_the_limit_reads_all_and_beyond_it_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f");
        std::fs::write(&p, b"0123456789").unwrap();
        assert_eq!(read_file(&p, 10).unwrap(), b"0123456789");
        assert!(matches!(
            read_file(&p, 9),
            Err(BoundedReadError::TooLarge {
                bytes: 10,
                limit: 9
            })
        ));
        #[cfg(unix)]
        {
            let fifo = dir.path().join("fifo");
            rustix::fs::mkfifoat(
                rustix::fs::CWD,
                &fifo,
                rustix::fs::Mode::RUSR | rustix::fs::Mode::WUSR,
            )
            .unwrap();
            assert!(matches!(
                read_file(&fifo, 9),
                Err(BoundedReadError::NotRegular)
            ));
        }
        assert!(matches!(
            read_file(&dir.path().join("missing"), 9),
            Err(BoundedReadError::Io(_))
        ));
    }
}
