//! `ncchannel run` and the no-argument demo: one program on one channel, optionally fed
//! through the stream interface by the built-in feeder, in virtual or real time.

use std::collections::BTreeMap;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use crate::channel::Finish;
use crate::feeder::Feeder;
use crate::machine::SearchTarget;
use crate::machine::{Machine, Op, Reply, StopWhen, TraceOp};
use crate::report::event::EventLog;
use crate::report::summary::{
    CycleReport, ErrorReport, FilesReport, Outcome, Report, StreamReport, TechnoReport,
};
use crate::runtime::{Clock, RunEnd, Runtime, Tick};
use crate::source::loader::Loader;
use crate::source::stream::MAX_PROGRAM_STREAM_INPUT_SIZE;

use super::exit;

/// Largest file the built-in feeder and `ncchannel stream` read: a soak file, not an accident.
pub(crate) const MAX_STREAM_FILE_BYTES: u64 = 1 << 30;
/// Points `--plot` keeps at most (the trace decimates beyond).
const PLOT_SAMPLES: usize = 20_000;

#[derive(Debug, Clone, clap::Args)]
pub struct RunArgs {
    /// Program to start: a name found through the channel's search paths, or a file path
    /// (with a `/`, or absolute), whose folder is then searched first for it and its
    /// subroutines. Default: the channel's streaming program when --stream is given.
    pub program: Option<String>,
    /// Start-up list: this, else $NCCHANNEL_PARAMS, else ./params/startup.lis, else the set
    /// built into the binary (`ncchannel init DIR` writes it out to edit).
    #[arg(long, env = "NCCHANNEL_PARAMS", default_value = "params/startup.lis")]
    pub params: PathBuf,
    /// Channel number, 1-based.
    #[arg(long, default_value_t = 1)]
    pub channel: u32,
    /// Feed this file through the stream interface.
    #[arg(long)]
    pub stream: Option<PathBuf>,
    /// Largest packet the feeder writes, bytes (1..=992).
    #[arg(value_parser = packet_bytes, long, default_value_t = MAX_PROGRAM_STREAM_INPUT_SIZE)]
    pub packet: usize,
    /// One write attempt every this many ticks.
    #[arg(long, default_value_t = 1)]
    pub every: u64,
    /// Send the stream file's bytes as they are (no line handling), for error tests.
    #[arg(long)]
    pub raw: bool,
    /// Run at the cycle period in wall-clock time instead of virtual time.
    #[arg(long)]
    pub(crate) realtime: bool,
    /// The real-time mode of the runtime thread (with --realtime; over runtime.toml's
    /// `[realtime]`).
    #[command(flatten)]
    pub(crate) rt: crate::runtime::realtime::RealtimeArgs,
    /// Stop after this many ticks (exit code 3).
    #[arg(long)]
    pub max_ticks: Option<u64>,
    /// Block search target: n:<N>, count:<K> or offset:<BYTES>.
    #[arg(long)]
    pub search: Option<SearchTarget>,
    /// Block-skip mask: bit n set skips blocks marked `/n` (`/` is `/1`), so 2 skips `/`
    /// and `/1`, 0x6 also `/2`. Decimal or 0x hex.
    #[arg(long, value_parser = parse_skip_mask, default_value = "0")]
    pub(crate) skip_mask: u16,
    /// Event log (JSON Lines): a file, or - for standard output.
    #[arg(long)]
    pub events: Option<String>,
    /// Write the report JSON here (- for standard output).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Draw the tool path at 1:1 (working plane and two side views) and the path velocity,
    /// acceleration and jerk, interrupts marked: SVG for FILE.svg (or - for standard output),
    /// PNG for FILE.png.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Write the interpolated motion to this CSV file (- for standard output): time, axis
    /// positions, path velocity, acceleration and jerk.
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// One CSV row every this many ticks.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub(crate) trace_every: u64,
}

impl RunArgs {
    /// The demo of `cargo run --release`: nc/demo.nc streamed into the streaming program.
    pub fn demo() -> Self {
        RunArgs {
            program: None,
            params: PathBuf::from("params/startup.lis"),
            channel: 1,
            stream: Some(PathBuf::from("nc/demo.nc")),
            packet: MAX_PROGRAM_STREAM_INPUT_SIZE,
            // A client offering a packet every 250 ms, as a PLC task might: the demo meets
            // a full buffer a few times instead of on every tick.
            every: 250,
            raw: false,
            realtime: false,
            rt: crate::runtime::realtime::RealtimeArgs::default(),
            max_ticks: None,
            search: None,
            skip_mask: 0,
            events: None,
            report: None,
            plot: None,
            trace: None,
            trace_every: 1,
        }
    }
}

/// `--skip-mask`: decimal or `0x` hex, 0..=0xFFFF.
fn parse_skip_mask(s: &str) -> Result<u16, String> {
    let r = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => u16::from_str_radix(h, 16),
        None => s.parse::<u16>(),
    };
    r.map_err(|_| format!("'{s}' is not a mask from 0 to 65535 (decimal or 0x hex)"))
}

/// Where the files the arguments name are read from (`params::shipped::locate`): the start-up
/// list, the --stream file and a PROGRAM path, each from the current folder or, for the
/// shipped names outside a clone, the set built into the binary. A PROGRAM that is a file of
/// the current folder is taken as a path (`run far.nc` runs ./far.nc); one written as a path
/// that exists nowhere is a usage error, before any channel starts.
fn locate_files(args: &mut RunArgs) -> Result<(), String> {
    use crate::params::shipped::locate;
    args.params = locate(&args.params).map_err(|e| e.to_string())?;
    if let Some(s) = &args.stream {
        args.stream = Some(locate(s).map_err(|e| e.to_string())?);
    }
    if let Some(p) = &args.program {
        args.program = Some(locate_program(p)?);
    }
    Ok(())
}

/// A PROGRAM argument as `run` and `serve --start` take it: a file of the current folder is
/// taken as a path (`far.nc` → `./far.nc`); one written as a path is looked up (in the
/// current folder, else the set built into the binary) and must exist; a name is kept for the
/// channel's search paths.
pub(crate) fn locate_program(p: &str) -> Result<String, String> {
    let path = Path::new(p);
    let as_path = program_path(p).is_some();
    if !(as_path || path.is_file()) {
        return Ok(p.to_string());
    }
    let found = crate::params::shipped::locate(path).map_err(|e| e.to_string())?;
    if !found.is_file() {
        return Err(format!("{p}: no such program file"));
    }
    let shown = if found.is_absolute() || as_path {
        found
    } else {
        Path::new(".").join(found)
    };
    Ok(shown.to_string_lossy().into_owned())
}

/// The name channel `ch` (0-based) starts `program` by: a path's folder goes first into the
/// channel's search paths and the program is started by its file name; a name is kept.
pub(crate) fn program_by_path(
    config: &mut crate::params::Config,
    ch: usize,
    program: &str,
    origin: &str,
) -> String {
    match program_path(program) {
        Some((dir, name)) => {
            search_first(config, ch, dir, origin);
            name
        }
        None => program.to_string(),
    }
}

/// A PROGRAM given by name must be found through the channel's search paths (or be its
/// streaming program): otherwise a usage error (exit 2) names the folders searched, instead
/// of a channel error with a summary of zeros.
pub(crate) fn program_exists(
    channels: &[crate::channel::Channel],
    channel: u32,
    program: &str,
) -> Result<(), String> {
    let Some(c) = channels.get((channel as usize).wrapping_sub(1)) else {
        return Ok(());
    };
    let Err(dirs) = c.find_program(program) else {
        return Ok(());
    };
    Err(format!(
        "program {program} not found in the current folder nor in channel {channel}'s search paths ({})",
        dirs.join(", ")
    ))
}

/// A program argument that is a file path rather than a program name: it holds a path
/// separator or is absolute. Its folder goes first into the channel's search paths (main
/// programs and subroutines), and the program is started by its file name.
fn program_path(program: &str) -> Option<(PathBuf, String)> {
    let p = Path::new(program);
    if !(p.is_absolute() || program.contains('/') || program.contains('\\')) {
        return None;
    }
    let name = p.file_name()?.to_str()?.to_string();
    let dir = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Some((dir, name))
}

/// Put `dir` first into channel `ch`'s search paths, for main programs and subroutines.
pub(crate) fn search_first(
    config: &mut crate::params::Config,
    ch: usize,
    dir: PathBuf,
    origin: &str,
) {
    use crate::params::search_path::{SearchPath, MAIN_PROGRAMS, SUBROUTINES};
    if let Some(c) = config.channels.get_mut(ch) {
        c.search_paths.insert(
            0,
            SearchPath {
                dir,
                kinds: MAIN_PROGRAMS | SUBROUTINES,
                priority: 0,
                file: PathBuf::from(origin),
                line: 0,
            },
        );
    }
}

/// Read and check the parameter lists (diagnostics on stderr) and build the channels: what
/// every command that runs channels does first.
pub(crate) fn load_channels(
    params: &Path,
    events: bool,
    loader: &Loader,
) -> Result<(crate::params::Config, Vec<crate::channel::Channel>), String> {
    let config = load_config(params)?;
    let channels = crate::setup::channels(&config, events, loader).map_err(|e| e.to_string())?;
    Ok((config, channels))
}

/// Read and check the parameter lists (diagnostics on stderr).
pub(crate) fn load_config(params: &Path) -> Result<crate::params::Config, String> {
    let config = match crate::params::load(params) {
        Ok(c) => c,
        Err(e) => {
            for d in e.diagnostics() {
                eprintln!("{}", d.render());
            }
            return Err(format!("parameter lists in {} refused", params.display()));
        }
    };
    for w in &config.warnings {
        eprintln!("{}", w.render());
    }
    Ok(config)
}

fn usage(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("ncchannel run: {msg}");
    ExitCode::from(exit::USAGE)
}

/// The output options that name standard output (`-`): at most one may, and then the human
/// summary goes to stderr so standard output holds that output alone.
fn stdout_outputs(args: &RunArgs) -> Vec<&'static str> {
    let dash = |p: Option<&Path>| p.is_some_and(crate::destination::is_stdout);
    [
        ("--events", dash(args.events.as_deref().map(Path::new))),
        ("--report", dash(args.report.as_deref())),
        ("--plot", dash(args.plot.as_deref())),
        ("--trace", dash(args.trace.as_deref())),
    ]
    .into_iter()
    .filter_map(|(name, on)| on.then_some(name))
    .collect()
}

/// The options checked before the run: the real-time mode's only with `--realtime`, a picture
/// format the extension names, and at most one output on standard output.
fn check_outputs(args: &RunArgs) -> Result<(), String> {
    if args.rt.any() && !args.realtime {
        return Err("the --rt-… options of the real-time mode need --realtime".into());
    }
    if let Some(p) = &args.plot {
        crate::report::picture::Format::of(p).map_err(|e| format!("--plot {e}"))?;
    }
    let on_stdout = stdout_outputs(args);
    if on_stdout.len() > 1 {
        return Err(format!(
            "{} all name standard output (-); at most one may",
            on_stdout.join(", ")
        ));
    }
    Ok(())
}

pub fn execute(mut args: RunArgs) -> ExitCode {
    if let Err(msg) = check_outputs(&args).and_then(|()| locate_files(&mut args)) {
        return usage(msg);
    }
    let mut config = match load_config(&args.params) {
        Ok(c) => c,
        Err(msg) => return usage(msg),
    };
    let by_path = args.program.as_deref().and_then(program_path);
    if let Some((dir, _)) = &by_path {
        search_first(
            &mut config,
            (args.channel as usize).wrapping_sub(1),
            dir.clone(),
            "ncchannel run PROGRAM",
        );
    }
    // The program loader of this run: it reads large program files and frees large texts off
    // the tick, for the channels built here.
    let loader = Loader::start();
    let channels = match crate::setup::channels(&config, args.events.is_some(), &loader) {
        Ok(c) => c,
        Err(e) => return usage(e),
    };
    let nch = channels.len();
    let Some(ch_config) = config.channels.get((args.channel as usize).wrapping_sub(1)) else {
        return usage(format!(
            "channel {} does not exist (the start-up list has {nch})",
            args.channel
        ));
    };
    let program = match program_name(&args, by_path.as_ref(), ch_config) {
        Ok(p) => p,
        Err(msg) => return usage(msg),
    };
    if let Err(msg) = program_exists(&channels, args.channel, &program) {
        return usage(msg);
    }
    let feeder = match open_feeder(&args) {
        Ok(f) => f,
        Err(msg) => return usage(msg),
    };
    let log = match &args.events {
        None => EventLog::disabled(),
        Some(t) => match EventLog::open(t) {
            Ok(l) => l,
            Err(e) => return usage(format!("--events {t}: {e}")),
        },
    };
    let period = Duration::from_micros(config.runtime.cycle_period_us);
    let mut machine = Machine::new(channels, log, StopWhen::ProgramsFinished);
    if let Err(msg) = enable_traces(&mut machine, &args, period) {
        return usage(msg);
    }
    if let Some(f) = feeder {
        machine.attach_feeder(args.channel, f);
    }
    if let Err(msg) = attach_plcs(&mut machine, config.runtime.plc.as_ref()) {
        return usage(msg);
    }
    let (rt, summary) = match run_program(machine, &args, &program, period, &config) {
        Ok(r) => r,
        Err(code) => return code,
    };
    let ticks = rt.ticks();
    let end_time = rt.time();
    let time_s = end_time.as_secs_f64();
    let (mut machine, stats) = rt.into_inner();
    let finish = machine
        .finishes()
        .get(args.channel as usize - 1)
        .copied()
        .flatten();
    let outcome = outcome_of(summary.as_ref().map(|s| s.end), finish);
    finish_trace(&mut machine, args.channel, ticks, end_time, period);
    let report = build_report(
        &machine,
        &args,
        outcome,
        (ticks, time_s),
        summary.as_ref(),
        &stats,
        period,
    );
    let c = machine.channels()[args.channel as usize - 1].report();
    let mut written = true;
    if let (Some(p), Some(trace)) = (&args.plot, &c.trace) {
        let title = format!("ncchannel run {program}");
        if let Err(e) = crate::report::plot::write(p, trace, &title) {
            eprintln!("ncchannel run: --plot {e}");
            written = false;
        }
    }
    written &= write_outputs(&mut machine, &args, &report);
    if !written {
        // An output the user asked for is missing: no run that leaves one out is a success.
        return ExitCode::from(exit::USAGE);
    }
    ExitCode::from(match outcome {
        Outcome::Ended => exit::OK,
        Outcome::Error => exit::CHANNEL_ERROR,
        Outcome::MaxTicks => exit::MAX_TICKS,
        Outcome::Stopped => exit::STOPPED,
    })
}

/// Start the program on the channel and run until it finishes, `--max-ticks` or a signal.
fn run_program(
    mut machine: Machine,
    args: &RunArgs,
    program: &str,
    period: Duration,
    config: &crate::params::Config,
) -> Result<(Runtime<Machine>, Option<crate::runtime::RunSummary>), ExitCode> {
    let tick0 = Tick::first(period, Clock::Virtual);
    let ch = args.channel;
    machine.apply(&tick0, ch, Op::SearchAt(args.search));
    machine.apply(&tick0, ch, Op::SkipMask(args.skip_mask));
    let start_failed = match machine.apply(&tick0, ch, Op::Start(program.to_string())) {
        Reply::Command(Err(e)) => {
            eprintln!("ncchannel run: {e}");
            true
        }
        _ => false,
    };
    let clock = if args.realtime {
        Clock::RealTime
    } else {
        Clock::Virtual
    };
    let (mut rt, _requests) = Runtime::new(machine, period, clock);
    if args.realtime {
        match super::signal::StopSignal::install() {
            Ok(sig) => rt.stop_on(sig.flag()),
            Err(e) => eprintln!("ncchannel run: cannot handle SIGINT/SIGTERM: {e}"),
        }
    }
    let summary = if start_failed {
        None
    } else {
        // runtime.toml's `[realtime]` applies to real-time runs only: a virtual-time run at a
        // real-time priority would hold its CPU for the whole run.
        if args.realtime {
            let mode = args.rt.over(&config.runtime.realtime);
            super::enter_realtime(&mode, "run", |m| eprintln!("{m}"))?;
        }
        Some(rt.run(args.max_ticks))
    };
    Ok((rt, summary))
}

/// `--trace`: the CSV file's last rows written out, at the tick the run ended.
fn finish_trace(
    machine: &mut Machine,
    channel: u32,
    ticks: u64,
    end_time: Duration,
    period: Duration,
) {
    let end = Tick {
        index: ticks,
        period,
        time: end_time,
        clock: Clock::Virtual,
    };
    if let Reply::Trace(Err(e)) = machine.apply(&end, channel, Op::Trace(TraceOp::FinishCsv)) {
        eprintln!("ncchannel run: --trace: {e}");
    }
}

/// `--plot` and `--trace`: the motion trace of the channel that runs the program.
fn enable_traces(machine: &mut Machine, args: &RunArgs, period: Duration) -> Result<(), String> {
    let tick0 = Tick::first(period, Clock::Virtual);
    let ch = args.channel;
    if args.plot.is_some() {
        let op = Op::Trace(TraceOp::Plot {
            max_samples: PLOT_SAMPLES,
        });
        machine.apply(&tick0, ch, op);
    }
    if let Some(p) = &args.trace {
        let op = Op::Trace(TraceOp::Csv {
            path: p.clone(),
            every: args.trace_every,
        });
        if let Reply::Trace(Err(e)) = machine.apply(&tick0, ch, op) {
            return Err(format!("--trace {e}"));
        }
    }
    Ok(())
}

/// How the run ended, from the channel's finish and the runtime's end.
fn outcome_of(end: Option<RunEnd>, finish: Option<Finish>) -> Outcome {
    match (end, finish) {
        (_, Some(Finish::Ended)) => Outcome::Ended,
        (_, Some(Finish::Error)) => Outcome::Error,
        (Some(RunEnd::MaxTicks), _) => Outcome::MaxTicks,
        (Some(RunEnd::StopRequested), _) => Outcome::Stopped,
        _ => Outcome::Error,
    }
}

/// The program to start: a path's file name, the named program, or (with `--stream`) the
/// channel's streaming program.
fn program_name(
    args: &RunArgs,
    by_path: Option<&(PathBuf, String)>,
    ch_config: &crate::params::ChannelConfig,
) -> Result<String, String> {
    match (by_path, &args.program, &args.stream) {
        (Some((_, name)), _, _) => Ok(name.clone()),
        (None, Some(p), _) => Ok(p.clone()),
        (None, None, Some(_)) => ch_config.streaming_prog_file.clone().ok_or_else(|| {
            format!(
                "--stream needs streaming_prog_file in {}",
                ch_config.list_path.display()
            )
        }),
        (None, None, None) => Err("name a PROGRAM or give --stream FILE".to_string()),
    }
}

/// The built-in feeder over `--stream FILE`, if given.
fn open_feeder(args: &RunArgs) -> Result<Option<Feeder>, String> {
    let Some(f) = &args.stream else {
        return Ok(None);
    };
    let text = crate::bounded::read_file(f, MAX_STREAM_FILE_BYTES)
        .map_err(|e| format!("{}: {e}", f.display()))?;
    Feeder::new(text, args.packet, args.every, args.raw)
        .map(Some)
        .map_err(|e| format!("{}: {e}", f.display()))
}

/// The run's report: outcome, times, the channel's position, stream, errors, cycle and files.
fn build_report(
    machine: &Machine,
    args: &RunArgs,
    outcome: Outcome,
    (ticks, time_s): (u64, f64),
    summary: Option<&crate::runtime::RunSummary>,
    stats: &crate::vocab::stats::CycleStats,
    period: Duration,
) -> Report {
    let c = machine.channels()[args.channel as usize - 1].report();
    Report {
        outcome,
        ticks,
        time_s,
        wall_s: summary.map_or(0.0, |s| s.wall.as_secs_f64()),
        blocks: c.stats.blocks,
        position: c
            .named_positions
            .into_iter()
            .map(|(a, v)| (a.to_string(), v))
            .collect::<BTreeMap<_, _>>(),
        stream: StreamReport::from(&c.stream),
        interrupts: c.stats.interrupts,
        errors: c
            .errors
            .iter()
            .map(|e| ErrorReport {
                code: e.code,
                msg: e.msg.clone(),
                prog: e.prog.clone(),
                line: e.line,
            })
            .collect(),
        cycle: CycleReport::new(period, stats),
        files: FilesReport {
            opens: c.store.opens,
            bytes_read: c.store.bytes_read,
            cache_hits: c.cache.hits,
            latency_s: c.store.latency.as_secs_f64(),
        },
        techno: TechnoReport {
            output: c.techno.output,
            acknowledged: c.techno.acknowledged,
            waited_s: c.techno.waited.as_secs_f64(),
            dropped_by_reset: c.techno.dropped_by_reset,
        },
    }
}

/// The event log written out, the report file and the human summary; false when the report
/// file could not be written.
fn write_outputs(machine: &mut Machine, args: &RunArgs, report: &Report) -> bool {
    // A reader of `--events -` or of the summary that went away (`| head`) is no error of
    // the run (`super::out`).
    match machine.finish_log() {
        Err(e) if !super::out::reader_gone(&e) => eprintln!("ncchannel run: event log: {e}"),
        _ => {}
    }
    let mut written = true;
    if let Some(p) = &args.report {
        match report.write_file(p) {
            Err(e) if !super::out::reader_gone(&e) => {
                eprintln!("ncchannel run: --report {}: {e}", p.display());
                written = false;
            }
            _ => {}
        }
    }
    // The summary goes to stderr when an output goes to stdout, so a pipe gets that alone.
    let to_stderr = !stdout_outputs(args).is_empty();
    let printed = if to_stderr {
        report.print_human(&mut std::io::stderr())
    } else {
        report.print_human(&mut std::io::stdout())
    };
    let plc = plc_line(machine, args.channel);
    let printed = printed.and_then(|()| match &plc {
        None => Ok(()),
        Some(line) if to_stderr => writeln!(std::io::stderr(), "{line}"),
        Some(line) => writeln!(std::io::stdout(), "{line}"),
    });
    match printed {
        Err(e) if !super::out::reader_gone(&e) => eprintln!("ncchannel run: summary: {e}"),
        _ => {}
    }
    written
}

/// runtime.toml's `[plc]`: a simulated PLC for each channel it names (default every channel)
/// of the machine; an error names a channel the machine does not have.
pub(crate) fn attach_plcs(
    machine: &mut Machine,
    settings: Option<&crate::params::runtime::PlcSettings>,
) -> Result<(), String> {
    let Some(s) = settings else { return Ok(()) };
    let n = machine.channels().len() as u32;
    let numbers: Vec<u32> = s.channels.clone().unwrap_or_else(|| (1..=n).collect());
    for number in numbers {
        if number == 0 || number > n {
            return Err(format!(
                "runtime.toml [plc] channels: channel {number} does not exist (the start-up list has {n})"
            ));
        }
        machine.attach_plc(crate::machine::plc::SimulatedPlc::new(
            number,
            crate::soak::scenario::plc_config(s, s.seed),
        ));
    }
    Ok(())
}

/// The summary's line of the simulated PLC of `channel`, if one played.
fn plc_line(machine: &Machine, channel: u32) -> Option<String> {
    let p = machine.plcs().iter().find(|p| p.channel() == channel)?;
    let (c, st) = (p.config(), p.stats());
    let delay = |[a, b]: [u64; 2]| {
        if a == b {
            format!("{a} ms")
        } else {
            format!("{a}..{b} ms")
        }
    };
    let mut line = format!(
        "plc:        simulated, delay {}, {} acknowledged",
        delay(c.delay_ms),
        st.acknowledged
    );
    for (kind, n, d) in &c.overrides {
        let n = n.map_or(String::new(), |n| n.to_string());
        line.push_str(&format!(", {}{n} {}", kind.letter(), delay(*d)));
    }
    if st.late > 0 {
        line.push_str(&format!(", {} late by {} ms", st.late, c.late_ms));
    }
    if let Some(n) = c.stop_after {
        line.push_str(&format!(
            ", stops after {n}: {} left unanswered",
            st.unanswered
        ));
    }
    Some(line)
}

/// `--packet`: 1..=992 bytes (MAX_PROGRAM_STREAM_INPUT_SIZE, ISG FCT-C19 Data streaming);
/// a larger packet would be refused by every write, so it is refused here, up front.
pub fn packet_bytes(s: &str) -> Result<usize, String> {
    let max = MAX_PROGRAM_STREAM_INPUT_SIZE;
    match s.parse::<usize>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        Ok(n) => Err(format!("{n} is not in 1..={max}")),
        Err(e) => Err(e.to_string()),
    }
}
