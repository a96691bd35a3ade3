//! The channel's log: its events, counters, errors and `#MSG` message, and the translation of
//! what the decoder and the motion report (`Note`, `MotionNote`) into events.

use super::hmi::Hmi;
use super::program::ProgramRun;
use super::refusals::RefusalStretch;
use super::techno::{TechnoNote, UnitSet};
use crate::decoder::Note;
use crate::motion::MotionNote;
use crate::queue::{BlockInfo, SyncMessage};
use crate::report::event::{EventBuffer, EventKind, ProgramEndKind};
use crate::runtime::Tick;
use crate::source::stream::{StreamWriteError, WARN_WRITE_REJECTED};
use crate::vocab::flush::FlushKind;
use crate::vocab::mode::{Mode, State};

/// Errors kept for the report (`ChannelStats::errors` counts all of them).
pub const MAX_LISTED_ERRORS: usize = 256;

/// An error as the channel keeps it: the ISG number and text, and the program and line that
/// raised it (`None` for errors no program line raised, such as a stream write refused).
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorRecord {
    pub code: u32,
    pub msg: String,
    pub prog: Option<String>,
    /// Line number in `prog`, 1-based.
    pub line: Option<u64>,
}

/// Counters the report shows.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ChannelStats {
    /// Blocks that took effect (one `block` event each).
    pub blocks: u64,
    pub interrupts: u64,
    pub warnings: u64,
    /// Every error raised (the first `MAX_LISTED_ERRORS` are kept with their text).
    pub errors: u64,
    pub(crate) programs_ended: u64,
}

/// A stream block that took effect, as the soak checker sees it: cheap enough to record for
/// every block of a 10-million-block run, where the event log would cost far more.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExecutedBlock {
    /// Byte offset of the line since stream start.
    pub offset: u64,
    pub n: Option<u32>,
}

/// What the channel must do after a motion note the log has written down.
#[derive(Debug, PartialEq)]
pub(super) enum AfterMotionNote {
    /// Nothing more.
    Go,
    /// A programmed stop (M00, M01 when on): HOLD if ACTIVE.
    ProgramStop,
    /// The program ended: READY.
    Ended,
    /// A planning error: raise it (the rest of the tick's notes are dropped).
    Fail(ErrorRecord),
}

/// The channel's events, counters and error list.
#[derive(Debug)]
pub(super) struct ChannelLog {
    /// 1-based channel number, on every event.
    number: u32,
    /// The tick's events, until the machine flushes them into the log.
    events: EventBuffer,
    /// Refused stream writes in a row, logged as one stretch.
    refusals: RefusalStretch,
    stats: ChannelStats,
    /// The first `MAX_LISTED_ERRORS` errors of the channel's life, oldest first.
    errors: Vec<ErrorRecord>,
    last_error: Option<ErrorRecord>,
    /// The latest `#MSG` text (kept until the next one or a reset).
    message: Option<String>,
    /// Record executed stream blocks in `executed` (soak checks); off by default.
    observe: bool,
    /// Executed stream blocks since the last [`ChannelLog::drain_executed`].
    executed: Vec<ExecutedBlock>,
}

impl ChannelLog {
    pub(super) fn new(number: u32, events_enabled: bool) -> Self {
        ChannelLog {
            number,
            events: EventBuffer::new(events_enabled),
            refusals: RefusalStretch::default(),
            stats: ChannelStats::default(),
            errors: Vec::new(),
            last_error: None,
            message: None,
            observe: false,
            executed: Vec::new(),
        }
    }

    pub(super) fn number(&self) -> u32 {
        self.number
    }
    pub(super) fn stats(&self) -> ChannelStats {
        self.stats
    }
    /// The first `MAX_LISTED_ERRORS` errors of the channel's life, oldest first.
    pub(super) fn errors(&self) -> &[ErrorRecord] {
        &self.errors
    }
    pub(super) fn last_error(&self) -> Option<&ErrorRecord> {
        self.last_error.as_ref()
    }
    /// The latest operator message an NC program sent with `#MSG` (`mc_message_r`).
    pub(super) fn message(&self) -> Option<&str> {
        self.message.as_deref()
    }
    /// Is the event log on (block events carry the block's text only then)?
    pub(super) fn events_enabled(&self) -> bool {
        self.events.enabled()
    }
    pub(super) fn events_mut(&mut self) -> &mut EventBuffer {
        &mut self.events
    }

    /// One event of this channel into the tick's buffer (nothing when the log is off).
    #[inline]
    pub(super) fn emit(&mut self, tick: &Tick, kind: EventKind) {
        self.events.push(tick, self.number, kind);
    }

    /// The channel ran `tick`.
    pub(super) fn seen(&mut self, tick: &Tick) {
        self.refusals.seen(tick);
    }

    /// Mode or state changed.
    pub(super) fn state(&mut self, tick: &Tick, mode: Mode, state: State) {
        self.emit(tick, EventKind::State { mode, state });
    }

    /// An operator message (`#MSG`): its event, and the channel's latest message
    /// (`mc_message_r`). A plain one comes when its block is decoded, a `SYN` one when
    /// execution reaches its block.
    fn operator_message(&mut self, tick: &Tick, text: String, save: bool) {
        self.emit(
            tick,
            EventKind::Message {
                text: text.clone(),
                save,
            },
        );
        self.message = Some(text);
    }

    pub(super) fn warn(&mut self, tick: &Tick, code: u32, msg: String) {
        self.stats.warnings += 1;
        self.emit(tick, EventKind::Warning { code, msg });
    }

    /// An error raised: its event, the count, the list and the last error. (Stopping the
    /// channel is the channel's.)
    pub(super) fn record_error(&mut self, tick: &Tick, record: ErrorRecord) {
        self.emit(
            tick,
            EventKind::Error {
                code: record.code,
                msg: record.msg.clone(),
                prog: record.prog.clone(),
                line: record.line,
            },
        );
        self.stats.errors += 1;
        // The report lists the first errors of a run; a soak raising the same expected
        // error for days must not grow memory, so the list is bounded and the rest counted.
        if self.errors.len() < MAX_LISTED_ERRORS {
            self.errors.push(record.clone());
        }
        self.last_error = Some(record);
    }

    /// NC reset: the last error and the `#MSG` message are cleared (the list and the counters
    /// stay: they cover the channel's life).
    pub(super) fn reset(&mut self) {
        self.last_error = None;
        self.message = None;
    }

    /// A stream write and its outcome: `write` event, the 11012 warning, refusal stretches.
    /// `false` for a retry inside a stretch of refusals: only counted, logged when it closes.
    pub(super) fn write(
        &mut self,
        tick: &Tick,
        bytes: usize,
        r: &Result<(), StreamWriteError>,
    ) -> bool {
        let code = r.as_ref().err().and_then(|e| e.isg_code());
        let full = matches!(r, Err(StreamWriteError::Full { .. }));
        if full {
            if !self.refusals.refused(tick, code) {
                // A retry within a stretch: counted, logged when the stretch closes.
                self.stats.warnings += 1;
                return false;
            }
        } else {
            self.close_refusals(tick);
        }
        self.emit(
            tick,
            EventKind::Write {
                bytes: bytes as u64,
                ok: r.is_ok(),
                code,
            },
        );
        if full {
            self.warn(
                tick,
                WARN_WRITE_REJECTED,
                "Error writing the object (stream buffer full)".into(),
            );
        }
        true
    }

    /// The log ends: a stretch of refused writes still open is closed with its count.
    pub(super) fn close_stretches(&mut self) {
        if let Some(tick) = self.refusals.now() {
            self.close_refusals(&tick);
        }
    }

    /// The `writes_refused` event of a stretch that is over (none when none was open).
    fn close_refusals(&mut self, tick: &Tick) {
        if let Some(c) = self.refusals.close() {
            self.emit(
                tick,
                EventKind::WritesRefused {
                    count: c.count,
                    code: c.code,
                    first_tick: c.first_tick,
                },
            );
        }
    }

    /// Record every executed stream block for [`ChannelLog::drain_executed`]. Whoever turns
    /// this on drains every tick: the record grows by the blocks of one tick only.
    pub(super) fn observe_stream_blocks(&mut self, on: bool) {
        self.observe = on;
        if !on {
            self.executed.clear();
        }
    }

    /// Whether stream blocks executed since the last [`ChannelLog::drain_executed`].
    pub(super) fn executed_pending(&self) -> bool {
        !self.executed.is_empty()
    }

    /// The stream blocks executed since the last call, in execution order.
    pub(super) fn drain_executed(&mut self) -> std::vec::Drain<'_, ExecutedBlock> {
        self.executed.drain(..)
    }

    /// Motion stopped for lack of stream data with `held` blocks in the lookahead window.
    pub(super) fn interrupt(&mut self, tick: &Tick, held: u64) {
        self.stats.interrupts += 1;
        self.emit(tick, EventKind::Interrupt { held });
    }

    /// One note of the decoder as events; an error note is handed back for the channel to
    /// raise (it stops the channel).
    #[inline]
    pub(super) fn decoder_note(&mut self, tick: &Tick, note: Note) -> Option<ErrorRecord> {
        match note {
            Note::ProgramStart { prog, stream } => self.emit(
                tick,
                EventKind::ProgramStart {
                    prog: prog.to_string(),
                    stream,
                },
            ),
            Note::Segment { bytes } => self.emit(
                tick,
                EventKind::Segment {
                    bytes: bytes as u64,
                },
            ),
            Note::Discard { bytes } => self.emit(
                tick,
                EventKind::Discard {
                    bytes: bytes as u64,
                },
            ),
            Note::Warning { code, msg } => self.warn(tick, code, msg),
            Note::Error {
                code,
                msg,
                prog,
                line,
                col,
            } => {
                let msg = match col {
                    Some(c) => format!("{msg} (column {c})"),
                    None => msg,
                };
                return Some(ErrorRecord {
                    code,
                    msg,
                    prog: Some(prog.to_string()),
                    line: Some(line as u64),
                });
            }
            Note::Search { target, found } => self.emit(
                tick,
                EventKind::Search {
                    target: target.to_string(),
                    found,
                },
            ),
            Note::Message { text, save } => self.operator_message(tick, text, save),
            Note::Cache { op, file } => self.emit(
                tick,
                EventKind::Cache {
                    op,
                    file: (!file.is_empty()).then_some(file),
                },
            ),
        }
        None
    }

    /// One note of the motion as events, in order: block events and the active block,
    /// flushes, programmed stops, a planning error, the program end. What the channel's
    /// state machine must do about it comes back.
    #[inline]
    pub(super) fn motion_note(
        &mut self,
        tick: &Tick,
        note: MotionNote,
        run: &mut ProgramRun,
        hmi: &mut Hmi,
    ) -> AfterMotionNote {
        match note {
            MotionNote::Started(info) => {
                if run.block_started(&info) {
                    self.emit(tick, EventKind::Resume);
                }
                self.block(tick, info);
            }
            MotionNote::Flush(FlushKind::Stop) if hmi.gate_flush_done() => {
                // The flush the single-block gate added: no program event.
            }
            MotionNote::Flush(kind) => self.emit(tick, EventKind::Flush { kind }),
            // The channel hands it to its technology units (channel/techno.rs).
            MotionNote::TechnoOutput(_) => {}
            MotionNote::Message(m) => {
                let SyncMessage { text, save } = *m;
                self.operator_message(tick, text, save);
            }
            MotionNote::ProgramStop { optional } => {
                let m = u32::from(optional);
                self.emit(tick, EventKind::ProgramStop { m });
                return AfterMotionNote::ProgramStop;
            }
            MotionNote::Error { code, msg, block } => {
                let (prog, line) = block.unzip();
                return AfterMotionNote::Fail(ErrorRecord {
                    code,
                    msg,
                    prog,
                    line,
                });
            }
            MotionNote::End { m, prog } => {
                self.emit(
                    tick,
                    EventKind::ProgramEnd {
                        prog: prog.to_string(),
                        end: ProgramEndKind::from_m(m),
                    },
                );
                self.stats.programs_ended += 1;
                run.ended();
                return AfterMotionNote::Ended;
            }
        }
        AfterMotionNote::Go
    }

    /// What the technology units did: one event per function output and per function
    /// acknowledged.
    pub(super) fn techno_notes(&mut self, tick: &Tick, notes: impl Iterator<Item = TechnoNote>) {
        for n in notes {
            let kind = match n {
                TechnoNote::Output {
                    unit,
                    set,
                    function: f,
                } => EventKind::TechnoOutput {
                    kind: f.kind,
                    number: f.number,
                    value: (f.add_value != 0).then_some(f.add_value),
                    sync: f.sync,
                    unit,
                    late: set == UnitSet::Late,
                    line: f.line,
                },
                TechnoNote::Acknowledged { function: f, at } => EventKind::TechnoAcknowledged {
                    kind: f.kind,
                    number: f.number,
                    waited_s: at.saturating_sub(f.output_at).as_secs_f64(),
                },
            };
            self.emit(tick, kind);
        }
    }

    /// A block took effect: counted, recorded for the soak when observed, one `block` event.
    #[inline]
    fn block(&mut self, tick: &Tick, info: BlockInfo) {
        self.stats.blocks += 1;
        if self.observe && info.stream {
            self.executed.push(ExecutedBlock {
                offset: info.offset,
                n: info.n,
            });
        }
        if self.events.enabled() {
            self.emit(
                tick,
                EventKind::Block {
                    prog: info.prog.to_string(),
                    line: info.line as u64,
                    offset: info.offset,
                    counter: info.counter,
                    n: info.n.map(u64::from),
                    text: info.text.map(String::from).unwrap_or_default(),
                },
            );
        }
    }
}
