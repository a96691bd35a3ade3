//! One NC channel: the ISG mode and state machine (HLI mode/state numbers) around the parts it owns —
//! stream interface, program store, file cache, decoder, block queue and motion.
//!
//! Everything a client does to a channel (stream writes, commands) and everything the tick
//! does happens through this type, in the runtime's one thread; errors and warnings carry
//! their ISG numbers and become events.

use std::sync::Arc;

use thiserror::Error;

use crate::decoder::modal::ZeroOffsets;
use crate::decoder::{Decoder, DecoderIo, DecoderSettings, DecoderState, Note, SearchTarget};
use crate::motion::{AxisLimits, Motion, MotionNote, PlannerSettings};
use crate::queue::{Action, BlockQueue, QueuedBlock};
use crate::report::event::{EventBuffer, EventKind, ProgramEndKind};
use crate::runtime::Tick;
use crate::source::cache::{Cache, CacheLimits};
use crate::source::store::{FsLatency, ProgramStore, SearchDir, StoreStats};
use crate::source::stream::{StreamBuffer, StreamWriteError};
use crate::vocab::axis::{Position, AXIS_LETTERS, MAX_AXES};

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

pub use crate::source::stream::{ERR_NO_LINE_END, WARN_WRITE_REJECTED};

pub mod door;
mod refusals;

pub use crate::vocab::mode::{Mode, State};
use door::{HmiOp, Op, Reply, TraceOp};

/// Why a command was refused.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CommandError {
    #[error("value {0} is not a mode or state")]
    InvalidValue(i32),
    #[error("not possible in mode {mode} / state {state}")]
    Busy { mode: Mode, state: State },
    #[error("no program selected (command parameter 0x108)")]
    NoProgram,
    #[error("program could not be started: {code} {msg}")]
    StartFailed { code: u32, msg: String },
    #[error("feed override {0} outside 0..200 %")]
    BadOverride(f64),
}

/// Everything a channel is built from (parameter lists and runtime.toml, already checked).
#[derive(Debug, Clone)]
pub struct ChannelSettings {
    /// 1-based channel number.
    pub number: u32,
    pub decoder: DecoderSettings,
    /// Block queue capacity: lookahead window plus decoder buffer, blocks.
    pub(crate) queue_capacity: usize,
    pub axes: Vec<AxisLimits>,
    /// Lookahead window (runtime.toml `[planner]`).
    pub planner: PlannerSettings,
    pub(crate) search_dirs: Vec<SearchDir>,
    /// `streaming_prog_file`; `None` = streaming off.
    pub(crate) streaming_prog: Option<String>,
    pub cache: CacheLimits,
    /// Simulated cost of each program file read (runtime.toml `fs_latency_us…`).
    pub(crate) fs_latency: FsLatency,
    /// Tool radii by D number for G41/G42, mm (`tools.lis`).
    pub tools: Vec<(u32, f64)>,
}

/// How a channel's program run finished, for `ncchannel run`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Finish {
    Ended,
    Error,
}

/// A stream block that took effect, as the soak checker sees it: cheap enough to record for
/// every block of a 10-million-block run, where the event log would cost far more.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExecutedBlock {
    /// Byte offset of the line since stream start.
    pub offset: u64,
    pub n: Option<u32>,
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

/// What an HMI commands besides mode and state: the COM task's `mc_command_*` objects
/// (ISG kernel object list, `SamWieHTWG/web-api` `examples/example1-hello-cnc/cnc_objects.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct HmiCommands {
    /// `mc_command_single_block_w`: one block per start.
    pub(crate) single_block: bool,
    /// `mc_command_M01_stop_enable_w`: M01 stops like M00.
    pub(crate) optional_stop: bool,
    /// `mc_command_block_ignore_w`: skip levels 1–10 as the kernel's mask (level n = bit n−1).
    pub(crate) skip_levels: u32,
    /// `mc_command_execution_mode_w`: bit 0 = block search at the next start.
    pub(crate) execution_mode: i32,
    /// `mc_feedhold_channel_w`: the HMI's feed hold holds the running program; only its
    /// release (or an operator start, a reset, the program's end) lets it go.
    pub(crate) feed_hold: bool,
    pub search: SearchCommand,
}

/// Block-search parameters (`mc_cmd_bs_*_w`, TwinSharp `BlockSearch.cs`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SearchCommand {
    /// `mc_cmd_bs_type_w`: 1 file offset, 3 block counter, 4 block number.
    pub kind: u16,
    /// Byte offset in the main program (`mc_command_file_offset_w` / `…pos_start_offset_w`).
    pub(crate) file_offset: i32,
    /// `mc_cmd_bs_intern_block_count_w`.
    pub(crate) block_count: u32,
    /// `mc_cmd_bs_block_number_w`: the N number.
    pub(crate) block_number: u32,
    /// `mc_cmd_bs_distance_prog_start_w`: path distance from the program start where
    /// machining is to continue, 0.1 µm.
    pub(crate) distance_prog_start_tenth_um: f64,
    /// `mc_cmd_bs_covered_distance_w`: share of the found block already covered, 0.1 %
    /// (0..=1000).
    pub(crate) covered_distance_per_mil: f64,
    /// `mc_cmd_bs_auto_return_w`: return to the contour automatically.
    pub(crate) auto_return: bool,
    /// `mc_cmd_bs_deviation_max_w`: largest axis deviation from the continuation position
    /// at the restart, 0.1 µm.
    pub(crate) deviation_max_tenth_um: u32,
    /// `mc_cmd_bs_no_hold_at_restart_w`: resume on the contour without an operator start.
    pub(crate) no_hold_at_restart: bool,
    /// `mc_cmd_bs_breakpoint_position_w`: automatic breakpoint, distance from the program
    /// start, 0.1 µm.
    pub(crate) breakpoint_tenth_um: f64,
}

/// Execution mode bit: block search at the next program start.
pub(crate) const EXECUTION_MODE_BLOCK_SEARCH: i32 = 0x1;

impl SearchCommand {
    /// The decoder's search target this command names, if any.
    pub fn target(&self) -> Option<SearchTarget> {
        match self.kind {
            1 => u64::try_from(self.file_offset)
                .ok()
                .map(SearchTarget::Offset),
            3 => Some(SearchTarget::Counter(u64::from(self.block_count))),
            4 => Some(SearchTarget::BlockNumber(self.block_number)),
            _ => None,
        }
    }
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
}

pub struct Channel {
    number: u32,
    mode: Mode,
    state: State,
    stream: StreamBuffer,
    store: ProgramStore,
    cache: Cache,
    queue: BlockQueue,
    decoder: Decoder,
    motion: Motion,
    /// Command parameter: the program `ACTIVE` starts.
    program: Option<String>,
    /// Block search target for the next start.
    search: Option<SearchTarget>,
    last_error: Option<ErrorRecord>,
    /// The latest `#MSG` text (kept until the next one or a reset).
    message: Option<String>,
    errors: Vec<ErrorRecord>,
    stats: ChannelStats,
    /// Motion stopped for lack of stream data; a `resume` is owed.
    interrupted: bool,
    /// A block has run since the program start (no interrupt before the first).
    ran_any: bool,
    finish: Option<Finish>,
    running_prog: Option<Arc<str>>,
    notes: Vec<MotionNote>,
    /// Reused buffer for the decoder's notes of a tick.
    decoder_notes: Vec<Note>,
    events: EventBuffer,
    /// Refused stream writes in a row, logged as one stretch.
    refusals: refusals::RefusalStretch,
    /// Record executed stream blocks in `executed` (soak checks); off by default.
    observe: bool,
    /// Executed stream blocks since the last [`Channel::drain_executed`].
    executed: Vec<ExecutedBlock>,
    hmi: HmiCommands,
    active: Option<ActiveBlock>,
    /// Single block: the one block motion may take (then a flush that releases it).
    single_gate: BlockQueue,
    /// Single block: a start allows one more block.
    single_credit: bool,
    /// Flushes put into the gate whose notes are not program events.
    single_flushes: usize,
    /// G54…G59 offsets (mm), for positions in the programming coordinate system.
    zero_offsets: ZeroOffsets,
    /// The last started main program's name and text (a shared handle to the decoder's copy),
    /// so the live view lists it after the decoder has read past its end.
    main_text: Option<(Arc<str>, Arc<Vec<u8>>)>,
}

impl Channel {
    /// The one door into a channel: every command and read a client, a feeder, the soak or
    /// the CLI makes is an [`Op`] applied here, in the tick that serves it.
    pub fn apply(&mut self, tick: &Tick, op: Op) -> Reply {
        match op {
            Op::WriteStream(_) if self.state() == State::Error || !self.streaming_enabled() => {
                Reply::StreamNotReady
            }
            Op::WriteStream(data) => Reply::Stream(self.write_stream(tick, &data)),
            Op::CommandMode(v) => Reply::Command(self.command_mode(tick, v)),
            Op::CommandState(v) => Reply::Command(self.command_state(tick, v)),
            Op::SetProgram(name) => {
                self.set_program(&name);
                Reply::Done
            }
            Op::Hold => {
                self.hold(tick);
                Reply::Done
            }
            Op::Resume => {
                self.resume(tick);
                Reply::Done
            }
            Op::Reset => {
                self.reset(tick);
                Reply::Done
            }
            Op::SetOverride(p) => Reply::Command(self.set_override(p)),
            Op::WriteExternal(name, v) => Reply::Value(self.write_external(&name, v).then_some(v)),
            Op::ReadExternal(name) => Reply::Value(self.read_external(&name)),
            Op::Status => {
                let mut s = door::status_of(self);
                s.tick = tick.index;
                s.period = tick.period;
                Reply::Status(Box::new(s))
            }
            Op::Hmi(h) => Reply::Command(match h {
                HmiOp::SingleBlock(on) => {
                    self.set_single_block(on);
                    Ok(())
                }
                HmiOp::OptionalStop(on) => {
                    self.set_optional_stop(on);
                    Ok(())
                }
                HmiOp::SkipLevels(mask) => {
                    self.set_skip_levels(mask);
                    Ok(())
                }
                HmiOp::ExecutionMode(m) => self.set_execution_mode(m),
                HmiOp::Search(s) => {
                    self.set_search_command(s);
                    Ok(())
                }
                HmiOp::ResetCycleTimes => Ok(()),
                HmiOp::FeedHold(on) => self.set_feed_hold(tick, on),
            }),
            Op::ErrorRecord(i) => Reply::ErrorRecord {
                total: self.stats().errors,
                record: door::error_record(self, i),
            },
            Op::Start(name) => Reply::Command(self.start(tick, &name)),
            Op::SearchAt(target) => {
                self.set_search(target);
                Reply::Done
            }
            Op::SkipMask(mask) => {
                self.decoder.set_skip_mask(mask);
                Reply::Done
            }
            Op::ObserveStreamBlocks(on) => {
                self.observe_stream_blocks(on);
                Reply::Done
            }
            Op::DrainExecuted => Reply::Executed(self.drain_executed().collect()),
            Op::Trace(t) => Reply::Trace(match t {
                TraceOp::Plot { max_samples } => {
                    self.motion.enable_trace(max_samples);
                    Ok(())
                }
                TraceOp::Csv { path, every } => self
                    .motion
                    .enable_csv_trace(&path, every)
                    .map_err(|e| format!("{}: {e}", path.display())),
                TraceOp::FinishCsv => self.motion.finish_csv_trace().map_err(|e| e.to_string()),
            }),
            Op::ProgramText(prog) => Reply::ProgramText(self.program_text(&prog)),
        }
    }

    pub fn new(s: ChannelSettings, events_enabled: bool) -> Self {
        let zero_offsets = s.decoder.zero_offsets;
        Channel {
            number: s.number,
            mode: Mode::Automatic,
            state: State::Ready,
            stream: StreamBuffer::new(),
            store: ProgramStore::new(s.search_dirs, s.streaming_prog.as_deref())
                .with_latency(s.fs_latency),
            cache: Cache::new(s.cache),
            queue: BlockQueue::new(s.queue_capacity),
            decoder: {
                let mut d = Decoder::new(s.decoder);
                d.set_tool_radii(s.tools.clone());
                d
            },
            motion: {
                let mut m = Motion::with_planner(s.axes, s.planner);
                m.set_tool_radii(s.tools);
                m
            },
            program: None,
            search: None,
            last_error: None,
            message: None,
            errors: Vec::new(),
            stats: ChannelStats::default(),
            interrupted: false,
            ran_any: false,
            finish: None,
            running_prog: None,
            notes: Vec::new(),
            decoder_notes: Vec::new(),
            events: EventBuffer::new(events_enabled),
            refusals: refusals::RefusalStretch::default(),
            observe: false,
            executed: Vec::new(),
            hmi: HmiCommands::default(),
            active: None,
            single_gate: BlockQueue::new(2),
            single_credit: false,
            single_flushes: 0,
            zero_offsets,
            main_text: None,
        }
    }

    pub fn number(&self) -> u32 {
        self.number
    }
    pub fn mode(&self) -> Mode {
        self.mode
    }
    pub fn state(&self) -> State {
        self.state
    }
    pub fn stats(&self) -> ChannelStats {
        self.stats
    }
    pub fn store_stats(&self) -> StoreStats {
        self.store.stats()
    }
    /// The program files this channel finds by name (its search paths).
    pub(crate) fn store(&self) -> &ProgramStore {
        &self.store
    }
    pub fn cache(&self) -> &Cache {
        &self.cache
    }
    /// Can a streaming program ever run here (and so drain the stream buffer)?
    pub(crate) fn streaming_enabled(&self) -> bool {
        self.store.streaming_enabled()
    }

    pub fn stream(&self) -> &StreamBuffer {
        &self.stream
    }
    pub fn decoder(&self) -> &Decoder {
        &self.decoder
    }
    pub fn motion(&self) -> &Motion {
        &self.motion
    }
    /// The first `MAX_LISTED_ERRORS` errors of the channel's life, oldest first.
    pub fn errors(&self) -> &[ErrorRecord] {
        &self.errors
    }
    /// The latest operator message an NC program sent with `#MSG` (`mc_message_r`).
    pub fn message(&self) -> Option<&str> {
        self.message.as_deref()
    }

    pub fn last_error(&self) -> Option<&ErrorRecord> {
        self.last_error.as_ref()
    }
    /// Blocks the lookahead window holds and may not release yet (the memory effect): what
    /// the axes wait for during an interrupt.
    pub fn held_blocks(&self) -> usize {
        self.motion.held_blocks()
    }

    pub fn position(&self) -> Position {
        self.motion.position()
    }
    /// Block counter of the running program (ISG: every decoded line).
    pub fn block_counter(&self) -> u64 {
        self.decoder.counter()
    }
    /// Stream fill level: (used, free) bytes.
    pub fn stream_fill(&self) -> (usize, usize) {
        (self.stream.used(), self.stream.free())
    }
    /// How the last program run finished, taken once.
    pub fn take_finish(&mut self) -> Option<Finish> {
        self.finish.take()
    }
    pub fn events_mut(&mut self) -> &mut EventBuffer {
        &mut self.events
    }
    /// The log ends: a stretch of refused writes still open is closed with its count.
    pub(crate) fn close_event_stretches(&mut self) {
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
    /// Record every executed stream block for [`Channel::drain_executed`]. Whoever turns this
    /// on drains every tick: the record grows by the blocks of one tick only.
    fn observe_stream_blocks(&mut self, on: bool) {
        self.observe = on;
        if !on {
            self.executed.clear();
        }
    }
    /// The stream blocks executed since the last call, in execution order.
    fn drain_executed(&mut self) -> std::vec::Drain<'_, ExecutedBlock> {
        self.executed.drain(..)
    }
    /// The position of each configured axis, in `AXIS_LETTERS` order.
    pub fn axis_positions(&self) -> Vec<(char, f64)> {
        self.positions_less(&[0.0; MAX_AXES])
    }

    /// The position of each configured axis under its configured name (`X`, `X1`), in
    /// `AXIS_LETTERS` order. [`Channel::axis_positions`] names each by its slot's letter.
    pub fn named_positions(&self) -> Vec<(crate::lang::block::AxisName, f64)> {
        let p = self.motion.position();
        let configured = self.decoder.axes();
        let names = self.decoder.axis_names();
        (0..MAX_AXES)
            .filter(|&i| configured[i])
            .map(|i| (names[i], p[i]))
            .collect()
    }

    /// The configured axes' positions minus `offset`, in `AXIS_LETTERS` order.
    fn positions_less(&self, offset: &Position) -> Vec<(char, f64)> {
        let p = self.motion.position();
        let configured = self.decoder.axes();
        AXIS_LETTERS
            .iter()
            .enumerate()
            .filter(|(i, _)| configured[*i])
            .map(|(i, l)| (*l as char, p[i] - offset[i]))
            .collect()
    }

    /// Positions in the programming coordinate system: machine positions minus the zero
    /// offset (G54…G59) the decoder has active, which runs ahead of execution by the
    /// lookahead when a program switches offsets.
    pub(crate) fn pcs_positions(&self) -> Vec<(char, f64)> {
        let offset = self
            .decoder
            .modal()
            .zero_offset
            .checked_sub(1)
            .and_then(|i| self.zero_offsets.get(i))
            .copied()
            .unwrap_or([0.0; MAX_AXES]);
        self.positions_less(&offset)
    }

    fn set_state(&mut self, tick: &Tick, state: State) {
        if !matches!(state, State::Active | State::Hold) {
            // No program runs: nothing is held.
            self.hmi.feed_hold = false;
        }
        if self.state != state {
            self.state = state;
            self.push_state(tick);
        }
    }

    /// One event of this channel into the tick's buffer (nothing when the log is off).
    #[inline]
    fn emit(&mut self, tick: &Tick, kind: EventKind) {
        self.events.push(tick, self.number, kind);
    }

    fn push_state(&mut self, tick: &Tick) {
        let (mode, state) = (self.mode, self.state);
        self.emit(tick, EventKind::State { mode, state });
    }

    fn raise_error(
        &mut self,
        tick: &Tick,
        code: u32,
        msg: String,
        prog: Option<String>,
        line: Option<u64>,
    ) {
        let msg = self.decoder.reported_message(code, msg);
        let record = ErrorRecord {
            code,
            msg,
            prog,
            line,
        };
        self.emit(
            tick,
            EventKind::Error {
                code,
                msg: record.msg.clone(),
                prog: record.prog.clone(),
                line,
            },
        );
        self.stats.errors += 1;
        // The report lists the first errors of a run; a soak raising the same expected
        // error for days must not grow memory, so the list is bounded and the rest counted.
        if self.errors.len() < MAX_LISTED_ERRORS {
            self.errors.push(record.clone());
        }
        self.last_error = Some(record);
        // An error stops decoding and motion; only a reset leaves ERROR.
        self.motion.reset();
        self.queue.clear();
        self.single_gate.clear();
        self.single_flushes = 0;
        if self.finish.is_none() && self.running_prog.is_some() {
            self.finish = Some(Finish::Error);
        }
        self.running_prog = None;
        self.set_state(tick, State::Error);
    }

    fn warn(&mut self, tick: &Tick, code: u32, msg: String) {
        self.stats.warnings += 1;
        self.emit(tick, EventKind::Warning { code, msg });
    }

    /// A client writes NC lines into the stream interface (`mc_program_stream_w`).
    fn write_stream(&mut self, tick: &Tick, packet: &[u8]) -> Result<(), StreamWriteError> {
        let r = self.stream.write(packet);
        let code = r.as_ref().err().and_then(|e| e.isg_code());
        if matches!(r, Err(StreamWriteError::Full { .. })) {
            if !self.refusals.refused(tick, code) {
                // A retry within a stretch: counted, logged when the stretch closes.
                self.stats.warnings += 1;
                return r;
            }
        } else {
            self.close_refusals(tick);
        }
        self.emit(
            tick,
            EventKind::Write {
                bytes: packet.len() as u64,
                ok: r.is_ok(),
                code,
            },
        );
        match &r {
            Err(StreamWriteError::Full { .. }) => {
                self.warn(
                    tick,
                    WARN_WRITE_REJECTED,
                    "Error writing the object (stream buffer full)".into(),
                );
            }
            Err(StreamWriteError::NoLineEnd { offset }) => {
                // The kernel's text once, then where: the writer's error carries the number
                // and the text again (for a writer that reports it on its own).
                let msg = format!(
                    "Streaming data does not contain a correct line end marker (packet byte {offset})"
                );
                if self.decoder.state() == DecoderState::Running && self.decoder.reads_stream() {
                    self.decoder.abort(ERR_NO_LINE_END, msg.clone());
                    self.drain_decoder_notes(tick);
                } else if self.running_prog.is_some() && !self.decoder.reads_stream() {
                    // A file program runs and never reads the stream: the refused write is the
                    // writer's problem, not the program's (docs/exactly-once.md).
                    self.warn(tick, ERR_NO_LINE_END, msg);
                } else {
                    self.raise_error(tick, ERR_NO_LINE_END, msg, None, None);
                }
            }
            _ => {}
        }
        r
    }

    /// Command to mode (0x104).
    fn command_mode(&mut self, tick: &Tick, v: i32) -> Result<(), CommandError> {
        let mode = Mode::from_i32(v).ok_or(CommandError::InvalidValue(v))?;
        if matches!(self.state, State::Active | State::Hold) {
            return Err(self.busy());
        }
        if self.mode != mode {
            self.mode = mode;
            self.push_state(tick);
        }
        Ok(())
    }

    fn busy(&self) -> CommandError {
        CommandError::Busy {
            mode: self.mode,
            state: self.state,
        }
    }

    /// Command parameter (0x108): the program to start.
    fn set_program(&mut self, name: &str) {
        let name = name.trim_matches(char::from(0)).trim();
        self.program = (!name.is_empty()).then(|| name.to_string());
    }

    pub fn program(&self) -> Option<&str> {
        self.program.as_deref()
    }

    /// Block search target for the next start (`--search`).
    fn set_search(&mut self, target: Option<SearchTarget>) {
        self.search = target;
    }

    /// Command to state (0x105): ACTIVE starts (or resumes), HOLD holds, READY resets.
    fn command_state(&mut self, tick: &Tick, v: i32) -> Result<(), CommandError> {
        let state = State::from_i32(v).ok_or(CommandError::InvalidValue(v))?;
        match state {
            State::Active => match self.state {
                State::Hold => {
                    self.resume(tick);
                    Ok(())
                }
                State::Ready | State::Selected if self.mode == Mode::Automatic => {
                    let name = self.program.clone().ok_or(CommandError::NoProgram)?;
                    self.start(tick, &name)
                }
                State::Active => Ok(()),
                _ => Err(self.busy()),
            },
            State::Hold => {
                self.hold(tick);
                Ok(())
            }
            State::Ready => {
                self.reset(tick);
                Ok(())
            }
            _ => Err(self.busy()),
        }
    }

    /// Start a main program in automatic mode.
    fn start(&mut self, tick: &Tick, name: &str) -> Result<(), CommandError> {
        if !matches!(self.state, State::Ready | State::Selected) {
            return Err(self.busy());
        }
        self.mode = Mode::Automatic;
        self.program = Some(name.to_string());
        self.finish = None;
        self.ran_any = false;
        self.interrupted = false;
        self.motion.start();
        let pos = self.motion.position();
        let search = self.search.take().or_else(|| self.take_commanded_search());
        self.active = None;
        self.single_credit = true;
        self.single_flushes = 0;
        self.single_gate.clear();
        if let Err(e) = self.decoder.start(name, &mut self.store, pos, search) {
            self.running_prog = Some(name.into());
            self.raise_error(tick, e.code, e.msg.clone(), Some(name.to_string()), None);
            return Err(CommandError::StartFailed {
                code: e.code,
                msg: e.msg,
            });
        }
        self.running_prog = Some(name.into());
        let kept = self
            .decoder
            .program_text(name)
            .map(|t| (Arc::from(name), t));
        // The last program's text may be the only hold on hundreds of MB: the loader thread
        // frees it, not this tick (the decoder's frames release theirs the same way).
        if let Some((_, old)) = std::mem::replace(&mut self.main_text, kept) {
            crate::source::loader::release(old);
        }
        self.set_state(tick, State::Active);
        self.drain_decoder_notes(tick);
        Ok(())
    }

    /// Feed hold (0x136).
    fn hold(&mut self, tick: &Tick) {
        if self.state == State::Active {
            self.motion.set_hold(true);
            self.set_state(tick, State::Hold);
        }
    }

    /// `mc_feedhold_channel_w`: TRUE holds a running program (refused when none runs: nothing
    /// to hold); FALSE releases the feed hold and resumes, and only it: a channel held by a
    /// programmed stop or a single block stays held. Repeating a value changes nothing.
    fn set_feed_hold(&mut self, tick: &Tick, on: bool) -> Result<(), CommandError> {
        match (on, self.hmi.feed_hold) {
            (true, true) | (false, false) => Ok(()),
            (true, false) if self.state == State::Active => {
                self.hmi.feed_hold = true;
                self.hold(tick);
                Ok(())
            }
            (true, false) => Err(self.busy()),
            (false, true) => {
                self.resume(tick);
                Ok(())
            }
        }
    }

    /// Resume after hold (0x137).
    fn resume(&mut self, tick: &Tick) {
        self.hmi.feed_hold = false;
        if self.state == State::Hold {
            self.single_credit = true;
            self.motion.set_hold(false);
            self.set_state(tick, State::Active);
        }
    }

    /// Feed override, percent 0..=200.
    fn set_override(&mut self, pct: f64) -> Result<(), CommandError> {
        if !(0.0..=200.0).contains(&pct) {
            return Err(CommandError::BadOverride(pct));
        }
        self.motion.set_override(pct);
        Ok(())
    }

    /// V.E. variable written from outside.
    fn write_external(&mut self, name: &str, v: f64) -> bool {
        self.decoder.vars_mut().set_external(name, v).is_ok()
    }

    fn read_external(&self, name: &str) -> Option<f64> {
        self.decoder.vars().get_external(name)
    }

    /// HMI commands as last written (the `mc_command_*_r` objects read them back).
    pub(crate) fn hmi(&self) -> HmiCommands {
        self.hmi
    }
    /// The block that took effect last since the program start.
    pub(crate) fn active_block(&self) -> Option<&ActiveBlock> {
        self.active.as_ref()
    }
    /// The text of file program `prog`: an open decoder frame's, or the last main program's.
    fn program_text(&self, prog: &str) -> Option<Arc<Vec<u8>>> {
        self.decoder.program_text(prog).or_else(|| {
            let (name, text) = self.main_text.as_ref()?;
            (**name == *prog).then(|| Arc::clone(text))
        })
    }
    /// The main program running (ACTIVE or HOLD), if any.
    pub(crate) fn running_program(&self) -> Option<&str> {
        self.running_prog.as_deref()
    }
    /// The zero-offset table G54…G59 (`V.G.NP[i].V`).
    pub(crate) fn zero_offsets(&self) -> &ZeroOffsets {
        &self.zero_offsets
    }
    /// Blocks decoded and waiting for the lookahead window (`mc_slope_buf_level`).
    pub(crate) fn queued_blocks(&self) -> usize {
        self.queue.len()
    }
    /// Blocks handed to the interpolator and not yet done (`mc_ipo_buf_level`).
    pub(crate) fn ipo_blocks(&self) -> usize {
        self.motion.released_blocks() + self.motion.held_blocks() + self.single_gate.len()
    }
    /// `mc_command_M01_stop_enable_w`: M01 holds the channel while on.
    fn set_optional_stop(&mut self, on: bool) {
        self.hmi.optional_stop = on;
        self.motion.set_optional_stop(on);
    }

    /// `mc_command_single_block_w`: stop after each block until the next start.
    fn set_single_block(&mut self, on: bool) {
        self.hmi.single_block = on;
    }
    /// `mc_command_block_ignore_w`: skip levels 1–10 as a mask (level n = bit n−1); the
    /// decoder skips `/n` blocks of a set level from the next line it reads.
    fn set_skip_levels(&mut self, mask: u32) {
        let mask = mask & 0x3FF;
        self.hmi.skip_levels = mask;
        self.decoder.set_skip_mask((mask << 1) as u16);
    }
    /// `mc_command_execution_mode_w`: 0 standard, 1 block search at the next start; other
    /// modes (contour visualisation, syntax check, machine lock …) are not modelled.
    fn set_execution_mode(&mut self, mode: i32) -> Result<(), CommandError> {
        if mode & !EXECUTION_MODE_BLOCK_SEARCH != 0 {
            return Err(CommandError::InvalidValue(mode));
        }
        self.hmi.execution_mode = mode;
        Ok(())
    }
    /// Block-search parameters for the next start in block-search execution mode.
    fn set_search_command(&mut self, search: SearchCommand) {
        self.hmi.search = search;
    }

    /// The commanded block search, taken once by a start in block-search execution mode.
    fn take_commanded_search(&mut self) -> Option<SearchTarget> {
        if self.hmi.execution_mode & EXECUTION_MODE_BLOCK_SEARCH == 0 {
            return None;
        }
        self.hmi.execution_mode &= !EXECUTION_MODE_BLOCK_SEARCH;
        self.hmi.search.target()
    }

    /// Remember the block that took effect. The program name is shared (`Arc`) and only
    /// replaced when it changes: this runs for every block, at tens per tick.
    fn note_active(&mut self, info: &crate::queue::BlockInfo) {
        match &mut self.active {
            Some(a) if Arc::ptr_eq(&a.prog, &info.prog) => {
                a.offset = info.offset;
                a.counter = info.counter;
                a.n = info.n;
            }
            _ => {
                self.active = Some(ActiveBlock {
                    prog: info.prog.clone(),
                    offset: info.offset,
                    counter: info.counter,
                    n: info.n,
                })
            }
        }
    }

    /// Single block: let the next decoded block (with its silent second parts) into motion,
    /// once per start, followed by a flush so the planner releases it at once instead of
    /// holding it for its lookahead window.
    fn feed_single_block(&mut self) {
        if !self.single_credit || !self.motion.idle() || !self.single_gate.is_empty() {
            return;
        }
        let Some(first) = self.queue.pop_front() else {
            return;
        };
        let mut last = first.clone();
        self.single_gate.push(first);
        while self.queue.front().is_some_and(|b| b.silent) {
            if let Some(b) = self.queue.pop_front() {
                last = b.clone();
                self.single_gate.push(b);
            }
        }
        if !matches!(last.action, Action::Flush(_) | Action::End { .. }) {
            self.single_gate.push(QueuedBlock {
                info: last.info,
                action: Action::Flush(crate::vocab::flush::FlushKind::Stop),
                silent: true,
            });
            self.single_flushes += 1;
        }
        self.single_credit = false;
    }

    /// NC reset (0x13C): stream buffer emptied and streaming left, program stack, queue,
    /// cache and errors cleared, motion stopped at once; READY.
    fn reset(&mut self, tick: &Tick) {
        let dropped = self.stream.clear();
        if dropped > 0 {
            self.emit(
                tick,
                EventKind::Discard {
                    bytes: dropped as u64,
                },
            );
        }
        if let Some(prog) = self.running_prog.take() {
            self.emit(
                tick,
                EventKind::ProgramEnd {
                    prog: prog.to_string(),
                    end: ProgramEndKind::Reset,
                },
            );
        }
        self.motion.reset();
        self.queue.clear();
        self.single_gate.clear();
        self.single_flushes = 0;
        self.active = None;
        self.decoder.reset(self.motion.position());
        self.cache.reset();
        // A read still pending is abandoned with the program.
        self.store.take_owed();
        self.last_error = None;
        self.message = None;
        self.interrupted = false;
        self.search = None;
        self.set_state(tick, State::Ready);
    }

    fn drain_decoder_notes(&mut self, tick: &Tick) {
        let mut notes = std::mem::take(&mut self.decoder_notes);
        self.decoder.take_notes(&mut notes);
        for n in notes.drain(..) {
            match n {
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
                    self.raise_error(tick, code, msg, Some(prog.to_string()), Some(line as u64));
                }
                Note::Search { target, found } => self.emit(
                    tick,
                    EventKind::Search {
                        target: target.to_string(),
                        found,
                    },
                ),
                Note::Message { text, save } => {
                    self.emit(
                        tick,
                        EventKind::Message {
                            text: text.clone(),
                            save,
                        },
                    );
                    self.message = Some(text);
                }
                Note::HFunction { h, value } => self.emit(tick, EventKind::HFunction { h, value }),
                Note::MFunction { m, value } => self.emit(
                    tick,
                    EventKind::MFunction {
                        m,
                        value: Some(value),
                    },
                ),
                Note::Cache { op, file } => self.emit(
                    tick,
                    EventKind::Cache {
                        op,
                        file: (!file.is_empty()).then_some(file),
                    },
                ),
            }
        }
        self.decoder_notes = notes;
    }

    /// What the motion reported this tick, in order: block events and the active block,
    /// flushes, programmed stops (HOLD), a planning error (ERROR, the rest dropped), the
    /// program end (READY).
    fn apply_motion_notes(&mut self, tick: &Tick, notes: &mut Vec<MotionNote>) {
        for n in notes.drain(..) {
            match n {
                MotionNote::Started(info) => {
                    if self.interrupted {
                        self.interrupted = false;
                        self.emit(tick, EventKind::Resume);
                    }
                    self.ran_any = true;
                    self.stats.blocks += 1;
                    self.note_active(&info);
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
                MotionNote::Flush(crate::vocab::flush::FlushKind::Stop)
                    if self.single_flushes > 0 =>
                {
                    // The flush feed_single_block added: no program event.
                    self.single_flushes -= 1;
                }
                MotionNote::Flush(kind) => self.emit(tick, EventKind::Flush { kind }),
                MotionNote::ProgramStop { optional } => {
                    let m = u32::from(optional);
                    self.emit(tick, EventKind::ProgramStop { m });
                    if self.state == State::Active {
                        self.set_state(tick, State::Hold);
                    }
                }
                MotionNote::Error { code, msg, block } => {
                    let (prog, line) = block.unzip();
                    self.raise_error(tick, code, msg, prog, line);
                    break;
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
                    self.running_prog = None;
                    self.finish = Some(Finish::Ended);
                    self.interrupted = false;
                    self.set_state(tick, State::Ready);
                }
            }
        }
    }

    /// One cycle: decode, execute, report. Returns the wall time the tick waited for the
    /// program loader with the clock stopped (virtual time; zero in real time), which the
    /// cycle reports apart from the tick's work.
    pub fn step(&mut self, tick: &Tick) -> std::time::Duration {
        self.store.begin_tick(tick.clock);
        self.run_tick(tick);
        self.store.take_clock_stopped()
    }

    fn run_tick(&mut self, tick: &Tick) {
        self.refusals.seen(tick);
        if !matches!(self.state, State::Active | State::Hold) {
            return;
        }
        let mut io = DecoderIo {
            stream: &mut self.stream,
            store: &mut self.store,
            cache: &mut self.cache,
            queue: &mut self.queue,
            motion_idle: self.motion.idle(),
            want_text: self.events.enabled(),
            now: tick.time,
            period: tick.period,
        };
        self.decoder.step(&mut io);
        self.drain_decoder_notes(tick);
        if self.state == State::Error {
            return;
        }
        let dt = tick.period.as_secs_f64();
        let mut notes = std::mem::take(&mut self.notes);
        if self.hmi.single_block || !self.single_gate.is_empty() {
            if self.hmi.single_block {
                self.feed_single_block();
            }
            self.motion.step(dt, &mut self.single_gate, &mut notes);
        } else {
            self.motion.step(dt, &mut self.queue, &mut notes);
        }
        self.apply_motion_notes(tick, &mut notes);
        self.notes = notes;
        if self.hmi.single_block
            && self.state == State::Active
            && !self.single_credit
            && self.motion.idle()
            && self.single_gate.is_empty()
        {
            // Single block: the block is done; wait for the next start.
            self.motion.set_hold(true);
            self.set_state(tick, State::Hold);
        }
        if self.state == State::Active
            && (self.ran_any || self.motion.held_blocks() > 0)
            && !self.interrupted
            && self.motion.waiting_for_data()
            && self.queue.is_empty()
            && self.decoder.starved()
        {
            self.interrupted = true;
            self.stats.interrupts += 1;
            self.motion.note_interrupt();
            let held = self.motion.held_blocks() as u64;
            self.emit(tick, EventKind::Interrupt { held });
        }
    }
}
