//! The main program run: which program runs, the block that took effect last, whether motion
//! waits for stream data, how the run finished, and the program text the live view lists.

use crate::source::loader::Loader;
use std::sync::Arc;

use crate::queue::BlockInfo;

/// How a channel's program run finished, for `ncchannel run`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Finish {
    Ended,
    Error,
}

/// The block that took effect last: what `mc_active_*` objects show.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ActiveBlock {
    /// Program (file) the block is in.
    pub prog: Arc<str>,
    /// Byte offset of the line in that program (in a stream: since stream start).
    pub offset: u64,
    /// ISG block counter of the block.
    pub counter: u64,
    pub n: Option<u32>,
    /// The block came from the stream interface (its offset counts from the stream start).
    pub stream: bool,
}

/// The run of the last started main program.
#[derive(Debug, Default)]
pub(super) struct ProgramRun {
    /// The main program running (ACTIVE or HOLD), if any.
    running: Option<Arc<str>>,
    /// How the last run finished, until taken.
    finish: Option<Finish>,
    /// Motion stopped for lack of stream data; a `resume` is owed.
    interrupted: bool,
    /// A block has run since the program start (no interrupt before the first).
    ran_any: bool,
    /// The block that took effect last since the program start.
    active: Option<ActiveBlock>,
    /// The last started main program's name and text (a shared handle to the decoder's copy),
    /// so the live view lists it after the decoder has read past its end.
    main_text: Option<(Arc<str>, Arc<Vec<u8>>)>,
}

impl ProgramRun {
    /// A main program is about to start: nothing of the last run counts any more.
    pub(super) fn starting(&mut self) {
        self.finish = None;
        self.ran_any = false;
        self.interrupted = false;
        self.active = None;
    }

    /// `name` runs (also when its start failed: the error belongs to it).
    pub(super) fn running_now(&mut self, name: &str) {
        self.running = Some(name.into());
    }

    /// The main program running (ACTIVE or HOLD), if any.
    pub(super) fn running(&self) -> Option<&str> {
        self.running.as_deref()
    }

    /// Keep the started main program's text for the live view.
    pub(super) fn keep_main_text(
        &mut self,
        kept: Option<(Arc<str>, Arc<Vec<u8>>)>,
        loader: &Loader,
    ) {
        // The last program's text may be the only hold on hundreds of MB: the loader thread
        // frees it, not this tick (the decoder's frames release theirs the same way).
        if let Some((_, old)) = std::mem::replace(&mut self.main_text, kept) {
            loader.release(old);
        }
    }

    /// The last started main program's text, if it is `prog`.
    pub(super) fn main_text(&self, prog: &str) -> Option<Arc<Vec<u8>>> {
        let (name, text) = self.main_text.as_ref()?;
        (**name == *prog).then(|| Arc::clone(text))
    }

    /// How the last program run finished, taken once.
    pub(super) fn take_finish(&mut self) -> Option<Finish> {
        self.finish.take()
    }

    /// A block took effect; `true` when it ends an interrupt (a `resume` is owed).
    pub(super) fn block_started(&mut self, info: &BlockInfo) -> bool {
        let resumed = std::mem::take(&mut self.interrupted);
        self.ran_any = true;
        self.note_active(info);
        resumed
    }

    /// The block that took effect last since the program start.
    pub(super) fn active_block(&self) -> Option<&ActiveBlock> {
        self.active.as_ref()
    }

    /// Remember the block that took effect. The program name is shared (`Arc`) and only
    /// replaced when it changes: this runs for every block, at tens per tick.
    fn note_active(&mut self, info: &BlockInfo) {
        match &mut self.active {
            Some(a) if Arc::ptr_eq(&a.prog, &info.prog) => {
                a.offset = info.offset;
                a.counter = info.counter;
                a.n = info.n;
                a.stream = info.stream;
            }
            _ => {
                self.active = Some(ActiveBlock {
                    prog: info.prog.clone(),
                    offset: info.offset,
                    counter: info.counter,
                    n: info.n,
                    stream: info.stream,
                })
            }
        }
    }

    /// May motion waiting for data count as an interrupt: a block has run (or waits in the
    /// lookahead window) and no interrupt is open yet.
    pub(super) fn may_interrupt(&self, held_blocks: usize) -> bool {
        (self.ran_any || held_blocks > 0) && !self.interrupted
    }

    /// Motion stopped for lack of stream data: a `resume` is owed.
    pub(super) fn interrupt(&mut self) {
        self.interrupted = true;
    }

    /// The program ran to its end.
    pub(super) fn ended(&mut self) {
        self.running = None;
        self.finish = Some(Finish::Ended);
        self.interrupted = false;
    }

    /// An error stopped the channel: the run, if one was on, finished with it.
    pub(super) fn failed(&mut self) {
        if self.finish.is_none() && self.running.is_some() {
            self.finish = Some(Finish::Error);
        }
        self.running = None;
    }

    /// NC reset: the running program (if any) is abandoned; returned for its `program_end`.
    pub(super) fn reset(&mut self) -> Option<Arc<str>> {
        self.active = None;
        self.interrupted = false;
        self.running.take()
    }
}
