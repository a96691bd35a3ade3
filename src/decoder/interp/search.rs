//! Block search: run a program up to a target block, collecting modal state without queueing
//! motion, then move from where the machine stood to where the program stands.

use super::Interpreter;
use crate::decoder::io::DecoderIo;
use crate::decoder::line::BlockAt;
use crate::decoder::note::Note;
use crate::decoder::reader::Reader;
use crate::decoder::search_target::{Search, SearchTarget};
use crate::queue::{Action, Move, MoveKind};

impl Interpreter {
    /// A block met during block search: is it the target? Then the search ends here.
    pub(in crate::decoder) fn search_block(
        &mut self,
        at: BlockAt<'_>,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) {
        let Some(s) = self.search else {
            return;
        };
        let hit = match s.target {
            SearchTarget::BlockNumber(n) => at.block.n == Some(n),
            SearchTarget::Counter(k) => self.counter >= k,
            SearchTarget::Offset(o) => rd.depth() == 1 && at.meta.offset >= o,
        };
        if hit {
            self.finish_search(s, at, rd, notes, io);
        }
    }

    pub(super) fn finish_search(
        &mut self,
        s: Search,
        at: BlockAt<'_>,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) {
        self.search = None;
        notes.push(Note::Search {
            target: s.target,
            found: true,
        });
        if s.from != self.modal.pos {
            let info = self.info(rd, at, io);
            let mv = Move {
                kind: MoveKind::Rapid,
                start: s.from,
                end: self.modal.pos,
                feed_mm_per_min: 0.0,
                path: Default::default(),
            };
            self.emit(info, Action::Move(Box::new(mv)), true, io);
        }
    }
}
