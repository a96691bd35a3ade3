//! One NC channel: the ISG mode and state machine, the HMI's commands, the program run and
//! the channel's log (each a part in its own file), around what it owns — stream interface,
//! program store, file cache, decoder, block queue and motion.
//!
//! Everything a client does to a channel (stream writes, commands) and everything the tick
//! does happens through this type, in the runtime's one thread; errors and warnings carry
//! their ISG numbers and become events. A client reads a channel through [`Channel::status`]
//! (live) and [`Channel::report`] (after a run).

use thiserror::Error;

use crate::decoder::{Decoder, DecoderIo, DecoderSettings, DecoderState, Note};
use crate::motion::{Motion, MotionNote, PlannerSettings};
use crate::queue::BlockQueue;
use crate::report::event::{EventBuffer, EventKind, ProgramEndKind};
use crate::runtime::Tick;
use crate::source::cache::{Cache, CacheLimits};
use crate::source::loader::Loader;
use crate::source::store::{FsLatency, ProgramStore, SearchDir};
use crate::source::stream::StreamBuffer;
use crate::vocab::axis::{Position, AXIS_LETTERS, MAX_AXES};

pub use crate::source::stream::{ERR_NO_LINE_END, WARN_WRITE_REJECTED};

pub mod door;
mod hmi;
mod isg;
pub mod live;
mod log;
mod program;
mod refusals;
pub mod techno;

pub use crate::decoder::modal::Modal;
pub use crate::decoder::vars::VarClass;
pub use crate::decoder::DecoderStats;
/// The words of the door and the settings that callers outside the channel name.
pub use crate::decoder::SearchTarget;
pub use crate::motion::trace::Trace;
pub use crate::motion::AxisLimits;
pub use crate::source::store::StoreStats;
pub use crate::source::stream::StreamCounters;
pub use crate::source::stream::StreamWriteError;
pub use crate::vocab::mode::{Mode, State};
pub use door::{CacheStats, ChannelReport, ExternalValue, Status};
pub(crate) use hmi::HmiCommands;
pub use hmi::SearchCommand;
pub use log::{ChannelStats, ErrorRecord, ExecutedBlock, MAX_LISTED_ERRORS};
pub(crate) use program::ActiveBlock;
pub use program::Finish;

use door::{HmiOp, Op, Reply, TraceOp};
use hmi::Hmi;
use isg::{Isg, StateCommand};
use log::{AfterMotionNote, ChannelLog};
use program::ProgramRun;
use techno::TechnoUnits;

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
    /// The tool list's data sets by D number, mm (`werkz_data[i]` or `tools.lis`).
    pub tools: crate::decoder::ToolTable,
    /// `einrechnen_mit_t` (P-CHAN-00014): a T word also selects the D data set of its number.
    pub t_selects_d: bool,
    /// The names of the tool and zero-offset lists, for ADS.
    pub list_files: door::ListFiles,
}

/// One NC channel: its parts (mode and state, HMI commands, program run, log) and what it
/// owns. Read through [`Channel::status`] and [`Channel::report`].
pub struct Channel {
    /// Mode and state (HLI numbers).
    isg: Isg,
    /// The operator's commands and the single-block gate.
    hmi: Hmi,
    /// The running main program, its active block and how it finished.
    run: ProgramRun,
    /// Events, counters, errors, `#MSG`.
    log: ChannelLog,
    stream: StreamBuffer,
    store: ProgramStore,
    cache: Cache,
    queue: BlockQueue,
    decoder: Decoder,
    /// Frees the kept main program text off the tick (the store and the decoder hold their
    /// own handles to the same loader thread).
    loader: Loader,
    motion: Motion,
    /// The HLI technology units: M/H/S/T functions handed to the PLC and acknowledged.
    techno: TechnoUnits,
    /// The names of the tool and zero-offset lists.
    list_files: door::ListFiles,
    /// Reused buffer for the motion's notes of a tick.
    notes: Vec<MotionNote>,
    /// Reused buffer for the decoder's notes of a tick.
    decoder_notes: Vec<Note>,
}

impl Channel {
    /// [`Op::WriteStream`] of a packet the writer keeps: a built-in client offers the same
    /// packet again after a refusal, and lends it rather than give a reference away.
    pub fn write_packet(&mut self, tick: &Tick, packet: &std::sync::Arc<[u8]>) -> Reply {
        // ERROR: nothing drains the buffer before a reset; no streaming program: nothing
        // ever will.
        if self.isg.state() == State::Error || !self.store.streaming_enabled() {
            return Reply::StreamNotReady;
        }
        Reply::Stream(self.write_stream(tick, packet))
    }

    /// The one door into a channel: every command and read a client, a feeder, the soak or
    /// the CLI makes is an [`Op`] applied here, in the tick that serves it.
    pub fn apply(&mut self, tick: &Tick, op: Op) -> Reply {
        match op {
            Op::WriteStream(data) => self.write_packet(tick, &data),
            Op::CommandMode(v) => Reply::Command(self.isg.command_mode(tick, v, &mut self.log)),
            Op::CommandState(v) => Reply::Command(self.command_state(tick, v)),
            Op::SetProgram(name) => {
                self.hmi.set_program(&name);
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
            Op::WriteExternalStr(name, text) => Reply::Value(self.write_external_str(&name, &text)),
            Op::ReadExternalTyped(name) => {
                Reply::External(self.decoder.vars().external_value(&name))
            }
            // Served by the machine (`machine::watch`, `machine::live`), never by a channel.
            Op::Watch(_) | Op::DrainLive => Reply::NoChannel,
            Op::Status => {
                let mut s = self.status();
                s.tick = tick.index;
                s.period = tick.period;
                Reply::Status(Box::new(s))
            }
            Op::Hmi(h) => Reply::Command(match h {
                HmiOp::SingleBlock(on) => {
                    self.hmi.set_single_block(on);
                    Ok(())
                }
                HmiOp::OptionalStop(on) => {
                    self.hmi.set_optional_stop(on, &mut self.motion);
                    Ok(())
                }
                HmiOp::SkipLevels(mask) => {
                    self.hmi.set_skip_levels(mask, &mut self.decoder);
                    Ok(())
                }
                HmiOp::ExecutionMode(m) => self.hmi.set_execution_mode(m),
                HmiOp::Search(s) => {
                    self.hmi.set_search_command(s);
                    Ok(())
                }
                HmiOp::ResetCycleTimes => Ok(()),
                HmiOp::FeedHold(on) => self.set_feed_hold(tick, on),
            }),
            Op::ErrorRecord(i) => Reply::ErrorRecord {
                total: self.log.stats().errors,
                record: door::error_record(self, i),
            },
            Op::Start(name) => Reply::Command(self.start(tick, &name)),
            Op::SearchAt(target) => {
                self.hmi.set_search(target);
                Reply::Done
            }
            Op::SkipMask(mask) => {
                self.decoder.set_skip_mask(mask);
                Reply::Done
            }
            Op::ObserveStreamBlocks(on) => {
                self.log.observe_stream_blocks(on);
                Reply::Done
            }
            Op::DrainExecuted => Reply::Executed(self.log.drain_executed().collect()),
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
            Op::Techno(w) => Reply::Techno(self.techno.write(w)),
            Op::ObserveTechno(on) => {
                self.techno.observe(on);
                Reply::Done
            }
            Op::DrainTechno => {
                let (seen, lost) = self.techno.drain_seen();
                Reply::TechnoSeen { seen, lost }
            }
        }
    }

    /// A channel built from its settings; `loader` (started by whoever runs the channels)
    /// reads its large program files and frees its large texts and tables off the tick.
    pub fn new(s: ChannelSettings, events_enabled: bool, loader: Loader) -> Self {
        Channel {
            isg: Isg::new(),
            hmi: Hmi::new(),
            run: ProgramRun::default(),
            log: ChannelLog::new(s.number, events_enabled),
            stream: StreamBuffer::new(),
            store: ProgramStore::new(s.search_dirs, s.streaming_prog.as_deref())
                .with_latency(s.fs_latency)
                .with_loader(loader.clone()),
            cache: Cache::new(s.cache),
            queue: BlockQueue::new(s.queue_capacity),
            decoder: {
                let mut d = Decoder::new(s.decoder, loader.clone());
                d.set_tools(s.tools.clone(), s.t_selects_d);
                d
            },
            motion: {
                let mut m = Motion::with_planner(s.axes, s.planner);
                m.set_tool_radii(s.tools.iter().map(|t| (t.d, t.radius_mm)).collect());
                m
            },
            techno: TechnoUnits::new(),
            list_files: s.list_files,
            loader,
            notes: Vec::new(),
            decoder_notes: Vec::new(),
        }
    }

    /// The technology units, read-only: what a PLC played inside the machine polls
    /// (`machine::plc`); it writes only through [`Channel::apply`].
    pub(crate) fn techno(&self) -> &TechnoUnits {
        &self.techno
    }

    /// The live snapshot a client reads (what `Op::Status` answers, without the tick's
    /// index and period).
    pub fn status(&self) -> Status {
        door::status_of(self)
    }

    /// Everything a channel tells after a run: counters, errors, position, trace.
    pub fn report(&self) -> ChannelReport {
        door::report_of(self)
    }

    /// The ISG state; for the machine's run loop (`src/machine/mod.rs`) and the soak's driver,
    /// which read it every tick, where a `status()` would allocate.
    pub(crate) fn state(&self) -> State {
        self.isg.state()
    }
    /// Whether [`Op::DrainExecuted`] and [`Op::DrainTechno`] would hand anything over; the
    /// soak's per-tick checks (`src/soak/driver.rs`) skip a drain of nothing, two requests in
    /// most ticks.
    pub(crate) fn drains_pending(&self) -> (bool, bool) {
        (self.log.executed_pending(), self.techno.seen_pending())
    }
    /// The first `MAX_LISTED_ERRORS` errors of the channel's life, oldest first; for the
    /// soak's per-tick check of new errors (`src/soak/driver.rs`), where `report()` would copy
    /// the list every tick.
    pub(crate) fn errors(&self) -> &[ErrorRecord] {
        self.log.errors()
    }
    /// The machine position; for the soak's per-tick soft-limit check (`src/soak/driver.rs`),
    /// where `status()` would allocate.
    pub(crate) fn position(&self) -> Position {
        self.motion.position()
    }
    /// Whether the executing motion block is a rapid (G0); for the live view's path record
    /// (`machine::live`), read every tick where `status()` would allocate.
    pub(crate) fn executing_rapid(&self) -> bool {
        self.motion
            .executing_move()
            .is_some_and(|m| m.kind == crate::queue::MoveKind::Rapid)
    }
    /// Bytes the stream interface holds and bytes taken from it so far; for the live view's
    /// stream record (`machine::live`).
    pub(crate) fn stream_fill(&self) -> (usize, u64) {
        (self.stream.used(), self.stream.counters().bytes_taken)
    }
    /// Bytes the stream interface accepted since the channel was built.
    pub(crate) fn stream_written(&self) -> u64 {
        self.stream.counters().bytes_written
    }
    /// The block that took effect last since the program start.
    pub(crate) fn active_block(&self) -> Option<&ActiveBlock> {
        self.run.active_block()
    }
    /// The configured axes' limits (software limits, rates).
    pub(crate) fn axis_limits(&self) -> &[crate::motion::AxisLimits] {
        self.motion.axes()
    }
    /// How the last program run finished, taken once.
    pub fn take_finish(&mut self) -> Option<Finish> {
        self.run.take_finish()
    }
    /// The tick's events, for the machine to flush into the event log.
    pub fn events_mut(&mut self) -> &mut EventBuffer {
        self.log.events_mut()
    }
    /// The log ends: a stretch of refused writes still open is closed with its count.
    pub(crate) fn close_event_stretches(&mut self) {
        self.log.close_stretches();
    }

    /// Does channel program `name` exist: the streaming program, or a main program in the
    /// search paths? `Err` lists the folders searched (`run`'s usage error).
    pub(crate) fn find_program(&self, name: &str) -> Result<(), Vec<String>> {
        use crate::source::store::ProgramKind;
        let store = &self.store;
        if store.is_streaming_program(name) || store.find(name, ProgramKind::Main).is_ok() {
            return Ok(());
        }
        Err(store
            .search_dirs()
            .iter()
            .map(|d| d.dir.display().to_string())
            .collect())
    }

    /// The position of each configured axis, in `AXIS_LETTERS` order.
    fn axis_positions(&self) -> Vec<(char, f64)> {
        self.positions_less(&[0.0; MAX_AXES])
    }

    /// The position of each configured axis under its configured name (`X`, `X1`), in
    /// `AXIS_LETTERS` order. [`Channel::axis_positions`] names each by its slot's letter.
    fn named_positions(&self) -> Vec<(crate::lang::block::AxisName, f64)> {
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
    fn pcs_positions(&self) -> Vec<(char, f64)> {
        let offset = self
            .decoder
            .modal()
            .zero_offset
            .checked_sub(1)
            .and_then(|i| self.decoder.zero_offsets().get(i))
            .copied()
            .unwrap_or([0.0; MAX_AXES]);
        self.positions_less(&offset)
    }

    /// Blocks handed to the interpolator and not yet done (`mc_ipo_buf_level`).
    fn ipo_blocks(&self) -> usize {
        self.motion.released_blocks() + self.motion.held_blocks() + self.hmi.gate_blocks()
    }

    /// The text of file program `prog`: an open decoder frame's, or the last main program's.
    fn program_text(&self, prog: &str) -> Option<std::sync::Arc<Vec<u8>>> {
        self.decoder
            .program_text(prog)
            .or_else(|| self.run.main_text(prog))
    }

    /// Enter `state` (the state machine's rules, its event).
    fn set_state(&mut self, tick: &Tick, state: State) {
        self.isg
            .set_state(tick, state, &mut self.hmi, &mut self.log);
    }

    /// Raise an error: logged with the kernel's text for its number; decoding and motion
    /// stop, the run finishes with it, ERROR.
    fn fail(&mut self, tick: &Tick, mut error: ErrorRecord) {
        error.msg = self
            .decoder
            .reported_message(error.code, std::mem::take(&mut error.msg));
        self.log.record_error(tick, error);
        // An error stops decoding and motion; only a reset leaves ERROR.
        self.motion.reset();
        self.techno.reset();
        self.queue.clear();
        self.hmi.close_gate();
        self.run.failed();
        self.set_state(tick, State::Error);
    }

    /// A client writes NC lines into the stream interface (`mc_program_stream_w`).
    fn write_stream(
        &mut self,
        tick: &Tick,
        packet: &std::sync::Arc<[u8]>,
    ) -> Result<(), StreamWriteError> {
        let r = self.stream.write_shared(packet);
        if !self.log.write(tick, packet.len(), &r) {
            return r;
        }
        if let Err(StreamWriteError::NoLineEnd { offset }) = &r {
            // The kernel's text once, then where: the writer's error carries the number
            // and the text again (for a writer that reports it on its own).
            let msg = format!(
                "Streaming data does not contain a correct line end marker (packet byte {offset})"
            );
            if self.decoder.state() == DecoderState::Running && self.decoder.reads_stream() {
                self.decoder.abort(ERR_NO_LINE_END, msg.clone());
                self.drain_decoder_notes(tick);
            } else if self.run.running().is_some() && !self.decoder.reads_stream() {
                // A file program runs and never reads the stream: the refused write is the
                // writer's problem, not the program's (docs/exactly-once.md).
                self.log.warn(tick, ERR_NO_LINE_END, msg);
            } else {
                self.fail(
                    tick,
                    ErrorRecord {
                        code: ERR_NO_LINE_END,
                        msg,
                        prog: None,
                        line: None,
                    },
                );
            }
        }
        r
    }

    /// Command to state (0x105): ACTIVE starts (or resumes), HOLD holds, READY resets.
    fn command_state(&mut self, tick: &Tick, v: i32) -> Result<(), CommandError> {
        match self.isg.command_state(v)? {
            StateCommand::Resume => self.resume(tick),
            StateCommand::Start => {
                let name = self
                    .hmi
                    .program()
                    .ok_or(CommandError::NoProgram)?
                    .to_string();
                return self.start(tick, &name);
            }
            StateCommand::Nothing => {}
            StateCommand::Hold => self.hold(tick),
            StateCommand::Reset => self.reset(tick),
        }
        Ok(())
    }

    /// Start a main program in automatic mode.
    fn start(&mut self, tick: &Tick, name: &str) -> Result<(), CommandError> {
        self.isg.enter_automatic()?;
        self.hmi.starting(name);
        self.run.starting();
        self.motion.start();
        let pos = self.motion.position();
        let search = self.hmi.take_search();
        self.hmi.restart_single_block();
        self.run.running_now(name);
        if let Err(e) = self.decoder.start(name, &mut self.store, pos, search) {
            self.fail(
                tick,
                ErrorRecord {
                    code: e.code,
                    msg: e.msg.clone(),
                    prog: Some(name.to_string()),
                    line: None,
                },
            );
            return Err(CommandError::StartFailed {
                code: e.code,
                msg: e.msg,
            });
        }
        let kept = self
            .decoder
            .program_text(name)
            .map(|t| (std::sync::Arc::from(name), t));
        self.run.keep_main_text(kept, &self.loader);
        self.set_state(tick, State::Active);
        self.drain_decoder_notes(tick);
        Ok(())
    }

    /// Feed hold (0x136).
    fn hold(&mut self, tick: &Tick) {
        if self.isg.state() == State::Active {
            self.motion.set_hold(true);
            self.set_state(tick, State::Hold);
        }
    }

    /// `mc_feedhold_channel_w`: TRUE holds a running program (refused when none runs: nothing
    /// to hold); FALSE releases the feed hold and resumes, and only it: a channel held by a
    /// programmed stop or a single block stays held. Repeating a value changes nothing.
    fn set_feed_hold(&mut self, tick: &Tick, on: bool) -> Result<(), CommandError> {
        match (on, self.hmi.feed_hold()) {
            (true, true) | (false, false) => Ok(()),
            (true, false) if self.isg.state() == State::Active => {
                self.hmi.hold_feed();
                self.hold(tick);
                Ok(())
            }
            (true, false) => Err(self.isg.busy()),
            (false, true) => {
                self.resume(tick);
                Ok(())
            }
        }
    }

    /// Resume after hold (0x137).
    fn resume(&mut self, tick: &Tick) {
        self.hmi.release_feed_hold();
        if self.isg.state() == State::Hold {
            self.hmi.grant_block();
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

    /// A string into a V.E. variable from outside: `Some(0.0)` when taken.
    fn write_external_str(&mut self, name: &str, text: &str) -> Option<f64> {
        let vars = self.decoder.vars_mut();
        vars.set_external_str(name, text).is_ok().then_some(0.0)
    }

    fn read_external(&self, name: &str) -> Option<f64> {
        self.decoder.vars().get_external(name)
    }

    /// NC reset (0x13C): stream buffer emptied and streaming left, program stack, queue,
    /// cache and errors cleared, motion stopped at once; READY.
    fn reset(&mut self, tick: &Tick) {
        let dropped = self.stream.clear();
        if dropped > 0 {
            self.log.emit(
                tick,
                EventKind::Discard {
                    bytes: dropped as u64,
                },
            );
        }
        if let Some(prog) = self.run.reset() {
            self.log.emit(
                tick,
                EventKind::ProgramEnd {
                    prog: prog.to_string(),
                    end: ProgramEndKind::Reset,
                },
            );
        }
        self.motion.reset();
        // What was output or waits to be is dropped with the program, as the operator's reset
        // ends a wait for the PLC (README "Technology functions: the PLC half");
        // `plc_present` stays.
        self.techno.reset();
        self.queue.clear();
        self.hmi.close_gate();
        self.decoder.reset(self.motion.position());
        self.cache.reset();
        // A read still pending is abandoned with the program.
        self.store.take_owed();
        self.log.reset();
        self.hmi.forget_search();
        self.set_state(tick, State::Ready);
    }

    /// The decoder's notes of this tick as events; an error note stops the channel.
    fn drain_decoder_notes(&mut self, tick: &Tick) {
        if !self.decoder.has_notes() {
            return;
        }
        let mut notes = std::mem::take(&mut self.decoder_notes);
        self.decoder.take_notes(&mut notes);
        for n in notes.drain(..) {
            if let Some(error) = self.log.decoder_note(tick, n) {
                self.fail(tick, error);
            }
        }
        self.decoder_notes = notes;
    }

    /// What the motion reported this tick, in order: block events and the active block,
    /// flushes, programmed stops (HOLD), a planning error (ERROR, the rest dropped), the
    /// program end (READY).
    fn apply_motion_notes(&mut self, tick: &Tick, notes: &mut Vec<MotionNote>) {
        for n in notes.drain(..) {
            if let MotionNote::TechnoOutput(group) = n {
                self.techno.output(*group, tick.time);
                continue;
            }
            if matches!(n, MotionNote::Started(_)) && self.techno.observing() {
                self.techno.block_started(tick.time);
            }
            match self.log.motion_note(tick, n, &mut self.run, &mut self.hmi) {
                AfterMotionNote::Go => {}
                AfterMotionNote::ProgramStop => {
                    if self.isg.state() == State::Active {
                        self.set_state(tick, State::Hold);
                    }
                }
                AfterMotionNote::Ended => self.set_state(tick, State::Ready),
                AfterMotionNote::Fail(error) => {
                    self.fail(tick, error);
                    break;
                }
            }
        }
    }

    /// One cycle: the requests of this tick are already applied; the decoder reads the
    /// stream or its files, the planner and interpolator move, and what happened becomes
    /// events. Returns the wall time the tick waited for the program loader with the clock
    /// stopped (virtual time; zero in real time), which the cycle reports apart from the
    /// tick's work.
    pub fn step(&mut self, tick: &Tick) -> std::time::Duration {
        self.store.begin_tick(tick.clock);
        self.run_tick(tick);
        self.store.take_clock_stopped()
    }

    /// The tick's named steps: decode, execute, hold after a single block, note an interrupt.
    fn run_tick(&mut self, tick: &Tick) {
        self.log.seen(tick);
        self.techno_units(tick);
        if !self.isg.running() {
            return;
        }
        self.decode(tick);
        if self.isg.state() == State::Error {
            return;
        }
        self.execute(tick);
        self.hold_after_single_block(tick);
        self.note_interrupt(tick);
    }

    /// The technology units' share: acknowledgements that came in (or, without a PLC, process
    /// times that passed) finish their functions; waiting ones are output.
    fn techno_units(&mut self, tick: &Tick) {
        if self.techno.idle() {
            return;
        }
        self.techno.tick(tick.time);
        self.log.techno_notes(tick, self.techno.drain_notes());
    }

    /// The decoder's share of the tick: stream or file lines into the block queue.
    fn decode(&mut self, tick: &Tick) {
        let mut io = DecoderIo {
            stream: &mut self.stream,
            store: &mut self.store,
            cache: &mut self.cache,
            queue: &mut self.queue,
            motion_idle: self.motion.idle(),
            want_text: self.log.events_enabled(),
            now: tick.time,
            period: tick.period,
        };
        self.decoder.step(&mut io);
        self.drain_decoder_notes(tick);
    }

    /// The planner and interpolator's share: blocks from the queue (or the single-block
    /// gate) move the axes for one period.
    fn execute(&mut self, tick: &Tick) {
        let dt = tick.period.as_secs_f64();
        let mut notes = std::mem::take(&mut self.notes);
        let blocks = self.hmi.blocks_for_motion(&mut self.queue, &self.motion);
        self.motion.step(dt, blocks, &mut notes, &self.techno);
        self.apply_motion_notes(tick, &mut notes);
        if !self.techno.idle() {
            self.log.techno_notes(tick, self.techno.drain_notes());
        }
        self.notes = notes;
    }

    /// Single block: the block is done; wait for the next start.
    fn hold_after_single_block(&mut self, tick: &Tick) {
        if self.isg.state() == State::Active && self.hmi.block_done(&self.motion) {
            self.motion.set_hold(true);
            self.set_state(tick, State::Hold);
        }
    }

    /// Motion waits for stream data the decoder has not got: an interrupt, one event per
    /// stretch (the next block that takes effect resumes).
    fn note_interrupt(&mut self, tick: &Tick) {
        if self.isg.state() == State::Active
            && self.run.may_interrupt(self.motion.held_blocks())
            && self.motion.waiting_for_data()
            && self.queue.is_empty()
            && self.decoder.starved()
        {
            self.run.interrupt();
            self.motion.note_interrupt();
            let held = self.motion.held_blocks() as u64;
            self.log.interrupt(tick, held);
        }
    }
}
