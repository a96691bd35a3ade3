//! Block search: run a program up to a target block, collecting modal state without queueing
//! motion, then move from where the machine stood to where the program stands.

use std::fmt;

use super::io::DecoderIo;
use super::line::LineMeta;
use super::note::Note;
use super::Decoder;
use crate::lang::block::Block;
use crate::queue::{Action, Move, MoveKind};
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
pub(super) struct Search {
    pub(super) target: SearchTarget,
    /// Machine position when the search began: the positioning move starts here.
    pub(super) from: Position,
}

impl Decoder {
    /// A block met during block search: is it the target? Then the search ends here.
    pub(super) fn search_block(
        &mut self,
        block: &Block,
        text: &str,
        meta: LineMeta,
        io: &mut DecoderIo<'_>,
    ) {
        let Some(s) = self.search else {
            return;
        };
        let hit = match s.target {
            SearchTarget::BlockNumber(n) => block.n == Some(n),
            SearchTarget::Counter(k) => self.counter >= k,
            SearchTarget::Offset(o) => self.reader.depth() == 1 && meta.offset >= o,
        };
        if hit {
            self.finish_search(s, block, text, meta, io);
        }
    }

    pub(super) fn finish_search(
        &mut self,
        s: Search,
        block: &Block,
        text: &str,
        meta: LineMeta,
        io: &mut DecoderIo<'_>,
    ) {
        self.search = None;
        self.notes.push(Note::Search {
            target: s.target,
            found: true,
        });
        if s.from != self.modal.pos {
            let info = self.info(block, text, meta, io);
            let mv = Move {
                kind: MoveKind::Rapid,
                start: s.from,
                end: self.modal.pos,
                feed_mm_per_min: 0.0,
                path: Default::default(),
            };
            self.emit(info, Action::Move(mv), true, io);
        }
    }
}
