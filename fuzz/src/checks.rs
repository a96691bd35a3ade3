//! What each fuzz target asserts about one input. The bodies are plain functions over bytes so
//! that `tests/hardening/fuzz_regressions.rs` runs the same assertions over the kept inputs in
//! `cargo test`, with no libFuzzer and no nightly toolchain.
//!
//! Every check panics on a finding (that is how libFuzzer sees it); a malformed input that is
//! refused with an error is not a finding.

use std::path::Path;

use arbitrary::{Arbitrary, Unstructured};

use ncchannel::ads::frame::{self, Frame};
use ncchannel::ads::payload;
use ncchannel::ads::route_service::{self, Identity};
use ncchannel::ads::routes::{RouteTable, MAX_ROUTES};
use ncchannel::dnc::markers::{Anchor, Markers};
use ncchannel::dnc::splitter::{ProgramEnd, ProgramSink, ProgramStart, Splitter};
use ncchannel::lang::{self, VarKey, Vars};
use ncchannel::vocab::ams::DEFAULT_MAX_FRAME_BYTES;
use ncchannel::{StreamBuffer, MAX_PROGRAM_STREAM_SIZE};

/// Longest NC line the fuzzers hand to the parser: ISG lines are at most 4000 characters, and
/// a longer one only slows the fuzzer without reaching new code.
const MAX_LINE_BYTES: usize = 8 * 1024;

fn text(data: &[u8]) -> Option<&str> {
    std::str::from_utf8(data).ok()
}

/// The NC line parser never panics, whatever the line (and neither do the two helpers the
/// decoder calls inside `#COMMENT` and `#VAR` blocks).
pub fn nc_line(data: &[u8]) {
    let Some(line) = text(data) else { return };
    if line.len() > MAX_LINE_BYTES {
        return;
    }
    let _ = lang::parse_block(line);
    let _ = lang::parse_var_declaration(line);
    let _ = lang::is_comment_end(line);
    let _ = lang::is_blank_line(line);
}

/// A block that parses prints as canonical text that parses back to the same block: what the
/// decoder logs and block search replays must mean what the programmer wrote.
pub fn nc_roundtrip(data: &[u8]) {
    let Some(line) = text(data) else { return };
    if line.len() > MAX_LINE_BYTES {
        return;
    }
    let Ok(block) = lang::parse_block(line) else {
        return;
    };
    let canonical = block.to_string();
    // The canonical text brackets every operation, so it may outgrow the 4000-character block
    // limit that the written line kept; such a text is for logs only and never read back.
    if canonical.chars().count() > lang::codes::MAX_BLOCK_CHARS {
        return;
    }
    let again = match lang::parse_block(&canonical) {
        Ok(b) => b,
        Err(e) => panic!("{line:?} printed as {canonical:?}, which does not parse: {e}"),
    };
    assert_eq!(
        again.to_string(),
        canonical,
        "{line:?}: the canonical text is not a fixed point"
    );
}

/// Every variable has the same value: the evaluator's arithmetic, indices and functions are
/// what is under test, not the decoder's storage.
struct AnyVars(f64);

impl Vars for AnyVars {
    fn get(&self, _key: &VarKey<'_>) -> Option<f64> {
        Some(self.0)
    }
}

/// Expression parsing and evaluation never panic: a result or an error with a number.
pub fn expr_eval(data: &[u8]) {
    let Some((&seed, rest)) = data.split_first() else {
        return;
    };
    let Some(src) = text(rest) else { return };
    if src.len() > MAX_LINE_BYTES {
        return;
    }
    let Ok(expr) = lang::parse_expr(src) else {
        return;
    };
    let value = f64::from(seed) - 128.0;
    if let Err(e) = lang::eval(&expr, &AnyVars(value)) {
        let _ = e.code();
    }
}

/// The static program checker never panics, and every finding points into the program.
pub fn program_check(data: &[u8]) {
    let Some(program) = text(data) else { return };
    let lines = program.lines().count().max(1);
    for d in lang::check_program(program) {
        assert!(
            d.line >= 1 && d.line <= lines + 1,
            "diagnostic on line {} of a {lines}-line program: {d:?}",
            d.line
        );
    }
}

/// The ISG parameter-list parser never panics and reports every problem with a position.
pub fn param_list(data: &[u8]) {
    let Some(src) = text(data) else { return };
    let (_list, _diags) = ncchannel::params::list::parse_list(Path::new("fuzz.lis"), src);
}

/// The route service (UDP 48899) takes any datagram: a clear error, or a reply that parses
/// back with the request's invoke id and the response bit, of a bounded size; the route
/// table stays within its bound.
pub fn route_datagram(data: &[u8]) {
    let me = Identity {
        net_id: ncchannel::vocab::ams::AmsNetId([127, 0, 0, 2, 1, 1]),
        host_name: "fuzz".into(),
    };
    let routes = RouteTable::new(&["10.0.0.1".parse().expect("an IP")]);
    let Ok((reply, _)) = route_service::answer(data, &me, &routes) else {
        return;
    };
    let request = route_service::parse(data).expect("an answered datagram parses");
    if let Some(r) = reply {
        assert!(r.len() <= 1024, "reply of {} bytes", r.len());
        let back = route_service::parse(&r).expect("a reply parses");
        assert_eq!(back.invoke_id, request.invoke_id);
        assert_eq!(back.service, request.service | 0x8000_0000);
    }
    assert!(routes.entries().len() <= MAX_ROUTES);
}

/// The AMS/TCP codec cuts any byte stream into frames or a clear error, never reads past what
/// it was given, and the ADS payload decoders take any frame body.
pub fn ams_codec(data: &[u8]) {
    let mut rest = data;
    loop {
        match frame::decode(rest, DEFAULT_MAX_FRAME_BYTES) {
            Ok(Some((f, used))) => {
                assert!(
                    used > 0 && used <= rest.len(),
                    "consumed {used} of {}",
                    rest.len()
                );
                if let Frame::Ams { header, data } = f {
                    let _ = payload::decode_request(header.command.to_u16(), &data);
                    let _ = payload::decode_data_response(&data);
                    let _ = payload::decode_result(&data);
                    let _ = payload::decode_notification(&data);
                    let encoded = frame::encode(&header, &data);
                    match frame::decode(&encoded, DEFAULT_MAX_FRAME_BYTES) {
                        Ok(Some((Frame::Ams { data: d2, .. }, n))) => {
                            assert_eq!(n, encoded.len());
                            assert_eq!(d2, data);
                        }
                        other => panic!("a decoded frame does not re-encode: {other:?}"),
                    }
                }
                rest = &rest[used..];
            }
            Ok(None) | Err(_) => return,
        }
    }
}

/// One program as the splitter delivered it.
#[derive(Debug, PartialEq)]
struct Program {
    bytes: Vec<u8>,
    complete: bool,
    /// (workpiece folder, file name) from the program's name lines.
    file_name: Option<(Option<String>, String)>,
}

/// Collects the programs of one transfer.
#[derive(Default)]
struct Collect {
    programs: Vec<Program>,
    open: Option<Vec<u8>>,
}

impl ProgramSink for Collect {
    type Error = std::convert::Infallible;
    fn start(&mut self, _start: &ProgramStart) -> Result<(), Self::Error> {
        assert!(self.open.is_none(), "a program starts inside another");
        self.open = Some(Vec::new());
        Ok(())
    }
    fn data(&mut self, bytes: &[u8]) -> Result<(), Self::Error> {
        match &mut self.open {
            Some(p) => p.extend_from_slice(bytes),
            None => panic!("data outside a program"),
        }
        Ok(())
    }
    fn end(&mut self, end: ProgramEnd) -> Result<(), Self::Error> {
        let Some(p) = self.open.take() else {
            panic!("end outside a program")
        };
        assert_eq!(p.len() as u64, end.bytes, "byte count of a program");
        self.programs.push(Program {
            bytes: p,
            complete: end.complete,
            file_name: end.name.file_name(),
        });
        Ok(())
    }
}

#[derive(Debug, Arbitrary)]
struct SplitCase {
    start: Vec<String>,
    end: Vec<String>,
    at_line_start: bool,
    /// Chunk lengths, used in turn (0 is read as 1).
    chunks: Vec<u8>,
    transfer: Vec<u8>,
}

/// The DNC splitter gives the same programs, names and byte counts whatever the chunking of
/// the transfer (compared with the whole transfer in one chunk).
pub fn dnc_split(data: &[u8]) {
    let Ok(case) = SplitCase::arbitrary_take_rest(Unstructured::new(data)) else {
        return;
    };
    let anchor = if case.at_line_start {
        Anchor::LineStart
    } else {
        Anchor::Anywhere
    };
    let start: Vec<&String> = case.start.iter().take(3).collect();
    let end: Vec<&String> = case.end.iter().take(3).collect();
    let Ok(markers) = Markers::new(start, end, anchor) else {
        return;
    };
    let mut whole = Collect::default();
    let mut splitter = Splitter::new(markers.clone());
    let Ok(()) = splitter.feed(&case.transfer, &mut whole);
    let Ok(whole_summary) = splitter.finish(&mut whole);

    let mut chunked = Collect::default();
    let mut splitter = Splitter::new(markers);
    let mut rest = &case.transfer[..];
    let mut sizes = case.chunks.iter().cycle();
    while !rest.is_empty() {
        let n = sizes.next().map_or(rest.len(), |&s| usize::from(s.max(1)));
        let (chunk, tail) = rest.split_at(n.min(rest.len()));
        let Ok(()) = splitter.feed(chunk, &mut chunked);
        rest = tail;
    }
    let Ok(chunked_summary) = splitter.finish(&mut chunked);
    assert_eq!(
        whole.programs, chunked.programs,
        "programs differ by chunking"
    );
    assert_eq!(
        whole_summary, chunked_summary,
        "summaries differ by chunking"
    );
}

#[derive(Debug, Arbitrary)]
enum StreamOp {
    /// A packet: `lines` whole lines of `width` bytes each (CR LF included), or raw bytes.
    Lines {
        lines: u8,
        width: u8,
    },
    Raw(Vec<u8>),
    Take,
    Reset,
}

/// The 4094-byte stream buffer: whole-or-nothing writes, fill level always consistent, and
/// exactly the accepted bytes read back, in order, once (none after a reset).
pub fn stream_buffer(data: &[u8]) {
    let Ok(ops) = Vec::<StreamOp>::arbitrary_take_rest(Unstructured::new(data)) else {
        return;
    };
    let mut buffer = StreamBuffer::new();
    let mut owed: Vec<u8> = Vec::new();
    let mut segment = Vec::with_capacity(MAX_PROGRAM_STREAM_SIZE);
    for op in ops.into_iter().take(10_000) {
        match op {
            StreamOp::Lines { lines, width } => {
                let width = usize::from(width.max(3));
                let mut packet = Vec::new();
                for _ in 0..lines {
                    packet.extend(std::iter::repeat_n(b'N', width - 2));
                    packet.extend_from_slice(b"\r\n");
                }
                write(&mut buffer, &mut owed, &packet);
            }
            StreamOp::Raw(bytes) => write(&mut buffer, &mut owed, &bytes),
            StreamOp::Take => {
                let n = buffer.take_segment(&mut segment);
                assert_eq!(n, segment.len());
                assert_eq!(segment, owed, "read back differs from what was accepted");
                owed.clear();
            }
            StreamOp::Reset => {
                assert_eq!(buffer.clear(), owed.len());
                owed.clear();
            }
        }
        assert_eq!(buffer.used(), owed.len());
        assert_eq!(buffer.used() + buffer.free(), MAX_PROGRAM_STREAM_SIZE);
    }
}

fn write(buffer: &mut StreamBuffer, owed: &mut Vec<u8>, packet: &[u8]) {
    let before = buffer.used();
    match buffer.write(packet) {
        Ok(()) => owed.extend_from_slice(packet),
        Err(_) => assert_eq!(buffer.used(), before, "a refused write changed the buffer"),
    }
}

/// Longest a tick may take on any NC text. The real kernel's cycle is 1 ms; this bound is
/// generous (sanitizers, debug builds, a loaded machine) but far below what an unbounded
/// declaration or loop costs.
const MAX_TICK: std::time::Duration = std::time::Duration::from_millis(250);

/// Ticks one fuzzed program may run: enough to decode and move through a few kilobytes.
const MAX_TICKS: u64 = 20_000;

/// The shipped start-up list, found from whichever crate compiled this file.
fn shipped_config() -> Option<&'static ncchannel::params::config::Config> {
    static CONFIG: std::sync::OnceLock<Option<ncchannel::params::config::Config>> =
        std::sync::OnceLock::new();
    CONFIG
        .get_or_init(|| {
            let here = Path::new(env!("CARGO_MANIFEST_DIR"));
            let list = here
                .ancestors()
                .map(|d| d.join("params/startup.lis"))
                .find(|p| p.is_file())?;
            ncchannel::params::config::load(&list).ok()
        })
        .as_ref()
}

/// A whole channel in virtual time runs a fuzzed program streamed in whole-line packets:
/// no panic, and no tick over [`MAX_TICK`] (of the thread's CPU time: a loaded machine's
/// scheduler must not make a finding), whatever the NC text.
pub fn channel_program(data: &[u8]) {
    use ncchannel::machine::{Op, Reply};
    use ncchannel::runtime::Tick;
    let Some(config) = shipped_config() else {
        panic!("params/startup.lis not found or refused")
    };
    let Ok(mut channels) = ncchannel::channels(config, false, &ncchannel::Loader::start()) else {
        panic!("the shipped parameter lists give no channel")
    };
    let Some(channel) = channels.first_mut() else {
        return;
    };
    let Some(program) = config.channels[0].streaming_prog_file.clone() else {
        return;
    };
    let period = std::time::Duration::from_micros(config.runtime.cycle_period_us);
    let tick = |index: u64| Tick {
        index,
        period,
        time: period * u32::try_from(index).unwrap_or(u32::MAX),
        clock: ncchannel::runtime::Clock::Virtual,
    };
    // Whole lines with CR LF, cut into packets of at most 992 bytes; longer lines are left out
    // (the stream interface refuses them whole, which the stream_buffer target covers).
    let mut packets: Vec<Vec<u8>> = Vec::new();
    let mut packet = Vec::new();
    for line in data.split(|&b| b == b'\n') {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line.len() + 2 > ncchannel::MAX_PROGRAM_STREAM_INPUT_SIZE {
            continue;
        }
        if packet.len() + line.len() + 2 > ncchannel::MAX_PROGRAM_STREAM_INPUT_SIZE {
            packets.push(std::mem::take(&mut packet));
        }
        packet.extend_from_slice(line);
        packet.extend_from_slice(b"\r\n");
    }
    packets.push(packet);
    packets.push(b"M30\r\n".to_vec());

    if channel.apply(&tick(0), Op::Start(program.clone())) != Reply::Command(Ok(())) {
        return;
    }
    let mut next = packets.iter().peekable();
    for k in 1..MAX_TICKS {
        let t = tick(k);
        if let Some(p) = next.peek() {
            if channel.apply(&t, Op::WriteStream(p.as_slice().into())) == Reply::Stream(Ok(())) {
                next.next();
            }
        }
        let began = cpu_time::ThreadTime::now();
        channel.step(&t);
        let took = began.elapsed();
        assert!(took <= MAX_TICK, "tick {k} took {took:?}");
        if channel.take_finish().is_some() {
            return;
        }
    }
}

#[derive(Debug, Arbitrary)]
struct ParamFolder {
    startup: String,
    channel_list: String,
    runtime_toml: String,
    /// Seed the generated start-up list from the shipped one (the mutator then edits it).
    from_shipped: bool,
}

/// `params::load` over a generated folder (start-up list, channel list, runtime.toml): a
/// configuration or diagnostics, never a panic; and a configuration it accepts builds channels
/// without a panic (what `check` accepts, `run` can start).
pub fn param_folder(data: &[u8]) {
    let Ok(case) = ParamFolder::arbitrary_take_rest(Unstructured::new(data)) else {
        return;
    };
    let Ok(dir) = tempfile::tempdir() else { return };
    let startup = if case.from_shipped {
        format!(
            "kanal_anzahl 1\nsda_mds[0] channel1.lis\n{}\n",
            case.startup
        )
    } else {
        case.startup
    };
    let files = [
        ("startup.lis", startup),
        ("channel1.lis", case.channel_list),
        ("runtime.toml", case.runtime_toml),
    ];
    for (name, text) in &files {
        if std::fs::write(dir.path().join(name), text).is_err() {
            return;
        }
    }
    if let Ok(config) = ncchannel::params::config::load(&dir.path().join("startup.lis")) {
        let _ = ncchannel::channels(&config, false, &ncchannel::Loader::start());
    }
}

/// One thing a client does to the machine: a request (through the same `Request` and
/// `Claim` the ADS server uses) or a number of ticks passing.
#[derive(Debug, Arbitrary)]
pub enum ClientStep {
    /// A packet of `lines` valid NC lines (sequential N numbers, small moves), CR LF ended,
    /// with `#FLUSH` after them when `flush` (else motion may hold them for its look-ahead).
    Lines {
        lines: u8,
        x: i8,
        feed: u8,
        flush: bool,
    },
    /// Raw bytes: bad line ends, garbage, empty or oversized packets.
    Raw(Vec<u8>),
    /// Automatic mode, the streaming program as command parameter, state ACTIVE.
    Start,
    Mode(i8),
    State(i8),
    Program(String),
    Hold,
    Resume,
    Reset,
    Override(i16),
    WriteExternal(u8, i32),
    ReadExternal(u8),
    Status,
    ErrorRecord(u8),
    SingleBlock(bool),
    OptionalStop(bool),
    SkipLevels(u32),
    ExecutionMode(i8),
    ResetCycleTimes,
    /// The caller gives up on its next request before the tick serves it.
    GiveUp,
    Ticks(u8),
}

/// Ticks one input may run: enough for a few hundred short moves.
const MAX_MACHINE_TICKS: u64 = 4_000;

/// The machine under random request sequences: no panic; every request answered exactly
/// once — or, when its caller gave up first, neither answered nor applied; stream lines
/// executed only when their write was accepted, each at most once, in the order written;
/// no tick over [`MAX_TICK`].
pub fn machine_requests(data: &[u8]) {
    if let Ok(steps) = Vec::<ClientStep>::arbitrary_take_rest(Unstructured::new(data)) {
        machine_steps(steps);
    }
}

/// The request of a step that is one request as it is; `None` for the steps the caller
/// handles itself (`Ticks`, `GiveUp`, `Start`, `Lines`).
fn plain_op(step: ClientStep) -> Option<ncchannel::machine::Op> {
    use ncchannel::machine::{HmiOp, Op};
    Some(match step {
        // No N in raw data: only the generated lines carry block numbers, so the order
        // check knows every numbered line and whether its write was accepted.
        ClientStep::Raw(mut bytes) => {
            bytes.retain(|b| !matches!(b, b'N' | b'n'));
            Op::WriteStream(bytes.into())
        }
        ClientStep::Mode(v) => Op::CommandMode(i32::from(v)),
        ClientStep::State(v) => Op::CommandState(i32::from(v)),
        ClientStep::Program(name) => Op::SetProgram(name),
        ClientStep::Hold => Op::Hold,
        ClientStep::Resume => Op::Resume,
        ClientStep::Reset => Op::Reset,
        ClientStep::Override(p) => Op::SetOverride(f64::from(p)),
        ClientStep::WriteExternal(name, v) => Op::WriteExternal(format!("V{name}"), f64::from(v)),
        ClientStep::ReadExternal(name) => Op::ReadExternal(format!("V{name}")),
        ClientStep::Status => Op::Status,
        ClientStep::ErrorRecord(i) => Op::ErrorRecord(u64::from(i)),
        ClientStep::SingleBlock(on) => Op::Hmi(HmiOp::SingleBlock(on)),
        ClientStep::OptionalStop(on) => Op::Hmi(HmiOp::OptionalStop(on)),
        ClientStep::SkipLevels(m) => Op::Hmi(HmiOp::SkipLevels(m)),
        ClientStep::ExecutionMode(m) => Op::Hmi(HmiOp::ExecutionMode(i32::from(m))),
        ClientStep::ResetCycleTimes => Op::Hmi(HmiOp::ResetCycleTimes),
        ClientStep::Ticks(_)
        | ClientStep::GiveUp
        | ClientStep::Start
        | ClientStep::Lines { .. } => return None,
    })
}

/// A packet of up to 40 numbered G01 lines (numbers from `next_n`, never reused), with a
/// `#FLUSH` after them if asked; the packet and its N numbers.
fn lines_packet(next_n: &mut u32, lines: u8, x: i8, feed: u8, flush: bool) -> (Vec<u8>, Vec<u32>) {
    let mut packet = Vec::new();
    let mut ns = Vec::new();
    for j in 0..lines.min(40) {
        let n = *next_n;
        *next_n += 1;
        ns.push(n);
        let x = i32::from(x) + i32::from(j);
        let f = 1000 + u32::from(feed) * 100;
        packet.extend_from_slice(format!("N{n} G01 X{x} F{f}\r\n").as_bytes());
    }
    if flush {
        packet.extend_from_slice(b"#FLUSH\r\n");
    }
    (packet, ns)
}

/// [`machine_requests`] over steps given directly; returns how many numbered stream lines
/// were executed (so a test can tell that its sequence reached the interpolator).
pub fn machine_steps(steps: Vec<ClientStep>) -> usize {
    use ncchannel::machine::{Machine, Op, Reply, StopWhen};
    use ncchannel::report::event::EventLog;
    let Some(config) = shipped_config() else {
        panic!("params/startup.lis not found or refused")
    };
    let Ok(channels) = ncchannel::channels(config, false, &ncchannel::Loader::start()) else {
        panic!("the shipped parameter lists give no channel")
    };
    let Some(stream_prog) = config.channels[0].streaming_prog_file.clone() else {
        return 0;
    };
    let mut machine = Machine::new(channels, EventLog::disabled(), StopWhen::Never);
    let period = std::time::Duration::from_micros(config.runtime.cycle_period_us);
    machine.apply(&tick_at(period, 0), 1, Op::ObserveStreamBlocks(true));
    let mut k: u64 = 0;
    let tick = |index: u64| tick_at(period, index);
    // N numbers of the lines written so far (never reused).
    let mut next_n: u32 = 1;
    let mut seen = Observed::default();
    let mut give_up = false;
    let (tx, rx) = crossbeam_channel::unbounded::<Reply>();

    for step in steps.into_iter().take(2_000) {
        if k >= MAX_MACHINE_TICKS {
            break;
        }
        let op = match step {
            ClientStep::Ticks(n) => {
                run_ticks(&mut machine, period, u64::from(n), &mut k, &mut seen);
                continue;
            }
            ClientStep::GiveUp => {
                give_up = true;
                continue;
            }
            ClientStep::Start => {
                for op in [
                    Op::CommandMode(2),
                    Op::SetProgram(stream_prog.clone()),
                    Op::CommandState(4),
                ] {
                    let _ = machine.apply(&tick(k), 1, op);
                }
                continue;
            }
            ClientStep::Lines {
                lines,
                x,
                feed,
                flush,
            } => {
                let (packet, ns) = lines_packet(&mut next_n, lines, x, feed, flush);
                let op = Op::WriteStream(packet.into());
                let (reply, applied) = serve_request(&mut machine, &tick(k), op, &tx, &rx, give_up);
                give_up = false;
                if applied && matches!(reply, Some(Reply::Stream(Ok(())))) {
                    seen.accepted.extend(ns);
                }
                continue;
            }
            step => match plain_op(step) {
                Some(op) => op,
                None => continue,
            },
        };
        let _ = serve_request(&mut machine, &tick(k), op, &tx, &rx, give_up);
        give_up = false;
    }
    // The rest of the program runs out without a client.
    run_ticks(&mut machine, period, MAX_MACHINE_TICKS, &mut k, &mut seen);
    seen.executed
}

/// What the order check knows: the N numbers of accepted writes, the last executed one and
/// how many executed.
#[derive(Default)]
struct Observed {
    accepted: std::collections::BTreeSet<u32>,
    last: u32,
    executed: usize,
}

/// Tick `index` of a cycle of `period`.
fn tick_at(period: std::time::Duration, index: u64) -> ncchannel::runtime::Tick {
    ncchannel::runtime::Tick {
        index,
        period,
        time: period * u32::try_from(index).unwrap_or(u32::MAX),
        clock: ncchannel::runtime::Clock::Virtual,
    }
}

/// Run `n` ticks (at most up to `MAX_MACHINE_TICKS` in all): each within `MAX_TICK`, and every
/// numbered stream line executed was accepted, once, in order.
fn run_ticks(
    machine: &mut ncchannel::machine::Machine,
    period: std::time::Duration,
    n: u64,
    k: &mut u64,
    seen: &mut Observed,
) {
    use ncchannel::machine::{Op, Reply};
    use ncchannel::runtime::Cycle;
    for _ in 0..n {
        if *k >= MAX_MACHINE_TICKS {
            return;
        }
        *k += 1;
        let began = cpu_time::ThreadTime::now();
        let _ = machine.step(&tick_at(period, *k));
        let took = began.elapsed();
        assert!(took <= MAX_TICK, "tick {k} took {took:?}");
        if let Reply::Executed(executed) = machine.apply(&tick_at(period, *k), 1, Op::DrainExecuted)
        {
            for b in executed {
                let Some(n) = b.n else { continue };
                assert!(
                    seen.accepted.contains(&n),
                    "N{n} executed but its write was not accepted"
                );
                let last = seen.last;
                assert!(
                    n > last,
                    "N{n} executed after N{last}: out of order or twice"
                );
                seen.last = n;
                seen.executed += 1;
            }
        }
    }
}

/// Serve one request as the runtime does; returns its reply and whether it was applied.
/// A request whose caller gave up first must be neither applied nor answered.
fn serve_request(
    machine: &mut ncchannel::machine::Machine,
    tick: &ncchannel::runtime::Tick,
    op: ncchannel::machine::Op,
    tx: &crossbeam_channel::Sender<ncchannel::machine::Reply>,
    rx: &crossbeam_channel::Receiver<ncchannel::machine::Reply>,
    give_up: bool,
) -> (Option<ncchannel::machine::Reply>, bool) {
    use ncchannel::runtime::Cycle;
    let write = matches!(op, ncchannel::machine::Op::WriteStream(_));
    let before = machine.channels()[0].report().stream_fill;
    let (req, caller) = ncchannel::machine::Request::new(1, op, tx.clone());
    let gave_up = give_up && caller.take();
    machine.serve(req, tick);
    let reply = rx.try_recv().ok();
    assert!(rx.try_recv().is_err(), "a request answered twice");
    if gave_up {
        assert!(reply.is_none(), "answered after its caller gave up");
        if write {
            assert_eq!(
                machine.channels()[0].report().stream_fill,
                before,
                "a write applied after its caller gave up"
            );
        }
        return (None, false);
    }
    assert!(reply.is_some(), "a request not answered");
    (reply, true)
}
