//! The one door into a channel: what a client asks ([`Op`]), what it hears back ([`Reply`]),
//! and the snapshot it reads ([`Status`]). `Channel::apply` answers every `Op` in the tick that
//! serves it; the machine routes requests to channels, the ADS object tables and the soak build
//! `Op`s. Defined here, beside the channel, so the channel needs nothing of the machine above it.

use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use super::techno::{TechnoRefusal, TechnoSeen, TechnoStats, TechnoStatus, TechnoWrite};
use super::{
    ActiveBlock, Channel, ChannelStats, CommandError, ErrorRecord, ExecutedBlock, HmiCommands,
    Mode, SearchCommand, State,
};
use crate::decoder::modal::Modal;
pub use crate::decoder::vars::ExternalValue;
use crate::decoder::vars::VarClass;
use crate::decoder::{DecoderStats, SearchTarget};
use crate::lang::block::AxisName;
use crate::motion::trace::Trace;
use crate::source::store::StoreStats;
use crate::source::stream::{StreamCounters, StreamWriteError};
use crate::vocab::axis::Position;
use crate::vocab::techno::Acknowledgements;

/// What a client asks of a channel.
#[derive(Debug, Clone, PartialEq)]
pub enum Op {
    /// Write NC lines into the stream interface. Shared bytes: a feeder that must offer the
    /// same packet again after 11012 hands the same allocation, not a new copy per attempt.
    WriteStream(Arc<[u8]>),
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
    /// A string into a V.E. variable (`V.E.USERINTERACTION.MESSAGE`), from outside.
    WriteExternalStr(String, String),
    /// A V.E. variable with its declared type ([`Reply::External`]), for the ADS side.
    ReadExternalTyped(String),
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
    /// The text of this file program while the decoder runs it ([`Reply::ProgramText`]): the
    /// live view's listing. A shared handle to the decoder's copy, so the tick copies nothing.
    ProgramText(Arc<str>),
    /// A PLC's write into the technology interface (`plc_present_w`, a unit's `please_rw`
    /// or `done_w`).
    Techno(TechnoWrite),
    /// Record every technology function's output, acknowledgement or drop, and the block
    /// starts that waited for functions, for [`Op::DrainTechno`] (the soak's checks).
    ObserveTechno(bool),
    /// The technology observations since the last drain ([`Reply::TechnoSeen`]).
    DrainTechno,
    /// Evaluate this notification watch after every tick (`machine::watch`); answered
    /// [`Reply::Done`] when it is active, `Reply::Value(None)` when the machine's watches
    /// are full. Served by the machine, not by a channel.
    Watch(WatchSlot),
    /// The live view's record of the channel since the last drain ([`Reply::Live`]); the
    /// first drain turns the record on (`machine::live`). Served by the machine.
    DrainLive,
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
    /// The HMI's feed hold (`mc_feedhold_channel_w`): TRUE holds, FALSE releases.
    FeedHold(bool),
}

/// Work time of the machine's ticks (serve the tick's requests, decode, plan, interpolate
/// every channel), as the kernel's `cnc_time_*` runtime statistics show their tasks' times.
/// The runtime measures it and hands it to the machine (the runtime's `Cycle::record_work`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CycleTimes {
    pub min: Duration,
    pub max: Duration,
    pub last: Duration,
    pub total: Duration,
    pub ticks: u64,
}

impl CycleTimes {
    pub(crate) fn record(&mut self, work: Duration) {
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
    pub(crate) stream_free: usize,
    /// Configured axes with their positions (mm / degrees).
    pub positions: Vec<(char, f64)>,
    pub last_error: Option<(u32, String)>,
    pub(crate) override_pct: f64,
    pub blocks: u64,
    /// Tick that served the request, and the cycle time.
    pub tick: u64,
    pub period: Duration,
    pub(crate) cycle_times: CycleTimes,
    /// The main program running, if any.
    pub program: Option<String>,
    pub(crate) active_block: Option<ActiveBlock>,
    /// Path velocity, mm/s.
    pub velocity_mm_per_s: f64,
    pub(crate) hmi: HmiCommands,
    /// A block search is running (the decoder skips towards its target).
    pub(crate) searching: bool,
    /// Blocks handed to the interpolator and not yet done.
    pub(crate) ipo_blocks: usize,
    /// Errors raised since the channel was built.
    pub(crate) errors_total: u64,
    /// Positions in the programming coordinate system (mm / degrees), as `positions`.
    pub(crate) pcs_positions: Vec<(char, f64)>,
    /// The latest operator message of `#MSG` (empty after a reset).
    pub message: Option<String>,
    /// Blocks decoded and waiting in the block queue for the lookahead window
    /// (`mc_slope_buf_level`; `ipo_blocks` counts those in the window).
    pub(crate) queued_blocks: usize,
    /// Programs that ran to their end (M02/M30) since the channel was built
    /// (`mc_program_count_r`).
    pub(crate) programs_ended: u64,
    /// The zero-offset table G54…G59 (mm / degrees per axis slot), as the parameter lists
    /// set it (`V.G.NP[1..6].V`).
    pub(crate) zero_offsets: crate::decoder::modal::ZeroOffsets,
    /// The active tool data set, as the decoder has selected it (it runs ahead of execution by
    /// the lookahead): D number (0: none) and radius, mm (`mc_active_tool_id_*`, IPO "Actual
    /// tool radius").
    pub(crate) active_tool: (u32, f64),
    /// The tool and zero-offset lists the channel was set up from (`mc_tool_file_r`,
    /// `mc_zero_offset_file_r`).
    pub(crate) list_files: ListFiles,
    /// Path length left in the executing move, mm (the DRO's distance to go).
    pub distance_to_go_mm: f64,
    /// The HLI technology interface: PLC present, the units and what they hold.
    pub techno: TechnoStatus,
    /// Technology functions output and acknowledged so far, and which units hold a function
    /// still open (not yet acknowledged): `techno.std` then `techno.late`, by index.
    pub techno_open: TechnoOpen,
    /// The executing motion block's programmed feed, mm/min, and whether it is a rapid
    /// (`None` between moves): the live view's feed, where `modal.feed_mm_per_min` is the
    /// decoder's, ahead by the lookahead.
    pub(crate) executing_feed_mm_per_min: Option<f64>,
    pub(crate) executing_rapid: bool,
    /// The decoder's modal state (programmed feed, mm/min, 0 = none yet; spindle, tool,
    /// G groups, zero offset), ahead of execution by the lookahead.
    pub modal: Box<crate::decoder::modal::Modal>,
    /// Stream writes refused because the buffer had no room (11012), since the channel was
    /// built.
    pub(crate) stream_writes_full: u64,
    /// Program and line of the last error, where known.
    pub(crate) last_error_at: Option<(Option<String>, Option<u64>)>,
    /// The streaming program (`streaming_prog_file`), if streaming is on: what the live
    /// view's MDI and jog start.
    pub(crate) streaming_program: Option<String>,
}

/// The file names of a channel's tool list (`werkz_data[i]` or `tools.lis`) and zero-offset
/// list (`nullp_data[i]` or `zero_offset_list`); `None`: no such list.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ListFiles {
    pub tool: Option<Arc<str>>,
    pub zero_offset: Option<Arc<str>>,
}

/// The technology counters and open units a [`Status`] carries for the live view.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TechnoOpen {
    pub stats: TechnoStats,
    /// `(late, unit)`: `false` for `techno.std[unit]`, `true` for `techno.late[unit]`.
    pub units: Vec<(bool, usize)>,
}

/// What a channel tells after a run (and what tests read between ticks): its counters and
/// those of the parts it owns, the errors, the position, the motion trace. Built on demand by
/// [`Channel::report`], never by the tick.
#[derive(Debug, Clone)]
pub struct ChannelReport {
    /// 1-based channel number.
    pub number: u32,
    /// Technology functions output, acknowledged, waited for.
    pub techno: TechnoStats,
    pub mode: Mode,
    pub state: State,
    pub stats: ChannelStats,
    /// Program files opened and read, by the program store.
    pub store: StoreStats,
    pub cache: CacheStats,
    /// What passed through the stream interface.
    pub stream: StreamCounters,
    /// Stream fill level: (used, free) bytes.
    pub stream_fill: (usize, usize),
    pub decoder: DecoderStats,
    /// The decoder's modal state (it runs ahead of execution by the lookahead).
    pub modal: Modal,
    /// The decoder reads the stream interface (a streaming program runs).
    pub reads_stream: bool,
    /// Block counter of the running program (ISG: every decoded line).
    pub block_counter: u64,
    /// Machine position of every axis slot, mm / degrees.
    pub position: Position,
    /// The configured axes' positions under their configured names (`X`, `X1`), in
    /// `AXIS_LETTERS` order, mm / degrees.
    pub named_positions: Vec<(AxisName, f64)>,
    /// The first `MAX_LISTED_ERRORS` errors of the channel's life, oldest first.
    pub errors: Vec<ErrorRecord>,
    pub last_error: Option<ErrorRecord>,
    /// The latest operator message an NC program sent with `#MSG` (`mc_message_r`).
    pub message: Option<String>,
    /// Command parameter (0x108): the program `ACTIVE` starts.
    pub program: Option<String>,
    /// Blocks the lookahead window holds and may not release yet (the memory effect): what
    /// the axes wait for during an interrupt.
    pub held_blocks: usize,
    /// The motion trace `run --plot` asked for ([`TraceOp::Plot`]), if on.
    pub trace: Option<Trace>,
    /// Bytes of variables by class, in [`VarClass`] order.
    var_bytes: [usize; VAR_CLASSES.len()],
}

/// The variable classes a report counts, in the order of `ChannelReport::var_bytes`.
const VAR_CLASSES: [VarClass; 5] = [
    VarClass::P,
    VarClass::Program,
    VarClass::Local,
    VarClass::SelfRetaining,
    VarClass::External,
];

impl ChannelReport {
    /// Bytes the decoder's variables of `class` take (what the class's limit counts).
    pub fn var_bytes(&self, class: VarClass) -> usize {
        // Exhaustive: a new class must find its place in `VAR_CLASSES`.
        let i = match class {
            VarClass::P => 0,
            VarClass::Program => 1,
            VarClass::Local => 2,
            VarClass::SelfRetaining => 3,
            VarClass::External => 4,
        };
        debug_assert_eq!(VAR_CLASSES[i], class);
        self.var_bytes[i]
    }
}

/// The file cache's counters and contents.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CacheStats {
    /// Calls served from the cache.
    pub hits: u64,
    /// Names of the cached files, in the cache's order.
    pub files: Vec<String>,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    Done,
    Stream(Result<(), StreamWriteError>),
    Command(Result<(), CommandError>),
    Value(Option<f64>),
    /// A V.E. variable read with its type; `None` when it does not exist.
    External(Option<ExternalValue>),
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
    /// The program text [`Op::ProgramText`] asked for; `None` when no frame runs it.
    ProgramText(Option<Arc<Vec<u8>>>),
    /// A technology write taken, or refused without a change.
    Techno(Result<(), TechnoRefusal>),
    /// The observations [`Op::DrainTechno`] asked for, in order, and how many did not fit
    /// between two drains.
    TechnoSeen {
        seen: Vec<TechnoSeen>,
        lost: u64,
    },
    /// What [`Op::DrainLive`] asked for.
    Live(Box<super::live::LiveDrain>),
}

/// An error as the ADS objects carry it: number and text.
fn wire(e: &ErrorRecord) -> (u32, String) {
    (e.code, e.msg.clone())
}

/// The `index`-th error of the channel (0 = first): kept in the channel's error list, or the
/// last error when it is the newest one.
pub(crate) fn error_record(c: &Channel, index: u64) -> Option<(u32, String)> {
    let i = usize::try_from(index).ok()?;
    if let Some(e) = c.log.errors().get(i) {
        return Some(wire(e));
    }
    if index + 1 == c.log.stats().errors {
        return c.log.last_error().map(wire);
    }
    None
}

pub(crate) fn status_of(c: &Channel) -> Status {
    let stats = c.log.stats();
    let techno = c.techno.status();
    let techno_open = techno_open(c, &techno);
    Status {
        mode: c.isg.mode(),
        state: c.isg.state(),
        block_counter: c.decoder.counter(),
        stream_used: c.stream.used(),
        stream_free: c.stream.free(),
        positions: c.axis_positions(),
        last_error: c.log.last_error().map(wire),
        override_pct: c.motion.override_pct(),
        blocks: stats.blocks,
        tick: 0,
        period: Duration::ZERO,
        cycle_times: CycleTimes::default(),
        program: c.run.running().map(String::from),
        active_block: c.run.active_block().cloned(),
        velocity_mm_per_s: c.motion.velocity_mm_per_s(),
        hmi: c.hmi.commands(),
        searching: c.decoder.searching(),
        ipo_blocks: c.ipo_blocks(),
        errors_total: stats.errors,
        pcs_positions: c.pcs_positions(),
        message: c.log.message().map(str::to_string),
        queued_blocks: c.queue.len(),
        programs_ended: stats.programs_ended,
        zero_offsets: *c.decoder.zero_offsets(),
        active_tool: c.decoder.active_tool(),
        list_files: c.list_files.clone(),
        distance_to_go_mm: c.motion.distance_to_go_mm(),
        techno,
        techno_open,
        executing_feed_mm_per_min: c.motion.executing_move().map(|m| m.feed_mm_per_min),
        executing_rapid: c
            .motion
            .executing_move()
            .is_some_and(|m| m.kind == crate::queue::MoveKind::Rapid),
        modal: Box::new(c.decoder.modal().clone()),
        stream_writes_full: c.stream.counters().writes_full,
        last_error_at: c.log.last_error().map(|e| (e.prog.clone(), e.line)),
        streaming_program: c.store.streaming_program().map(str::to_string),
    }
}

/// Units holding an open function: none while the units are idle (no allocation).
fn techno_open(c: &Channel, s: &TechnoStatus) -> TechnoOpen {
    let t = &c.techno;
    let open = |u: &super::techno::Unit| {
        u.function
            .as_ref()
            .is_some_and(|f| !t.is_acknowledged(f.seq))
    };
    let units = if t.idle() {
        Vec::new()
    } else {
        let std = s
            .std
            .iter()
            .enumerate()
            .filter(|(_, u)| open(u))
            .map(|(i, _)| (false, i));
        let late = s
            .late
            .iter()
            .enumerate()
            .filter(|(_, u)| open(u))
            .map(|(i, _)| (true, i));
        std.chain(late).collect()
    };
    TechnoOpen {
        stats: t.stats(),
        units,
    }
}

pub(crate) fn report_of(c: &Channel) -> ChannelReport {
    ChannelReport {
        number: c.log.number(),
        techno: c.techno.stats(),
        mode: c.isg.mode(),
        state: c.isg.state(),
        stats: c.log.stats(),
        store: c.store.stats(),
        cache: CacheStats {
            hits: c.cache.hits,
            files: c.cache.names().map(String::from).collect(),
        },
        stream: *c.stream.counters(),
        stream_fill: (c.stream.used(), c.stream.free()),
        decoder: c.decoder.stats(),
        modal: c.decoder.modal().clone(),
        reads_stream: c.decoder.reads_stream(),
        block_counter: c.decoder.counter(),
        position: c.motion.position(),
        named_positions: c.named_positions(),
        errors: c.log.errors().to_vec(),
        last_error: c.log.last_error().cloned(),
        message: c.log.message().map(String::from),
        program: c.hmi.program().map(String::from),
        held_blocks: c.motion.held_blocks(),
        trace: c.motion.trace().cloned(),
        var_bytes: VAR_CLASSES.map(|class| c.decoder.vars().bytes(class)),
    }
}

/// What the sink did with a sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Delivery {
    /// Queued for the client: it is the watch's last value now.
    Sent,
    /// Not yet wanted (the client does not know the handle yet): offered again next tick.
    NotYet,
    /// The owner is gone (handle deleted, connection closed or overflowed): the watch ends.
    Gone,
}

/// Why a channel request failed (the ADS server maps each to one ADS result code).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DeviceError {
    /// The channel cannot do that in its current mode/state (0x707).
    #[error("device not ready")]
    NotReady,
    /// Try again shortly (0x708).
    #[error("device busy")]
    Busy,
    /// The channel's mode and state do not allow the command: retrying cannot help until
    /// something else changes them, e.g. a start while in ERROR or a mode change while ACTIVE
    /// (0x707; the HLI posts the kernel's 270061 in `mc_error`).
    #[error("not permitted in the channel's mode and state")]
    Refused,
    /// The value is out of range or unknown, e.g. mode 9 or override 250 % (0x706).
    #[error("invalid parameter value")]
    InvalidValue,
    /// A named thing does not exist, e.g. an unknown V.E. variable (0x70C).
    #[error("not found")]
    NotFound,
}

/// What an object's encoder reads: channels' status and the answers of read-only requests.
/// A read through the runtime asks it now (`ads::backend::Live`); a watch evaluated in the
/// cycle reads the tick being evaluated (`machine::watch`). Either way a channel's status is
/// built at most once per encoding. `ch` is 1-based.
pub trait Source {
    /// Number of channels (`1..=channel_count()`).
    fn channel_count(&self) -> u16;
    /// Channel `ch`'s status.
    fn status(&mut self, ch: u16) -> Result<&Status, DeviceError>;
    /// Apply a read-only `op` to channel `ch` (an encoder never asks for a change).
    fn call(&mut self, ch: u16, op: Op) -> Result<Reply, DeviceError>;
}

/// The object's bytes read from `source`, `None` when it cannot be encoded now.
pub type Encode = Box<dyn Fn(&mut dyn Source) -> Option<Vec<u8>> + Send>;
/// Where a sample goes.
pub type Deliver = Box<dyn FnMut(&[u8]) -> Delivery + Send>;

/// One notification handle as the cycle sees it.
pub struct Watch {
    /// Cyclic: a sample every `cycle`; on change: checked every `cycle`, sent when different.
    pub cycle: Duration,
    pub on_change: bool,
    pub encode: Encode,
    pub deliver: Deliver,
    /// Cleared by the owner to end the watch.
    pub alive: Arc<AtomicBool>,
}

/// A [`Watch`] handed to the machine through the request queue ([`Op::Watch`]): taken once.
/// The watch types live here, with the door's vocabulary, so the channel that defines `Op`
/// needs nothing of the machine; the machine evaluates them (`machine::watch`).
#[derive(Clone)]
pub struct WatchSlot(pub Arc<Mutex<Option<Watch>>>);

impl WatchSlot {
    pub fn new(w: Watch) -> Self {
        WatchSlot(Arc::new(Mutex::new(Some(w))))
    }

    /// The watch, once: the machine takes it when it serves [`Op::Watch`].
    pub(crate) fn take(&self) -> Option<Watch> {
        self.0.lock().unwrap_or_else(|p| p.into_inner()).take()
    }
}

impl std::fmt::Debug for WatchSlot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("WatchSlot")
    }
}

impl PartialEq for WatchSlot {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}
