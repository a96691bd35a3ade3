//! `ncchannel receive`: split a transfer into programs by start/end markers and file them in
//! the program directory.
//!
//! Standard output carries the receive log (one line per program filed or dropped) and the
//! summary; operator messages (no start marker, cut-off transfer, kept files, refused names)
//! go to standard error. Exit 0 when at least one program was filed and none was cut off or
//! lost, 1 when no program was filed, a transfer broke inside a program or the disk refused
//! one, 2 for bad usage, 130 after a second stop signal.

use std::fs::File;
use std::io::{self, Write};
use std::net::{SocketAddr, TcpListener};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use super::receive_stop;

use crate::dnc::{
    self, Anchor, Disposition, Markers, NameKind, NameTemplate, ProgramWriter, ReceivedProgram,
    Splitter, TransferEnd, TransferReport, WriterConfig,
};

use super::exit;
// Operator messages never panic on a closed stderr (`eprintln!` would, mid-transfer).
use super::out::{log, say};

#[derive(Debug, clap::Args)]
pub struct ReceiveArgs {
    /// Input file, or `-` for standard input (the default without --listen).
    #[arg(conflicts_with = "listen")]
    pub input: Option<PathBuf>,
    /// Program start marker (up to 3). Matched anywhere in a line, case-sensitive.
    #[arg(long = "start", value_name = "S")]
    pub start: Vec<String>,
    /// Program end marker (up to 3). Matched anywhere in a line, case-sensitive.
    #[arg(long = "end", value_name = "S")]
    pub end: Vec<String>,
    /// Program directory (default: the channel's first program path).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Take transfers on a TCP port, one connection per transfer. `PORT` alone binds loopback.
    #[arg(long, value_name = "ADDR:PORT")]
    pub listen: Option<String>,
    /// With --listen: accept a non-loopback ADDR (any host that reaches it can file programs),
    /// as `serve --allow-non-loopback`.
    #[arg(long, requires = "listen")]
    pub allow_non_loopback: bool,
    /// With --listen: stop after this many transfers.
    #[arg(long, value_name = "N")]
    pub max_transfers: Option<usize>,
    /// With --listen: end a connection silent for this many seconds (a broken transfer).
    #[arg(long, value_name = "SECONDS", default_value_t = DEFAULT_IDLE_TIMEOUT_S)]
    pub idle_timeout: f64,
    /// Bytes one transfer may carry; beyond, the transfer ends and the program in progress is
    /// cut off (default with --listen: 256 MiB; unbounded for a file or standard input).
    #[arg(long, value_name = "BYTES")]
    pub(crate) max_transfer_bytes: Option<u64>,
    /// With --listen: transfers taken at the same time (a silent or slow sender holds one).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_CONCURRENT,
          value_parser = clap::value_parser!(u16).range(1..=64))]
    pub(crate) max_concurrent: u16,
    /// Programs one transfer may deliver; the next is dropped and the transfer ends
    /// (default with --listen: 1000; unbounded for a file or standard input).
    #[arg(long, value_name = "N")]
    pub(crate) max_programs: Option<usize>,
    /// With --listen: after SIGINT/SIGTERM, the transfers in progress may run this many seconds
    /// more; then they are cut (a second signal cuts them at once).
    #[arg(long, value_name = "SECONDS", default_value_t = dnc::listen::DEFAULT_GRACE.as_secs_f64())]
    pub(crate) stop_grace: f64,
    /// Replace existing program files (default: keep them and drop the received program).
    #[arg(long)]
    pub overwrite: bool,
    /// Keep a program cut off by the end of the transfer as `<name>.partial`.
    #[arg(long)]
    pub keep_partial: bool,
    /// Markers count only at the very beginning of a line.
    #[arg(long)]
    pub at_line_start: bool,
    /// Names for programs whose data names none: `{n:W}` is the number in W digits,
    /// zero-padded; without `:W`, as in the default, in 3 (`received_001.nc`).
    #[arg(long, value_name = "TEMPLATE", default_value = "received_{n}.nc")]
    pub(crate) name_template: String,
    /// Start-up list whose channel decides the default program directory: this, else
    /// $NCCHANNEL_PARAMS, else ./params/startup.lis; without any, programs go to the current
    /// folder.
    #[arg(long, env = "NCCHANNEL_PARAMS")]
    pub params: Option<PathBuf>,
    /// Channel (1-based) whose first program path is the default program directory.
    #[arg(long, default_value_t = 1)]
    pub channel: u32,
}

/// `--listen` defaults: a silent sender frees the port after 30 s; one transfer carries at
/// most 256 MiB and 1000 programs (docs/ads-limits.md, "receive --listen").
pub(crate) const DEFAULT_IDLE_TIMEOUT_S: f64 = 30.0;
pub(crate) const DEFAULT_MAX_TRANSFER_BYTES: u64 = 256 << 20;
pub(crate) const DEFAULT_MAX_PROGRAMS: usize = 1000;
pub(crate) const DEFAULT_MAX_CONCURRENT: u16 = 4;

/// Where programs go without `--out`: the channel's first main-program search path, from the
/// parameter lists, so received programs are ready to run.
/// The start-up list whose program folder receives programs: the one named, else
/// ./params/startup.lis when it exists. Not the set built into the binary: received programs
/// belong to the user, not to a cache folder.
fn installation_list(given: Option<&Path>) -> Option<PathBuf> {
    match given {
        Some(p) => Some(p.to_path_buf()),
        None => {
            let p = Path::new(crate::params::shipped::DEFAULT_STARTUP_LIST);
            p.exists().then(|| p.to_path_buf())
        }
    }
}

pub(crate) fn default_out_dir(params: &Path, channel: u32) -> Result<PathBuf, String> {
    let config = crate::params::load(params).map_err(|e| {
        for d in e.diagnostics() {
            say(format_args!("{}", d.render()));
        }
        format!(
            "no --out, and the parameter lists in {} are refused",
            params.display()
        )
    })?;
    let ch = config
        .channels
        .get((channel as usize).wrapping_sub(1))
        .ok_or_else(|| format!("no --out, and channel {channel} does not exist"))?;
    let dir = ch.main_program_paths().next().map(Path::to_path_buf);
    dir.ok_or_else(|| format!("no --out, and channel {channel} has no main-program path"))
}

pub fn execute(args: ReceiveArgs) -> ExitCode {
    match run(args) {
        Ok(code) => ExitCode::from(code),
        Err(Failure::Usage(msg)) => {
            say(format_args!("ncchannel receive: {msg}"));
            ExitCode::from(exit::USAGE)
        }
        Err(Failure::Io(msg)) => {
            say(format_args!("ncchannel receive: {msg}"));
            ExitCode::from(exit::CHANNEL_ERROR)
        }
    }
}

enum Failure {
    Usage(String),
    Io(String),
}

impl From<dnc::DncError> for Failure {
    fn from(e: dnc::DncError) -> Self {
        match e {
            dnc::DncError::Io { .. } | dnc::DncError::ProgramLost { .. } => {
                Failure::Io(e.to_string())
            }
            _ => Failure::Usage(e.to_string()),
        }
    }
}

fn run(args: ReceiveArgs) -> Result<u8, Failure> {
    let (markers, template, limits) = settings(&args)?;
    let grace = seconds("--stop-grace", args.stop_grace, true)?;
    let out = match args.out.clone() {
        Some(o) => o,
        None => match installation_list(args.params.as_deref()) {
            Some(params) => default_out_dir(&params, args.channel).map_err(Failure::Usage)?,
            None => PathBuf::from("."),
        },
    };
    remove_stale_temp_files(&out);
    let mut cfg = WriterConfig::new(&out);
    cfg.overwrite = args.overwrite;
    cfg.keep_partial = args.keep_partial;
    cfg.template = template;
    let mut writer = ProgramWriter::new(cfg.clone()).with_log(log_line);
    let mut splitter = Splitter::new(markers.clone());

    let mut total = Totals::default();
    let mut stopped_at_once = false;
    if let Some(addr) = &args.listen {
        let listen = dnc::Listener {
            numbers: writer.numbers(),
            program_log: Some(log_line),
            grace,
            ..dnc::Listener::new(markers.clone(), cfg.clone(), limits)
        };
        stopped_at_once = serve(&args, addr, &listen, &mut total)? == dnc::StopLevel::Now;
        // A transfer thread left behind at a cut may still hold a temporary file.
        if let Err(e) = dnc::temp_files::remove_own(&out) {
            say(format_args!("ncchannel receive: {}: {e}", out.display()));
        }
    } else {
        let r = receive_input(&args, &limits, &mut splitter, &mut writer)?;
        log_end(Ok(&r));
        total.add(&r);
    }
    total.print(&out);
    Ok(if stopped_at_once {
        exit::SECOND_SIGNAL
    } else if total.filed > 0 && total.cut_off == 0 && total.refused == 0 && total.lost == 0 {
        exit::OK
    } else {
        exit::CHANNEL_ERROR
    })
}

/// Temporary files of receivers that no longer run (a second signal, SIGKILL, a power loss)
/// are removed before anything is received; a failure to do so is only reported.
fn remove_stale_temp_files(out: &Path) {
    match dnc::temp_files::remove_stale(out) {
        Ok(0) => {}
        Ok(n) => say(format_args!(
            "ncchannel receive: removed {n} temporary file(s) a stopped receiver left in {}",
            out.display()
        )),
        Err(e) => say(format_args!(
            "ncchannel receive: {}: cannot remove stale temporary files: {e}",
            out.display()
        )),
    }
}

/// A time option in seconds (`zero_ok`: 0 is allowed).
fn seconds(option: &str, s: f64, zero_ok: bool) -> Result<Duration, Failure> {
    if s.is_finite() && (s > 0.0 || (zero_ok && s == 0.0)) && s < 1e9 {
        Ok(Duration::from_secs_f64(s))
    } else {
        Err(Failure::Usage(format!("{option} {s}: not a positive time")))
    }
}

/// Step 1 of `run`: the arguments checked and turned into markers, name template and
/// transfer limits (a listening port gets bounded transfers by default).
fn settings(args: &ReceiveArgs) -> Result<(Markers, NameTemplate, dnc::TransferLimits), Failure> {
    let anchor = if args.at_line_start {
        Anchor::LineStart
    } else {
        Anchor::Anywhere
    };
    if args.listen.is_none() && args.max_transfers.is_some() {
        return Err(Failure::Usage("--max-transfers needs --listen".to_string()));
    }
    let markers = Markers::new(&args.start, &args.end, anchor)?;
    let template = NameTemplate::parse(&args.name_template)?;
    let idle = seconds("--idle-timeout", args.idle_timeout, false)?;
    let listening = args.listen.is_some();
    let limits = dnc::TransferLimits {
        idle_timeout: Some(idle),
        max_bytes: args
            .max_transfer_bytes
            .or(listening.then_some(DEFAULT_MAX_TRANSFER_BYTES)),
        max_programs: args
            .max_programs
            .or(listening.then_some(DEFAULT_MAX_PROGRAMS)),
    };
    Ok((markers, template, limits))
}

/// Step 2 without --listen: one transfer from the input file or standard input.
fn receive_input(
    args: &ReceiveArgs,
    limits: &dnc::TransferLimits,
    splitter: &mut Splitter,
    writer: &mut ProgramWriter,
) -> Result<TransferReport, Failure> {
    Ok(match args.input.as_deref() {
        None => dnc::receive_limited(io::stdin().lock(), limits, splitter, writer)?,
        Some(p) if p == Path::new("-") => {
            dnc::receive_limited(io::stdin().lock(), limits, splitter, writer)?
        }
        Some(p) => {
            let f = File::open(p).map_err(|e| Failure::Io(format!("{}: {e}", p.display())))?;
            dnc::receive_limited(f, limits, splitter, writer)?
        }
    })
}

/// Step 2 with --listen: accept transfers, each on its own thread (at most
/// --max-concurrent at once), until --max-transfers or a stop signal; then wait for the
/// transfers in progress (after a signal at most --stop-grace). Returns how far a stop was
/// asked for.
fn serve(
    args: &ReceiveArgs,
    addr: &str,
    listen: &dnc::Listener,
    total: &mut Totals,
) -> Result<dnc::StopLevel, Failure> {
    let addr = parse_listen(addr).map_err(Failure::Usage)?;
    if !addr.ip().is_loopback() {
        if !args.allow_non_loopback {
            return Err(Failure::Usage(format!(
                "refusing to listen on non-loopback address {addr} without --allow-non-loopback"
            )));
        }
        say(format_args!(
            "listening on non-loopback {addr}: any host that reaches it can file programs"
        ));
    }
    let listener =
        TcpListener::bind(addr).map_err(|e| Failure::Io(format!("listen on {addr}: {e}")))?;
    let local = listener
        .local_addr()
        .map_err(|e| Failure::Io(format!("listen on {addr}: {e}")))?;
    // SIGINT/SIGTERM: no new transfer, the ones in progress get the grace period; a second
    // signal cuts them at once.
    let stop = dnc::StopRequest::new();
    if let Err(e) = receive_stop::on_signals(stop.clone(), local, listen.grace) {
        return Err(Failure::Io(format!("stop signals: {e}")));
    }
    say(format_args!("listening on {local}"));
    let listen = dnc::Listener {
        max_transfers: args.max_transfers,
        max_concurrent: args.max_concurrent,
        ..listen.clone()
    };
    listen.serve(
        &listener,
        &stop,
        log_end,
        |r| settle(r, total),
        |e| log(format_args!("ncchannel receive: accept on {local}: {e}")),
    );
    Ok(stop.level())
}

/// Whatever a transfer came to: filed programs, or refused with its reason (a name the disk
/// refuses, a full disk); the port keeps serving the others.
/// Its lines were logged by [`log_end`] as it ended; this only counts it.
fn settle(r: Result<TransferReport, dnc::DncError>, total: &mut Totals) {
    match r {
        Ok(r) => total.add(&r),
        Err(_) => total.refused += 1,
    }
}

/// How a transfer ended, logged by the transfer's own thread as it ends: the line must not
/// wait for the accept loop, which sleeps in `accept` until the next sender connects.
fn log_end(r: Result<&TransferReport, &dnc::DncError>) {
    let r = match r {
        Ok(r) => r,
        Err(e) => return log(format_args!("ncchannel receive: transfer refused: {e}")),
    };
    let from = r.peer.map(|p| format!(" from {p}")).unwrap_or_default();
    if r.split.no_start_marker() {
        log(format_args!(
            "ncchannel receive: no start marker found in the transfer{from}: all {} bytes discarded",
            r.split.bytes_in
        ));
    }
    match &r.end {
        TransferEnd::Complete => {}
        TransferEnd::IdleTimeout => {
            log(format_args!("ncchannel receive: transfer{from} timed out"))
        }
        TransferEnd::Broken(e) => log(format_args!("ncchannel receive: transfer{from} broke: {e}")),
        TransferEnd::LimitReached(l) => log(format_args!(
            "ncchannel receive: transfer{from} ended at its limit ({l}); the rest was not read"
        )),
        TransferEnd::WriteFailed(e) => log(format_args!(
            "ncchannel receive: transfer{from} stopped: {e}"
        )),
    }
}

/// `PORT` → loopback, `ADDR:PORT` as given.
fn parse_listen(s: &str) -> Result<SocketAddr, String> {
    if let Ok(port) = s.parse::<u16>() {
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    s.parse::<SocketAddr>()
        .map_err(|_| format!("--listen {s}: expected ADDR:PORT or PORT"))
}

/// The receive log: one line per program, on standard output as it is filed.
fn log_line(p: &ReceivedProgram) {
    let what = match p.disposition {
        Disposition::Written => "received",
        Disposition::Replaced => "replaced",
        Disposition::KeptExisting => "kept existing",
        Disposition::CutOffDropped => "cut off, dropped",
        Disposition::CutOffKept => "cut off, kept",
        Disposition::NameUnusable => "not filed",
        Disposition::OverLimit => "over the limit, dropped",
        Disposition::WriteFailed => "lost",
    };
    let mut out = io::stdout().lock();
    let _ = writeln!(
        out,
        "{what} {} ({} bytes, lines {}-{})",
        p.path.display(),
        p.bytes,
        p.first_line,
        p.last_line
    );
    let _ = out.flush();
    // What became of the program, not what might have: a refused workpiece folder files the
    // program at the top under its own name, a refused program name numbers it.
    for name in &p.rejected_names {
        let what = match name.kind {
            NameKind::Program => "program name",
            NameKind::Workpiece => "workpiece folder name",
        };
        let outcome = if p.is_filed() {
            format!("filed as {} instead", p.path.display())
        } else {
            "not used".to_string()
        };
        log(format_args!(
            "ncchannel receive: {what} `{}` in lines {}-{} is not a plain name; {outcome}",
            name.text, p.first_line, p.last_line
        ));
    }
    match p.disposition {
        Disposition::KeptExisting => log(format_args!(
            "ncchannel receive: {} exists and was kept; the received program was dropped (use --overwrite)",
            p.path.display()
        )),
        Disposition::CutOffDropped => log(format_args!(
            "ncchannel receive: the transfer ended inside the program from line {}; it was dropped (--keep-partial keeps it)",
            p.first_line
        )),
        Disposition::NameUnusable => log(format_args!(
            "ncchannel receive: the program from line {} cannot be filed as {}: {}; it was dropped",
            p.first_line,
            p.path.display(),
            p.reason.as_deref().unwrap_or("name unusable")
        )),
        Disposition::OverLimit => log(format_args!(
            "ncchannel receive: the program from line {} was dropped: {}",
            p.first_line,
            p.reason.as_deref().unwrap_or("limit reached")
        )),
        Disposition::WriteFailed => log(format_args!(
            "ncchannel receive: {} (lines {}-{}) was lost: {}",
            p.path.display(),
            p.first_line,
            p.last_line,
            p.reason.as_deref().unwrap_or("the disk refused it")
        )),
        _ => {}
    }
}

#[derive(Default)]
struct Totals {
    transfers: usize,
    filed: usize,
    kept: usize,
    cut_off: usize,
    /// Transfers refused by an error of the receiver (nothing of them filed).
    refused: usize,
    /// Programs the disk refused (full, file too large).
    lost: usize,
    bytes: u64,
}

impl Totals {
    fn add(&mut self, r: &TransferReport) {
        self.transfers += 1;
        self.filed += r.filed();
        self.kept += r
            .programs
            .iter()
            .filter(|p| p.disposition == Disposition::KeptExisting)
            .count();
        self.lost += r
            .programs
            .iter()
            .filter(|p| p.disposition == Disposition::WriteFailed)
            .count();
        self.cut_off += r.split.cut_off;
        self.bytes += r.split.bytes_in;
    }

    fn print(&self, out: &Path) {
        let _ = writeln!(
            io::stdout().lock(),
            "{} program(s) filed in {} from {} transfer(s), {} bytes; {} kept existing, {} cut off, {} lost to write errors, {} transfer(s) refused",
            self.filed,
            out.display(),
            self.transfers,
            self.bytes,
            self.kept,
            self.cut_off,
            self.lost,
            self.refused
        );
    }
}
