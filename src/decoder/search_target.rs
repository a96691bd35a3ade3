//! Where a block search stops (TF5200 block search): the target as the operator names it.

use std::fmt;

use crate::vocab::axis::Position;

/// Block search target (TF5200 block search).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SearchTarget {
    /// The first block with this N number.
    BlockNumber(u32),
    /// The block with this block counter.
    Counter(u64),
    /// The first block starting at or after this byte offset of the main program / stream.
    Offset(u64),
}

impl fmt::Display for SearchTarget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SearchTarget::BlockNumber(n) => write!(f, "n:{n}"),
            SearchTarget::Counter(k) => write!(f, "count:{k}"),
            SearchTarget::Offset(o) => write!(f, "offset:{o}"),
        }
    }
}

impl std::str::FromStr for SearchTarget {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (kind, v) = s.split_once(':').ok_or_else(|| {
            format!("search target '{s}': expected n:<N>, count:<K> or offset:<BYTES>")
        })?;
        let bad = |_| format!("search target '{s}': '{v}' is not a whole number");
        match kind {
            "n" => v.parse().map(SearchTarget::BlockNumber).map_err(bad),
            "count" => v.parse().map(SearchTarget::Counter).map_err(bad),
            "offset" => v.parse().map(SearchTarget::Offset).map_err(bad),
            _ => Err(format!(
                "search target '{s}': kind must be n, count or offset"
            )),
        }
    }
}

#[derive(Debug, Clone, Copy)]
/// A block search under way.
pub(crate) struct Search {
    pub(crate) target: SearchTarget,
    /// Machine position when the search began: the positioning move starts here.
    pub(crate) from: Position,
}
