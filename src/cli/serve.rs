//! `ncchannel serve`: the channels in real time behind an ADS server, for real clients.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use crate::ads::{AmsNetId, ServerConfig};
use crate::machine::remote::ChannelBackend;
use crate::machine::{Machine, Op, Reply, StopWhen};
use crate::report::event::{Backlog, EventLog};
use crate::runtime::{Clock, Runtime, Tick};
use crate::soak::external::{load_external, Supervised};
use crate::soak::scenario::Scenario;

use super::exit;
use super::out::say;

#[derive(Debug, Clone, clap::Args)]
pub struct ServeArgs {
    /// Start-up list: this, else $NCCHANNEL_PARAMS, else ./params/startup.lis, else the set
    /// built into the binary (`ncchannel init DIR` writes it out to edit).
    #[arg(long, env = "NCCHANNEL_PARAMS", default_value = "params/startup.lis")]
    pub params: PathBuf,
    /// Listen address (default: runtime.toml `ads.bind`, 127.0.0.1:48898). Port 0 picks one.
    #[arg(long)]
    pub bind: Option<SocketAddr>,
    /// Allow a non-loopback --bind (the server moves axes on request, without authentication).
    #[arg(long)]
    pub allow_non_loopback: bool,
    /// This device's AMS NetId (default: runtime.toml `ads.net_id`).
    #[arg(long)]
    pub net_id: Option<AmsNetId>,
    /// Start this program on channel 1 at the first tick: a file of the current folder by its
    /// path, else a name through channel 1's search paths, as `run PROGRAM`; one found nowhere
    /// is a usage error (exit 2), a start the channel refuses exits 1.
    #[arg(long)]
    pub start: Option<String>,
    /// Event log (JSON Lines): a file, or - for standard output.
    #[arg(long)]
    pub events: Option<String>,
    /// Stop after this many seconds (default, or `inf`: run until SIGINT/SIGTERM).
    #[arg(long)]
    pub seconds: Option<f64>,
    /// Soak external clients: inject the scenario's [faults] and check the invariants on what
    /// they write (the scenario's `params` replaces --params). Exit 1 on a violation.
    #[arg(long)]
    pub soak: Option<PathBuf>,
    /// Close an ADS connection that completed no frame for this many seconds while in the
    /// middle of a frame or holding no notification handles (default 60; docs/ads-limits.md).
    #[arg(long, value_name = "SECONDS")]
    pub(crate) ads_idle_timeout: Option<f64>,
    /// Serve the live web view on this address (default 127.0.0.1:8080; loopback unless
    /// --allow-non-loopback). Port 0 picks one. With --soak it shows the soak's counters too.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8080")]
    pub http: Option<SocketAddr>,
    /// Let the web view's operator controls (start, hold, resume, reset, override, run from
    /// line, MDI, jog) command the channels; without it they are refused (HTTP 403).
    #[arg(long, requires = "http")]
    pub http_controls: bool,
    /// A further `Host` name the web view answers (repeatable), e.g. the name a reverse proxy
    /// forwards; other names than the bound address and loopback are refused with 421.
    #[arg(
        long = "http-allow-host",
        value_name = "HOST[:PORT]",
        requires = "http"
    )]
    pub http_allow_host: Vec<String>,
    /// The real-time mode of the runtime thread (over runtime.toml's `[realtime]`).
    #[command(flatten)]
    pub rt: crate::runtime::realtime::RealtimeArgs,
    /// With --soak: write the report as JSON here.
    #[arg(long, requires = "soak")]
    pub report: Option<PathBuf>,
}

/// How long the stop waits for its last stderr lines to be written: a reader that does not
/// read loses them rather than the exit.
const FINAL_LINES_WAIT: Duration = Duration::from_millis(100);

fn load_scenario(p: &std::path::Path) -> Result<Scenario, String> {
    let p = crate::params::shipped::locate(p).map_err(|e| e.to_string())?;
    load_external(&p)
}

/// The ADS server's settings: the command line over runtime.toml's `[ads]`.
fn server_config(args: &ServeArgs, config: &crate::params::Config) -> ServerConfig {
    let ads = &config.runtime.ads;
    ServerConfig {
        bind: args.bind.unwrap_or(ads.bind.0),
        allow_non_loopback: args.allow_non_loopback,
        net_id: Some(args.net_id.unwrap_or(ads.net_id)),
        route_service: true,
        max_frame_bytes: ads.max_frame_bytes as usize,
        allow: ads.allowed_clients.clone(),
        max_connections: ads.max_connections as usize,
        max_notifications: ads.max_notifications_per_connection as usize,
        max_notifications_total: ads.max_notifications_total as usize,
        notification_samples_per_s: u64::from(ads.notification_samples_per_s),
        notification_samples_per_s_per_connection: u64::from(
            ads.notification_samples_per_s_per_connection,
        ),
        idle_timeout: args
            .ads_idle_timeout
            .and_then(|s| Duration::try_from_secs_f64(s).ok())
            .filter(|d| !d.is_zero())
            .unwrap_or(Duration::from_secs(u64::from(ads.idle_timeout_s))),
        ..ServerConfig::default()
    }
}

/// `--seconds`: `None` runs until a signal (no value, `inf`, or longer than `Duration` holds);
/// a negative or NaN value is a usage error. `Duration::from_secs_f64` would panic on those.
fn run_limit(seconds: Option<f64>) -> Result<Option<Duration>, String> {
    match seconds {
        None => Ok(None),
        Some(s) if s.is_nan() || s < 0.0 => Err(format!("--seconds {s}: not a duration")),
        Some(s) => Ok(Duration::try_from_secs_f64(s).ok()),
    }
}

fn usage(msg: impl std::fmt::Display) -> ExitCode {
    say(format_args!("ncchannel serve: {msg}"));
    ExitCode::from(exit::USAGE)
}

/// The machine under the soak's supervision: faults injected, invariants checked on what the
/// external clients make the channels do.
fn supervised(machine: Machine, sc: &Scenario, config: &crate::params::Config) -> Supervised {
    // The soft limits of the first channel's axes, as the in-process soak checks them.
    let axes = crate::setup::axes(config).unwrap_or_default();
    let programs = config
        .channels
        .iter()
        .map(|c| c.streaming_prog_file.clone())
        .collect();
    Supervised::new(machine, sc, &axes, programs)
}

/// The event log `--events` asks for. The soak's checks need the channels' events: without
/// `--events` they go nowhere. Real time: a reader that falls behind loses events (counted),
/// never the cycle's pace.
fn event_log(target: Option<&str>, soak: bool) -> Result<EventLog, ExitCode> {
    match target {
        None if soak => Ok(EventLog::to_writer(Box::new(std::io::sink()))),
        None => Ok(EventLog::disabled()),
        Some(t) => match EventLog::open(t) {
            Ok(l) => Ok(l.with_backlog(Backlog::Drop)),
            Err(e) => Err(usage(format!("--events {t}: {e}"))),
        },
    }
}

/// The served channels, and the program `--start` names as channel 1 starts it. `--start`
/// resolves as `run PROGRAM` does: a file of the current folder by its path, a name through
/// channel 1's search paths; one found nowhere is a usage error.
fn load_with_start(
    args: &ServeArgs,
    events: bool,
    loader: &crate::source::loader::Loader,
) -> Result<
    (
        crate::params::Config,
        Vec<crate::channel::Channel>,
        Option<String>,
    ),
    String,
> {
    let start = match args.start.as_deref().map(super::run::locate_program) {
        None => None,
        Some(Ok(p)) => Some(p),
        Some(Err(msg)) => return Err(format!("--start {msg}")),
    };
    let mut config = super::run::load_config(&args.params)?;
    let start =
        start.map(|p| super::run::program_by_path(&mut config, 0, &p, "ncchannel serve --start"));
    let channels = crate::setup::channels(&config, events, loader).map_err(|e| e.to_string())?;
    if let Some(p) = &start {
        super::run::program_exists(&channels, 1, p).map_err(|msg| format!("--start {msg}"))?;
    }
    Ok((config, channels, start))
}

/// Channel 1 starts `program` before the runtime's first tick (`serve --start`, the live-view
/// bench): the channel's refusal, if it refuses.
pub(super) fn start_at_first_tick(
    machine: &mut Machine,
    period: Duration,
    program: &str,
) -> Result<(), String> {
    let tick0 = Tick::first(period, Clock::RealTime);
    match machine.apply(&tick0, 1, Op::Start(program.to_string())) {
        Reply::Command(Err(e)) => Err(e.to_string()),
        _ => Ok(()),
    }
}

/// The web view's settings from `--http`, `--http-controls`, `--http-allow-host` and
/// `--allow-non-loopback` (`None` without `--http`).
fn http_config(args: &ServeArgs) -> Option<crate::http::HttpConfig> {
    let bind = args.http?;
    Some(crate::http::HttpConfig {
        bind,
        allow_non_loopback: args.allow_non_loopback,
        controls: if args.http_controls {
            crate::http::ControlAccess::Allowed
        } else {
            crate::http::ControlAccess::Refused
        },
        allow_hosts: args.http_allow_host.clone(),
    })
}

/// The checks of `serve`'s arguments before anything starts: `--ads-idle-timeout`, the
/// `--soak` scenario (whose lists replace `--params`) and where the lists are.
fn checked_scenario(args: &mut ServeArgs) -> Result<Option<Scenario>, String> {
    if let Some(s) = args.ads_idle_timeout {
        if !(s.is_finite() && s > 0.0) {
            return Err(format!("--ads-idle-timeout {s}: not a positive time"));
        }
    }
    let scenario = match &args.soak {
        None => None,
        Some(p) => {
            let s = load_scenario(p)?;
            args.params = s.params_path();
            Some(s)
        }
    };
    args.params = crate::params::shipped::locate(&args.params).map_err(|e| e.to_string())?;
    Ok(scenario)
}

pub fn execute(mut args: ServeArgs) -> ExitCode {
    let limit = match run_limit(args.seconds) {
        Ok(l) => l,
        Err(msg) => return usage(msg),
    };
    let scenario = match checked_scenario(&mut args) {
        Ok(s) => s,
        Err(msg) => return usage(msg),
    };
    // The program loader of the served channels: large program files are read, and large
    // texts freed, off the runtime thread.
    let loader = crate::source::loader::Loader::start();
    let (config, channels, start) =
        match load_with_start(&args, args.events.is_some() || scenario.is_some(), &loader) {
            Ok(c) => c,
            Err(msg) => return usage(msg),
        };
    let log = match event_log(args.events.as_deref(), scenario.is_some()) {
        Ok(l) => l,
        Err(code) => return code,
    };
    let nch = channels.len() as u16;
    let period = Duration::from_micros(config.runtime.cycle_period_us);
    let mut machine = Machine::new(channels, log, StopWhen::Never);
    if args.http.is_some() {
        machine.record_live();
    }
    if let Err(msg) = super::run::attach_plcs(&mut machine, config.runtime.plc.as_ref()) {
        return usage(msg);
    }
    if let Some(p) = &start {
        if let Err(e) = start_at_first_tick(&mut machine, period, p) {
            say(format_args!("ncchannel serve: --start {p}: {e}"));
            return ExitCode::from(super::exit::CHANNEL_ERROR);
        }
    }
    if let Some(sc) = scenario {
        let cycle = supervised(machine, &sc, &config);
        let soak = super::serve_soak::SoakServe {
            web: http_config(&args),
            server_config: server_config(&args, &config),
            limit,
            report: args.report.clone(),
            period,
            channels: nch,
            reply_timeout: config.runtime.ads.reply_timeout(),
            realtime: args.rt.over(&config.runtime.realtime),
        };
        return super::serve_soak::run(cycle, &sc, soak);
    }
    let (mut rt, requests) = Runtime::new(machine, period, Clock::RealTime);
    let previews = super::preview::previewer(config.clone(), loader.clone());
    let web = match super::web_view::spawn(
        http_config(&args),
        &mut rt,
        requests.clone(),
        nch,
        Some(previews),
    ) {
        Ok(w) => w,
        Err(code) => return code,
    };
    let server_config = server_config(&args, &config);
    let net_id = server_config.net_id;
    let backend =
        ChannelBackend::new(requests, nch).with_reply_timeout(config.runtime.ads.reply_timeout());
    let server = match crate::ads::spawn(server_config, Arc::new(backend)) {
        Ok(s) => s,
        Err(e) => return usage(format!("cannot listen: {e}")),
    };
    // From here on stderr is written through the logger's queue: a supervisor that stops
    // reading it (a full pipe) must hold up neither the server nor the stop.
    let line = super::logger::listening_line(&server, net_id, "", nch, period);
    super::logger::line(format_args!("{line}"));
    match super::signal::StopSignal::install() {
        Ok(sig) => rt.stop_on(sig.flag()),
        Err(e) => super::logger::line(format_args!(
            "ncchannel serve: cannot handle SIGINT/SIGTERM: {e}"
        )),
    }
    let stop = rt.stop_handle();
    if let Some(d) = limit {
        std::thread::spawn(move || {
            std::thread::sleep(d);
            stop.stop();
        });
    }
    // Every other thread (ADS, web view, loader, logger, the limit's timer) runs by now: the
    // real-time mode keeps them off the runtime's CPU.
    let mode = args.rt.over(&config.runtime.realtime);
    if let Err(code) = super::enter_realtime(&mode, "serve", super::logger::line) {
        server.shutdown();
        drop(web);
        super::logger::flush(FINAL_LINES_WAIT);
        return code;
    }
    let summary = rt.run(None);
    // The tick in progress has finished; close the sockets, then write out the log.
    server.shutdown();
    drop(web); // the web view stops polling and ends its pages' streams
    stopped(rt, &summary, args.events.is_some())
}

/// After the stop: the summary line and the event log written out (exit 1 when it fails).
fn stopped(rt: Runtime<Machine>, summary: &crate::runtime::RunSummary, events: bool) -> ExitCode {
    let (mut machine, stats) = rt.into_inner();
    let log = machine.finish_log();
    let blocks: u64 = machine
        .channels()
        .iter()
        .map(|c| c.report().stats.blocks)
        .sum();
    super::logger::line(format_args!(
        "stopped after {} ticks ({:.1} s), {blocks} blocks; {}",
        summary.ticks,
        summary.wall.as_secs_f64(),
        stats.describe()
    ));
    match log {
        Ok(lines) if events => super::logger::line(format_args!("event log: {lines} lines")),
        Ok(_) => {}
        Err(e) => {
            super::logger::line(format_args!("ncchannel serve: event log: {e}"));
            super::logger::flush(FINAL_LINES_WAIT);
            return ExitCode::from(exit::CHANNEL_ERROR);
        }
    }
    super::logger::flush(FINAL_LINES_WAIT);
    ExitCode::from(exit::OK)
}
