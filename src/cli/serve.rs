//! `ncchannel serve`: the channels in real time behind an ADS server, for real clients.

use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use crate::ads::channel_backend::ChannelBackend;
use crate::ads::{AmsNetId, ServerConfig};
use crate::machine::{Machine, StopWhen};
use crate::report::event::EventLog;
use crate::runtime::{Clock, Runtime, Tick};
use crate::soak::external::{load_external, Supervised};
use crate::soak::scenario::Scenario;

use super::exit;

#[derive(Debug, Clone, clap::Args)]
pub struct ServeArgs {
    /// Start-up list.
    #[arg(long, default_value = "params/startup.lis")]
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
    /// Start this program on channel 1 when the channel is up.
    #[arg(long)]
    pub start: Option<String>,
    /// Event log (JSON Lines): a file, or - for standard output.
    #[arg(long)]
    pub events: Option<String>,
    /// Stop after this many seconds, 0 to 1e9 (default: run until SIGINT/SIGTERM).
    #[arg(long, value_parser = run_seconds)]
    pub seconds: Option<Duration>,
    /// Soak external clients: inject the scenario's [faults] and check the invariants on what
    /// they write (the scenario's `params` replaces --params). Exit 1 on a violation.
    #[arg(long)]
    pub soak: Option<PathBuf>,
    /// With --soak: write the report as JSON here.
    #[arg(long, requires = "soak")]
    pub report: Option<PathBuf>,
}

fn load_scenario(p: &std::path::Path) -> Result<Scenario, String> {
    load_external(&super::run::locate(p))
}

/// The ADS server's settings: the command line over runtime.toml's `[ads]`.
pub(crate) fn server_config(args: &ServeArgs, config: &crate::params::Config) -> ServerConfig {
    let ads = &config.runtime.ads;
    ServerConfig {
        bind: args.bind.unwrap_or(ads.bind.0),
        allow_non_loopback: args.allow_non_loopback,
        net_id: Some(args.net_id.unwrap_or(ads.net_id)),
        max_frame_bytes: ads.max_frame_bytes as usize,
        allow: ads.allowed_clients.clone(),
        max_connections: ads.max_connections as usize,
        max_notifications: ads.max_notifications_per_connection as usize,
        max_notification_rate_per_s: u64::from(ads.max_notification_rate_per_s),
    }
}

pub(crate) fn usage(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("ncchannel serve: {msg}");
    ExitCode::from(exit::USAGE)
}

pub fn execute(mut args: ServeArgs) -> ExitCode {
    let scenario = match &args.soak {
        None => None,
        Some(p) => match load_scenario(p) {
            Ok(s) => {
                args.params = s.params_path();
                Some(s)
            }
            Err(msg) => return usage(msg),
        },
    };
    let (config, channels) = match super::run::load_channels(
        &args.params,
        args.events.is_some() || scenario.is_some(),
    ) {
        Ok(c) => c,
        Err(msg) => return usage(msg),
    };
    let log = match &args.events {
        // The soak's checks need the channels' events; without --events they go nowhere.
        None if scenario.is_some() => EventLog::to_writer(Box::new(std::io::sink())),
        None => EventLog::disabled(),
        Some(t) => match EventLog::open(t) {
            Ok(l) => l,
            Err(e) => return usage(format!("--events {t}: {e}")),
        },
    };
    let nch = channels.len() as u16;
    let period = Duration::from_micros(config.runtime.cycle_period_us);
    let mut machine = Machine::new(channels, log, StopWhen::Never);
    if let Some(p) = &args.start {
        let tick0 = Tick {
            index: 0,
            period,
            time: Duration::ZERO,
        };
        if let Some(c) = machine.channel_mut(1) {
            if let Err(e) = c.start(&tick0, p) {
                eprintln!("ncchannel serve: --start {p}: {e}");
            }
        }
    }
    if let Some(sc) = scenario {
        let soft_limits = config
            .runtime
            .axes
            .iter()
            .filter_map(|a| {
                let c = a.name.chars().next()?;
                Some((c, a.soft_limit_min_mm, a.soft_limit_max_mm))
            })
            .collect();
        let programs = config
            .channels
            .iter()
            .map(|c| c.streaming_prog_file.clone())
            .collect();
        let cycle = Supervised::new(machine, &sc, soft_limits, programs);
        return super::serve_soak::run(cycle, &sc, &args, &config, period, nch);
    }
    let (mut rt, requests) = Runtime::new(machine, period, Clock::RealTime);
    let server_config = server_config(&args, &config);
    let net_id = server_config.net_id;
    let server =
        match crate::ads::spawn(server_config, Arc::new(ChannelBackend::new(requests, nch))) {
            Ok(s) => s,
            Err(e) => return usage(format!("cannot listen: {e}")),
        };
    eprintln!(
        "listening on {} (AMS NetId {}, port 553, {nch} channel(s), cycle {} µs)",
        server.local_addr(),
        net_id.map(|n| n.to_string()).unwrap_or_default(),
        period.as_micros()
    );
    match super::signal::StopSignal::install() {
        Ok(sig) => rt.stop_on(sig.flag()),
        Err(e) => eprintln!("ncchannel serve: cannot handle SIGINT/SIGTERM: {e}"),
    }
    let stop = rt.stop_handle();
    if let Some(d) = args.seconds {
        std::thread::spawn(move || {
            std::thread::sleep(d);
            stop.stop();
        });
    }
    let summary = rt.run(None);
    // The tick in progress has finished; close the sockets, then write out the log.
    server.shutdown();
    let (mut machine, stats) = rt.into_inner();
    // The log first, then the words: `writeln!` rather than `eprintln!`, whose panic on a
    // closed stderr (a supervisor that went away) would lose the stop's exit code.
    let dropped = machine.events_dropped();
    let log = machine.finish_log();
    let blocks: u64 = machine.channels().iter().map(|c| c.stats().blocks).sum();
    let mut err = std::io::stderr().lock();
    let _ = writeln!(
        err,
        "stopped after {} ticks ({:.1} s), {blocks} blocks; {}",
        summary.ticks,
        summary.wall.as_secs_f64(),
        stats.describe()
    );
    match log {
        Ok(lines) if args.events.is_some() => {
            let _ = writeln!(err, "event log: {lines} lines");
            if dropped > 0 {
                let _ = writeln!(
                    err,
                    "event log: {dropped} events dropped: its reader fell more than {} ticks behind",
                    crate::report::event::MAX_PENDING_BATCHES
                );
            }
        }
        Ok(_) => {}
        Err(e) => {
            let _ = writeln!(err, "ncchannel serve: event log: {e}");
            return ExitCode::from(exit::CHANNEL_ERROR);
        }
    }
    ExitCode::from(exit::OK)
}

/// `--seconds`: a finite number of seconds from 0 to 1e9 (about 31 years); "inf", NaN or a
/// negative number is a usage error rather than a panic or a silent default.
fn run_seconds(s: &str) -> Result<Duration, String> {
    let v: f64 = s.trim().parse().map_err(|e| format!("{e}"))?;
    if !(0.0..=1e9).contains(&v) {
        return Err(format!(
            "{v} is not a number of seconds from 0 to 1e9 (leave --seconds out to run until stopped)"
        ));
    }
    Duration::try_from_secs_f64(v).map_err(|e| e.to_string())
}
