//! Event words named below the event log: the file cache reports its operations in them, the
//! decoder passes them up, and `report::event` writes them (`op` of `cache`).

use serde::Serialize;

/// A file cache operation (TF5200 File Caching; `op` of `cache`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CacheOp {
    /// `#CACHE LOAD` of a file not yet cached.
    Load,
    /// `#CACHE LOAD` of a cached file that changed on disk.
    Refresh,
    /// `#CACHE CLEAR`.
    Clear,
    /// `#CACHE CLEAR ALL`.
    ClearAll,
    /// A subroutine call served from the cache.
    Hit,
}
