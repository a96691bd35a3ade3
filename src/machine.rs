//! The emulated controller as the runtime ticks it: its channels, the built-in stream feeders,
//! and the requests other threads (ADS connections, tests) send it.
//!
//! One tick: serve requests → feeders write → each channel decodes, executes, reports →
//! events leave for the log. Nothing here blocks or does I/O.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crossbeam_channel::Sender;

use crate::channel::{
    ActiveBlock, Channel, CommandError, ErrorRecord, ExecutedBlock, Finish, HmiCommands, Mode,
    SearchCommand, State,
};
use crate::decoder::SearchTarget;
use crate::feeder::Feeder;
use crate::report::event::EventLog;
use crate::runtime::{Cycle, Flow, Tick};
use crate::source::stream::StreamWriteError;

/// What a client asks of a channel.
#[derive(Debug, Clone, PartialEq)]
pub enum Op {
    /// Write NC lines into the stream interface.
    WriteStream(Vec<u8>),
    CommandMode(i32),
    CommandState(i32),
    /// Command parameter: the program name ACTIVE starts.
    SetProgram(String),
    Hold,
    Resume,
    Reset,
    /// Feed override, percent.
    SetOverride(f64),
    WriteExternal(String, f64),
    ReadExternal(String),
    Status,
    /// An HMI command object (`mc_command_*_w`) of the COM task.
    Hmi(HmiOp),
    /// The error with this index (0 = the first the channel raised) and the total count.
    ErrorRecord(u64),
    /// Start this main program at once (`run`, `serve --start`, the soak's restarts): the
    /// command parameter and ACTIVE in one step, refused as ACTIVE would be.
    Start(String),
    /// Block search target for the next start (`run --search`); `None` forgets it.
    SearchAt(Option<SearchTarget>),
    /// The decoder's block-skip mask as a whole, bit n = `/n` (`run --skip-mask`, which
    /// reaches levels the HMI's ten-level `SkipLevels` does not).
    SkipMask(u16),
    /// Record every executed stream block for [`Op::DrainExecuted`] (the soak's checks).
    ObserveStreamBlocks(bool),
    /// The stream blocks executed since the last drain, in execution order
    /// ([`Reply::Executed`]).
    DrainExecuted,
    /// The motion traces of `run --plot` and `--trace` ([`Reply::Trace`]).
    Trace(TraceOp),
}

/// What `run` asks of the motion trace.
#[derive(Debug, Clone, PartialEq)]
pub enum TraceOp {
    /// Keep up to this many samples for the plot.
    Plot { max_samples: usize },
    /// Write every `every`-th tick's sample into this CSV file (created now).
    Csv {
        path: std::path::PathBuf,
        every: u64,
    },
    /// Flush and close the CSV file.
    FinishCsv,
}

/// The HMI command objects a client writes (see [`crate::channel::HmiCommands`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum HmiOp {
    SingleBlock(bool),
    /// The M01 switch.
    OptionalStop(bool),
    SkipLevels(u32),
    ExecutionMode(i32),
    Search(SearchCommand),
    /// Forget the cycle-time statistics (`cnc_time_reset`).
    ResetCycleTimes,
}

/// Work time of the machine's ticks (decode, plan, interpolate every channel), as the
/// kernel's `cnc_time_*` runtime statistics show their tasks' times.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CycleTimes {
    pub min: Duration,
    pub max: Duration,
    pub last: Duration,
    pub total: Duration,
    pub ticks: u64,
}

impl CycleTimes {
    fn record(&mut self, work: Duration) {
        self.min = if self.ticks == 0 {
            work
        } else {
            self.min.min(work)
        };
        self.max = self.max.max(work);
        self.last = work;
        self.total = self.total.saturating_add(work);
        self.ticks += 1;
    }
    /// Mean work time, zero before the first tick.
    pub fn mean(&self) -> Duration {
        match u32::try_from(self.ticks) {
            Ok(0) => Duration::ZERO,
            Ok(n) => self.total / n,
            Err(_) => Duration::from_secs_f64(self.total.as_secs_f64() / self.ticks as f64),
        }
    }
}

/// A snapshot of what a client may read of a channel.
#[derive(Debug, Clone, PartialEq)]
pub struct Status {
    pub mode: Mode,
    pub state: State,
    pub block_counter: u64,
    /// Stream fill: bytes used, bytes free.
    pub stream_used: usize,
    pub stream_free: usize,
    /// Configured axes with their positions (mm / degrees).
    pub positions: Vec<(char, f64)>,
    pub last_error: Option<(u32, String)>,
    pub override_pct: f64,
    pub blocks: u64,
    /// Tick that served the request, and the cycle time.
    pub tick: u64,
    pub period: Duration,
    pub cycle_times: CycleTimes,
    /// The main program running, if any.
    pub program: Option<String>,
    pub active_block: Option<ActiveBlock>,
    /// Modal programmed feed as decoded, mm/min (0 = none yet).
    pub feed_mm_per_min: f64,
    /// Path velocity, mm/s.
    pub velocity_mm_per_s: f64,
    pub hmi: HmiCommands,
    /// A block search is running (the decoder skips towards its target).
    pub searching: bool,
    /// Blocks handed to the interpolator and not yet done.
    pub ipo_blocks: usize,
    /// Errors raised since the channel was built.
    pub errors_total: u64,
    /// Positions in the programming coordinate system (mm / degrees), as `positions`.
    pub pcs_positions: Vec<(char, f64)>,
    /// The latest operator message of `#MSG` (empty after a reset).
    pub message: Option<String>,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    Done,
    Stream(Result<(), StreamWriteError>),
    Command(Result<(), CommandError>),
    Value(Option<f64>),
    Status(Box<Status>),
    /// The error asked for (if still kept) and how many the channel raised.
    ErrorRecord {
        total: u64,
        record: Option<(u32, String)>,
    },
    /// No channel with that number.
    NoChannel,
    /// A stream write refused without touching the buffer: the channel is in ERROR, so
    /// nothing will drain it before a reset (which deletes the buffer), or it has no streaming
    /// program (`streaming_prog_file` unset), so nothing ever will. ADS 0x707, not 0x708:
    /// retrying cannot succeed (docs/exactly-once.md).
    StreamNotReady,
    /// The executed stream blocks [`Op::DrainExecuted`] asked for.
    Executed(Vec<ExecutedBlock>),
    /// A trace file could not be written: the reason.
    Trace(Result<(), String>),
}

/// A request with its own way back: answered in the tick that serves it.
#[derive(Debug)]
pub struct Request {
    /// 1-based channel number.
    pub channel: u32,
    pub op: Op,
    pub reply: Sender<Reply>,
    /// Who decides this request's fate: the runtime (it applies it) or the waiting caller (it
    /// gave up and answers "not applied"). Whoever takes the claim first wins; the other side
    /// then knows, so a request is never both applied and answered as not applied
    /// (docs/exactly-once.md).
    pub claim: Claim,
}

impl Request {
    /// A request and the caller's half of its claim.
    pub fn new(channel: u32, op: Op, reply: Sender<Reply>) -> (Self, Claim) {
        let claim = Claim::default();
        let caller = claim.clone();
        (
            Request {
                channel,
                op,
                reply,
                claim,
            },
            caller,
        )
    }
}

/// A one-shot flag shared by a request and the thread waiting for its reply.
#[derive(Debug, Clone, Default)]
pub struct Claim(Arc<AtomicBool>);

impl Claim {
    /// Take the claim; true when this side got it (the other side had not taken it yet).
    pub fn take(&self) -> bool {
        !self.0.swap(true, Ordering::AcqRel)
    }
}

/// A built-in client streaming a file into one channel.
pub struct Attached {
    pub channel: u32,
    pub feeder: Feeder,
}

/// When `run` is over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopWhen {
    /// Never by itself (`serve`).
    Never,
    /// When every channel that ran a program has finished it (`run`, `soak`).
    ProgramsFinished,
}

pub struct Machine {
    channels: Vec<Channel>,
    feeders: Vec<Attached>,
    log: EventLog,
    stop_when: StopWhen,
    /// Per channel: how its last program finished.
    finishes: Vec<Option<Finish>>,
    cycle_times: CycleTimes,
}

impl Machine {
    pub fn new(channels: Vec<Channel>, log: EventLog, stop_when: StopWhen) -> Self {
        let n = channels.len();
        Machine {
            channels,
            feeders: Vec::new(),
            log,
            stop_when,
            finishes: vec![None; n],
            cycle_times: CycleTimes::default(),
        }
    }

    pub fn set_stop_when(&mut self, w: StopWhen) {
        self.stop_when = w;
    }

    pub fn attach_feeder(&mut self, channel: u32, feeder: Feeder) {
        self.feeders.push(Attached { channel, feeder });
    }

    pub fn feeders(&self) -> &[Attached] {
        &self.feeders
    }

    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// The channel by number; commands reach it only through [`Machine::apply`].
    fn channel_mut(&mut self, number: u32) -> Option<&mut Channel> {
        self.channels.get_mut((number as usize).checked_sub(1)?)
    }

    pub fn finishes(&self) -> &[Option<Finish>] {
        &self.finishes
    }

    /// Hand the remaining events to the log and wait for it to write them.
    pub fn finish_log(&mut self) -> std::io::Result<u64> {
        for c in &mut self.channels {
            c.events_mut().flush_to(&mut self.log);
        }
        std::mem::replace(&mut self.log, EventLog::disabled()).finish()
    }

    /// Events from every channel, in channel order within a tick.
    fn publish(&mut self) {
        if !self.log.enabled() {
            return;
        }
        for c in &mut self.channels {
            c.events_mut().flush_to(&mut self.log);
        }
    }

    /// Route one request to its channel (the runtime serves requests through this). The
    /// cycle-time statistics are the machine's, so their reset and the times in a status are
    /// filled in here.
    pub fn apply(&mut self, tick: &Tick, channel: u32, op: Op) -> Reply {
        if op == Op::Hmi(HmiOp::ResetCycleTimes) {
            self.cycle_times = CycleTimes::default();
            return Reply::Done;
        }
        let times = self.cycle_times;
        let Some(c) = self.channel_mut(channel) else {
            return Reply::NoChannel;
        };
        match c.apply(tick, op) {
            Reply::Status(mut s) => {
                s.cycle_times = times;
                Reply::Status(s)
            }
            r => r,
        }
    }
}

/// An error as the ADS objects carry it: number and text.
fn wire(e: &ErrorRecord) -> (u32, String) {
    (e.code, e.msg.clone())
}

/// The `index`-th error of the channel (0 = first): kept in the channel's error list, or the
/// last error when it is the newest one.
pub(crate) fn error_record(c: &Channel, index: u64) -> Option<(u32, String)> {
    let i = usize::try_from(index).ok()?;
    if let Some(e) = c.errors().get(i) {
        return Some(wire(e));
    }
    if index + 1 == c.stats().errors {
        return c.last_error().map(wire);
    }
    None
}

pub fn status_of(c: &Channel) -> Status {
    let (used, free) = c.stream_fill();
    Status {
        mode: c.mode(),
        state: c.state(),
        block_counter: c.block_counter(),
        stream_used: used,
        stream_free: free,
        positions: c.axis_positions(),
        last_error: c.last_error().map(wire),
        override_pct: c.motion().override_pct(),
        blocks: c.stats().blocks,
        tick: 0,
        period: Duration::ZERO,
        cycle_times: CycleTimes::default(),
        program: c.running_program().map(String::from),
        active_block: c.active_block().cloned(),
        feed_mm_per_min: c.decoder().modal().feed_mm_per_min,
        velocity_mm_per_s: c.motion().velocity_mm_per_s(),
        hmi: c.hmi(),
        searching: c.decoder().searching(),
        ipo_blocks: c.ipo_blocks(),
        errors_total: c.stats().errors,
        pcs_positions: c.pcs_positions(),
        message: c.message().map(str::to_string),
    }
}

impl Cycle for Machine {
    type Request = Request;

    fn serve(&mut self, req: Request, tick: &Tick) {
        // The caller gave up waiting and already answered "not applied": leave it so.
        if !req.claim.take() {
            return;
        }
        let reply = self.apply(tick, req.channel, req.op);
        // A client that went away no longer needs its answer.
        let _ = req.reply.send(reply);
    }

    fn step(&mut self, tick: &Tick) -> Flow {
        let work_start = Instant::now();
        for a in &mut self.feeders {
            let Some(c) = self.channels.get_mut((a.channel as usize).wrapping_sub(1)) else {
                continue;
            };
            if let Some(packet) = a.feeder.poll(tick.index) {
                // Through the door like any client's write; a write the channel cannot take
                // (ERROR, no streaming program) is a refusal the feeder retries.
                let reply = c.apply(tick, Op::WriteStream(packet.to_vec()));
                a.feeder.result(matches!(reply, Reply::Stream(Ok(()))));
            }
        }
        for (i, c) in self.channels.iter_mut().enumerate() {
            c.step(tick);
            if let Some(f) = c.take_finish() {
                self.finishes[i] = Some(f);
            }
        }
        self.publish();
        self.cycle_times.record(work_start.elapsed());
        match self.stop_when {
            StopWhen::Never => Flow::Continue,
            StopWhen::ProgramsFinished => {
                let running = self
                    .channels
                    .iter()
                    .any(|c| matches!(c.state(), State::Active | State::Hold));
                let any_finished = self.finishes.iter().any(Option::is_some);
                if !running && any_finished {
                    Flow::Stop
                } else {
                    Flow::Continue
                }
            }
        }
    }
}
