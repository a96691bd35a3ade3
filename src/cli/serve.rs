//! `ncchannel serve`: the channels in real time behind an ADS server, for real clients.

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
    /// Stop after this many seconds (default: run until killed).
    #[arg(long)]
    pub seconds: Option<f64>,
}

fn usage(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("ncchannel serve: {msg}");
    ExitCode::from(exit::USAGE)
}

pub fn execute(args: ServeArgs) -> ExitCode {
    let (config, channels) = match super::run::load_channels(&args.params, args.events.is_some()) {
        Ok(c) => c,
        Err(msg) => return usage(msg),
    };
    let log = match &args.events {
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
    let (mut rt, requests) = Runtime::new(machine, period, Clock::RealTime);
    let ads = &config.runtime.ads;
    let server_config = ServerConfig {
        bind: args.bind.unwrap_or(ads.bind.0),
        allow_non_loopback: args.allow_non_loopback,
        net_id: Some(args.net_id.unwrap_or(ads.net_id)),
        max_frame_bytes: ads.max_frame_bytes as usize,
        allow: ads.allowed_clients.clone(),
        ..ServerConfig::default()
    };
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
    if let Some(s) = args.seconds {
        let d = Duration::from_secs_f64(s.max(0.0));
        std::thread::spawn(move || {
            std::thread::sleep(d);
            stop.stop();
        });
    }
    let summary = rt.run(None);
    // The tick in progress has finished; close the sockets, then write out the log.
    server.shutdown();
    let (mut machine, stats) = rt.into_inner();
    let log = machine.finish_log();
    let blocks: u64 = machine.channels().iter().map(|c| c.stats().blocks).sum();
    eprintln!(
        "stopped after {} ticks ({:.1} s), {blocks} blocks; {}",
        summary.ticks,
        summary.wall.as_secs_f64(),
        stats.describe()
    );
    match log {
        Ok(lines) if args.events.is_some() => eprintln!("event log: {lines} lines"),
        Ok(_) => {}
        Err(e) => {
            eprintln!("ncchannel serve: event log: {e}");
            return ExitCode::from(exit::CHANNEL_ERROR);
        }
    }
    ExitCode::from(exit::OK)
}
