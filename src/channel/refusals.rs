//! Stretches of refused stream writes: a writer that retries a full buffer every 250 µs, as
//! the interface prescribes (ADS 0x708, warning 11012), would otherwise put two event lines
//! per retry into the log (5 MB in 10 s). The first refusal of a stretch is logged as it
//! happens (`write` with `ok: false` and the warning); the rest are counted, and one
//! `writes_refused` event with the count closes the stretch.

use crate::runtime::Tick;

/// The stretch of refusals in progress, if any.
#[derive(Debug, Default)]
pub(crate) struct RefusalStretch {
    /// Refusals so far in the open stretch (0: none open).
    count: u64,
    /// The ISG code of the refusals.
    code: Option<u32>,
    /// Tick index of the stretch's first refusal.
    first_tick: u64,
    /// The latest tick the channel ran, for closing a stretch when the log ends.
    now: Option<Tick>,
}

/// A closed stretch: what its `writes_refused` event says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Closed {
    pub count: u64,
    pub code: Option<u32>,
    pub first_tick: u64,
}

impl RefusalStretch {
    /// One more refusal; `true` when it opens a stretch (then it is logged in full).
    pub(crate) fn refused(&mut self, tick: &Tick, code: Option<u32>) -> bool {
        self.count += 1;
        if self.count == 1 {
            self.code = code;
            self.first_tick = tick.index;
            return true;
        }
        false
    }

    /// The writer got through (or was refused for another reason): the stretch, if one is
    /// open, is over.
    pub(crate) fn close(&mut self) -> Option<Closed> {
        let count = std::mem::take(&mut self.count);
        (count > 0).then_some(Closed {
            count,
            code: self.code,
            first_tick: self.first_tick,
        })
    }

    /// The channel ran `tick`.
    pub(crate) fn seen(&mut self, tick: &Tick) {
        self.now = Some(*tick);
    }

    /// The last tick seen, to date the event that closes a stretch at the log's end.
    pub(crate) fn now(&self) -> Option<Tick> {
        self.now
    }
}
