//! What the decoder reports besides queued blocks.

use std::sync::Arc;

use super::search_target::SearchTarget;

/// What the decoder reports besides queued blocks; the channel turns these into events.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Note {
    ProgramStart {
        prog: Arc<str>,
        stream: bool,
    },
    Segment {
        bytes: usize,
    },
    Discard {
        bytes: usize,
    },
    Warning {
        code: u32,
        msg: String,
    },
    Error {
        code: u32,
        msg: String,
        prog: Arc<str>,
        line: u32,
        col: Option<u32>,
    },
    Search {
        target: SearchTarget,
        found: bool,
    },
    Cache {
        op: crate::vocab::event::CacheOp,
        file: String,
    },
    /// `#MSG`: an operator message (`save`: `#MSG SAVE`, also to be written to a file).
    Message {
        text: String,
        save: bool,
    },
}
