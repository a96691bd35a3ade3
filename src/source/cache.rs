//! The channel's file cache (`#CACHE`, TF5200 File Caching): global subroutines and cycles
//! held in memory so that calling them no longer touches the file system.

use thiserror::Error;

use super::loader::PendingRead;
use super::store::{Opened, ProgramKind, ProgramStore, ProgramText, StoreError};
use crate::vocab::event::CacheOp;

/// Cache limits from the lists (P-STUP-00050..52 / P-CHAN-00500..504).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CacheLimits {
    /// `FCT_USE_CACHED_FILES` set.
    pub enabled: bool,
    /// `max_cache_number`: files.
    pub max_files: usize,
    /// `max_cache_size`: bytes per file.
    pub max_file_bytes: u64,
}

#[derive(Debug, Error, Clone, PartialEq)]
pub enum CacheError {
    #[error("#CACHE needs file caching: set configuration.channel[i].decoder.function FCT_USE_CACHED_FILES in the start-up list (or configuration.decoder.function in the channel list)")]
    NotEnabled,
    #[error("cache full: {max} files cached, '{name}' cannot be loaded")]
    Full { name: String, max: usize },
    #[error("file for cache not found: '{0}'")]
    NotFound(String),
    #[error("'{name}' is {bytes} bytes, larger than max_cache_size {max}")]
    TooLarge { name: String, bytes: u64, max: u64 },
    #[error("'{name}' could not be read for the cache: {reason}")]
    Unreadable { name: String, reason: String },
}

impl CacheError {
    /// The error id: the kernel's (TF5200 File Caching, diagnosis list), or ours for
    /// [`CacheError::NotEnabled`] (no kernel id known); see `crate::lang::codes`.
    pub fn code(&self) -> u32 {
        use crate::lang::codes;
        match self {
            CacheError::NotEnabled => codes::CACHE_NOT_ENABLED,
            CacheError::Full { .. } => codes::CACHE_FULL,
            CacheError::NotFound(_) => codes::CACHE_FILE_NOT_FOUND,
            CacheError::TooLarge { .. } => codes::CACHE_FILE_TOO_LARGE,
            CacheError::Unreadable { .. } => codes::CACHE_FILE_NOT_FOUND,
        }
    }
}

/// Where `#CACHE LOAD` stands after [`Cache::load`].
#[derive(Debug)]
pub enum LoadStep {
    Done(Loaded),
    /// The file is large: the loader reads it; hand its text to [`Cache::finish_load`].
    Reading(PendingRead),
}

/// What `#CACHE LOAD` did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Loaded {
    /// The file was not cached before.
    New,
    /// It was: its text was replaced by the file's current content.
    Refreshed,
}

impl Loaded {
    /// The `op` of the `cache` event.
    pub fn op(self) -> CacheOp {
        match self {
            Loaded::New => CacheOp::Load,
            Loaded::Refreshed => CacheOp::Refresh,
        }
    }
}

#[derive(Debug, Clone)]
struct CacheEntry {
    /// Lower-case name: cache names are case-insensitive.
    key: String,
    program: ProgramText,
}

/// One channel's cache. A refresh replaces an entry's text as a whole; a frame already
/// running from the old text holds its own reference and finishes with it.
#[derive(Debug, Clone)]
pub struct Cache {
    limits: CacheLimits,
    entries: Vec<CacheEntry>,
    /// Calls served from the cache.
    pub hits: u64,
}

impl Cache {
    pub fn new(limits: CacheLimits) -> Self {
        Cache {
            limits,
            entries: Vec::new(),
            hits: 0,
        }
    }

    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    #[cfg(test)]
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// `#CACHE LOAD [FILE=name]`: load, or refresh when already cached. The file is read
    /// through the store, so the load counts as a file-system open and pays its latency; a
    /// file too large for the tick's inline read budget is read by the loader
    /// ([`LoadStep::Reading`]).
    pub fn load(&mut self, name: &str, store: &mut ProgramStore) -> Result<LoadStep, CacheError> {
        if !self.limits.enabled {
            return Err(CacheError::NotEnabled);
        }
        self.check_room(name)?;
        // Check the size before reading: a huge file is refused without being read.
        let path = store
            .find(name, ProgramKind::Subroutine)
            .map_err(|_| CacheError::NotFound(name.to_string()))?;
        let bytes = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        self.check_size(name, bytes)?;
        let opened = store
            .open_file(name, ProgramKind::Subroutine)
            .map_err(|e| read_refusal(name, e))?;
        match opened {
            Opened::File(program) => self.finish_load(name, Ok(program)).map(LoadStep::Done),
            Opened::Loading(p) => Ok(LoadStep::Reading(p)),
            Opened::Stream { .. } => Err(CacheError::NotFound(name.to_string())),
        }
    }

    /// The second half of [`Cache::load`]: the file's text (or why it could not be read)
    /// goes into the cache.
    pub fn finish_load(
        &mut self,
        name: &str,
        read: Result<ProgramText, StoreError>,
    ) -> Result<Loaded, CacheError> {
        let program = read.map_err(|e| read_refusal(name, e))?;
        self.check_size(name, program.text.len() as u64)?;
        self.check_room(name)?;
        let key = name.to_ascii_lowercase();
        Ok(match self.entries.iter().position(|e| e.key == key) {
            Some(i) => {
                self.entries[i].program = program;
                Loaded::Refreshed
            }
            None => {
                self.entries.push(CacheEntry { key, program });
                Loaded::New
            }
        })
    }

    /// A new entry needs a free place (a refresh does not).
    fn check_room(&self, name: &str) -> Result<(), CacheError> {
        let cached = self
            .entries
            .iter()
            .any(|e| e.key.eq_ignore_ascii_case(name));
        if !cached && self.entries.len() >= self.limits.max_files {
            return Err(CacheError::Full {
                name: name.to_string(),
                max: self.limits.max_files,
            });
        }
        Ok(())
    }

    fn check_size(&self, name: &str, bytes: u64) -> Result<(), CacheError> {
        if bytes > self.limits.max_file_bytes {
            return Err(CacheError::TooLarge {
                name: name.to_string(),
                bytes,
                max: self.limits.max_file_bytes,
            });
        }
        Ok(())
    }

    /// `#CACHE CLEAR [FILE=name]`: silent when not cached.
    pub fn clear(&mut self, name: &str) -> Result<(), CacheError> {
        if !self.limits.enabled {
            return Err(CacheError::NotEnabled);
        }
        self.entries.retain(|e| !e.key.eq_ignore_ascii_case(name));
        Ok(())
    }

    /// `#CACHE CLEAR ALL`.
    pub fn clear_all(&mut self) -> Result<(), CacheError> {
        if !self.limits.enabled {
            return Err(CacheError::NotEnabled);
        }
        self.entries.clear();
        Ok(())
    }

    /// Channel reset: the cache empties (TF5200 File Caching: RESET).
    pub fn reset(&mut self) {
        self.entries.clear();
    }

    /// A call looks here before the file system.
    pub fn get(&mut self, name: &str) -> Option<ProgramText> {
        let e = self
            .entries
            .iter()
            .find(|e| e.key.eq_ignore_ascii_case(name))?;
        self.hits += 1;
        Some(e.program.clone())
    }

    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.entries.iter().map(|e| &*e.program.name)
    }
}

/// A store refusal as the cache reports it.
fn read_refusal(name: &str, e: StoreError) -> CacheError {
    match e {
        StoreError::SubroutineNotFound(_) | StoreError::MainNotFound(_) => {
            CacheError::NotFound(name.to_string())
        }
        other => CacheError::Unreadable {
            name: name.to_string(),
            reason: other.to_string(),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::source::store::{SearchDir, PATH_MAIN, PATH_SUB};
    use std::fs;

    fn store(dir: &std::path::Path) -> ProgramStore {
        ProgramStore::new(
            vec![SearchDir {
                dir: dir.to_path_buf(),
                kinds: PATH_MAIN | PATH_SUB,
                priority: 0,
            }],
            None,
        )
    }

    /// A load of a small file, done in the call.
    fn done(r: Result<LoadStep, CacheError>) -> Result<Loaded, CacheError> {
        r.map(|step| match step {
            LoadStep::Done(l) => l,
            LoadStep::Reading(p) => panic!("a small file is read inline: {p:?}"),
        })
    }

    fn limits(max_files: usize, max_file_bytes: u64) -> CacheLimits {
        CacheLimits {
            enabled: true,
            max_files,
            max_file_bytes,
        }
    }

    #[test]
    fn load_refresh_clear_and_limits() {
        let d = tempfile::tempdir().unwrap();
        fs::write(d.path().join("A.cyc"), "M17\n").unwrap();
        fs::write(d.path().join("b.cyc"), "M17\n").unwrap();
        fs::write(d.path().join("c.cyc"), "M17\n").unwrap();
        fs::write(d.path().join("big.cyc"), vec![b'x'; 11]).unwrap();
        let mut s = store(d.path());
        let mut c = Cache::new(limits(2, 10));
        assert_eq!(done(c.load("a.cyc", &mut s)), Ok(Loaded::New));
        assert_eq!(done(c.load("A.CYC", &mut s)), Ok(Loaded::Refreshed));
        assert_eq!(done(c.load("b.cyc", &mut s)), Ok(Loaded::New));
        assert_eq!(c.load("c.cyc", &mut s).unwrap_err().code(), 21562);
        c.clear("B.cyc").unwrap();
        assert_eq!(c.load("nope.cyc", &mut s).unwrap_err().code(), 21563);
        let opens = s.stats().opens;
        assert_eq!(c.load("big.cyc", &mut s).unwrap_err().code(), 21564);
        assert_eq!(s.stats().opens, opens, "too large: refused unread");
        c.clear("not-cached.cyc").unwrap();
        assert_eq!(c.len(), 1);
        assert!(c.get("a.CYC").is_some() && c.get("b.cyc").is_none());
        assert_eq!(c.hits, 1);
        c.clear_all().unwrap();
        assert!(c.is_empty());
    }

    #[test]
    fn a_refresh_leaves_a_running_copy_alone() {
        let d = tempfile::tempdir().unwrap();
        fs::write(d.path().join("s.sub"), "X1\n").unwrap();
        let mut s = store(d.path());
        let mut c = Cache::new(limits(1, 100));
        c.load("s.sub", &mut s).unwrap();
        let running = c.get("s.sub").unwrap();
        fs::write(d.path().join("s.sub"), "X2\n").unwrap();
        c.load("s.sub", &mut s).unwrap();
        assert_eq!(&*running.text, b"X1\n");
        assert_eq!(&*c.get("s.sub").unwrap().text, b"X2\n");
    }

    #[test]
    fn everything_but_reset_needs_the_function() {
        let d = tempfile::tempdir().unwrap();
        let mut s = store(d.path());
        let mut c = Cache::new(CacheLimits {
            enabled: false,
            max_files: 0,
            max_file_bytes: 0,
        });
        assert_eq!(
            c.load("x", &mut s).unwrap_err().code(),
            crate::lang::codes::CACHE_NOT_ENABLED
        );
        assert_eq!(
            c.clear("x").unwrap_err().code(),
            crate::lang::codes::CACHE_NOT_ENABLED
        );
        assert_eq!(
            c.clear_all().unwrap_err().code(),
            crate::lang::codes::CACHE_NOT_ENABLED
        );
        c.reset();
    }
}
