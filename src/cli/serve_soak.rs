//! `ncchannel serve --soak SCENARIO.toml`: the ADS server over the supervised channels
//! (`soak::external`), a live status line on stderr, and the report at the end (`--seconds`
//! or SIGINT/SIGTERM). Exit 0 every invariant held, 1 one was violated.

use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::ads::ServerConfig;
use crate::machine::remote::ChannelBackend;
use crate::runtime::{Clock, RunEnd, Runtime};
use crate::soak::external::{resident, Supervised};
use crate::soak::report::{CycleFigures, MemoryReport, RunFigures, SoakReport};
use crate::soak::scenario::Scenario;

use super::exit;
use super::out::say;

/// What `serve` settled before handing over: the ADS endpoint, the run limit, the report
/// file, the cycle time and the channel count.
pub struct SoakServe {
    /// The live view beside the soak (`--http`), if asked for.
    pub web: Option<crate::http::HttpConfig>,
    pub(crate) server_config: ServerConfig,
    pub limit: Option<Duration>,
    pub report: Option<PathBuf>,
    pub period: Duration,
    pub channels: u16,
    /// runtime.toml `ads.reply_timeout_ms`: when a request the runtime has not answered is
    /// refused 0x708.
    pub reply_timeout: Duration,
    /// The runtime thread's real-time mode (`--rt-…` over runtime.toml's `[realtime]`).
    pub realtime: crate::runtime::realtime::RealtimeConfig,
}

pub fn run(cycle: Supervised, scenario: &Scenario, soak: SoakServe) -> ExitCode {
    let SoakServe {
        web: web_config,
        server_config,
        limit,
        report: report_path,
        period,
        channels: nch,
        reply_timeout,
        realtime,
    } = soak;
    let net_id = server_config.net_id;
    // Until the end the report file says the run is under way (see `ncchannel soak`).
    let placeholder = SoakReport::incomplete(&scenario.path, scenario.seed);
    if !super::out::mark_report_incomplete("serve", report_path.as_deref(), &placeholder.to_json())
    {
        return ExitCode::from(exit::USAGE);
    }
    let (mut rt, requests) = Runtime::new(cycle, period, Clock::RealTime);
    let web = match super::web_view::spawn(web_config, &mut rt, requests.clone(), nch, None) {
        Ok(w) => w,
        Err(code) => return code,
    };
    let backend = ChannelBackend::new(requests, nch).with_reply_timeout(reply_timeout);
    let server = match crate::ads::spawn(server_config, Arc::new(backend)) {
        Ok(s) => s,
        Err(e) => {
            say(format_args!("ncchannel serve: cannot listen: {e}"));
            return ExitCode::from(exit::USAGE);
        }
    };
    let soak = format!("soak {}, ", scenario.path.display());
    let line = super::logger::listening_line(&server, net_id, &soak, nch, period);
    super::out::log(format_args!("{line}"));
    let signal = super::signal::StopSignal::install().ok();
    if let Some(s) = &signal {
        rt.stop_on(s.flag());
    }
    let warmup = limit.map_or(Duration::from_secs(10), |l| {
        l.mul_f64(scenario.invariants.warmup)
    });
    if let Err(code) = super::enter_realtime(&realtime, "serve", say) {
        server.shutdown();
        return code;
    }
    let start = Instant::now();
    let warm_kib = serve_until_stopped(&mut rt, web.as_ref(), (period, limit, warmup), start);
    server.shutdown();
    drop(web); // the web view stops polling and ends its pages' streams
    let wall = start.elapsed().as_secs_f64();
    let ticks = rt.ticks();
    let sim_seconds = rt.time().as_secs_f64();
    let (cycle, stats) = rt.into_inner();
    let end_kib = resident();
    let growth = warm_kib.zip(end_kib).map(|(a, b)| b as i64 - a as i64);
    let report = report_of(
        &cycle,
        scenario,
        (ticks, sim_seconds, wall),
        MemoryReport {
            warmup_kib: warm_kib,
            end_kib,
            growth_kib: growth,
        },
        CycleFigures::new(period.as_secs_f64() * 1e6, &stats),
    );
    let all_held = report.all_held;
    let mut machine = cycle.into_machine();
    if let Err(e) = machine.finish_log() {
        super::out::log(format_args!("ncchannel serve: event log: {e}"));
    }
    say(format_args!(""));
    let _ = report.print_human(&mut std::io::stdout());
    if let Some(p) = &report_path {
        if !super::out::write_report("serve", p, &report.to_json()) {
            return ExitCode::from(exit::USAGE);
        }
    }
    ExitCode::from(if all_held {
        exit::OK
    } else {
        exit::CHANNEL_ERROR
    })
}

/// Runs the soak in chunks of 50 ms of ticks until a stop or the limit
/// (`timing`: period, limit, warm-up), announcing resets, publishing to the web view and
/// printing the status line; the resident memory (KiB) once the warm-up is over.
fn serve_until_stopped(
    rt: &mut Runtime<Supervised>,
    web: Option<&crate::http::HttpHandle>,
    timing: (Duration, Option<Duration>, Duration),
    start: Instant,
) -> Option<u64> {
    let (period, limit, warmup) = timing;
    let chunk = ((0.05 / period.as_secs_f64()) as u64).max(1);
    let live = std::io::stderr().is_terminal();
    let mut last_status = start;
    let mut warm_kib = None;
    let mut last_published = start;
    loop {
        let s = rt.run(Some(chunk));
        let wall = start.elapsed();
        if warm_kib.is_none() && wall >= warmup {
            warm_kib = resident();
        }
        announce_resets(rt, period, live);
        if s.end == RunEnd::StopRequested || limit.is_some_and(|l| wall >= l) {
            return warm_kib;
        }
        publish_soak(web, rt, wall, &mut last_published);
        let every = if live { 500 } else { 5_000 };
        if last_status.elapsed() >= Duration::from_millis(every) {
            last_status = Instant::now();
            status_line(rt, wall, live);
        }
    }
}

/// The soak's report of a `serve --soak` run (`times`: ticks, channel seconds, wall seconds).
fn report_of(
    cycle: &Supervised,
    scenario: &Scenario,
    (ticks, sim_seconds, wall_seconds): (u64, f64, f64),
    memory: MemoryReport,
    cycle_figures: CycleFigures,
) -> SoakReport {
    let run = RunFigures {
        seed: scenario.seed,
        realtime: true,
        ticks,
        sim_seconds,
        wall_seconds,
        blocks: cycle.blocks(),
    };
    let invariants = cycle.verdicts(memory.growth_kib, scenario.invariants.memory_slack_kib);
    SoakReport::new(
        &scenario.path,
        run,
        invariants,
        cycle.counters(),
        memory,
        cycle_figures,
    )
}

/// One stderr line per reset the soak made since the last call, so the people behind a
/// client learn that accepted lines were dropped and when the program restarts.
fn announce_resets(rt: &mut Runtime<Supervised>, period: Duration, live: bool) {
    let (notices, lost) = rt.cycle_mut().take_notices();
    if notices.is_empty() && lost == 0 {
        return;
    }
    let secs = |tick: u64| period.as_secs_f64() * tick as f64;
    // On a terminal the live status line is cleared first (it is redrawn).
    let clear = if live { "\r\x1b[2K" } else { "" };
    let mut err = std::io::stderr().lock();
    for n in notices {
        let why = if n.after_error {
            "after a channel error"
        } else {
            "injected"
        };
        let restart = n.restart_tick.map_or(String::new(), |t| {
            format!(
                "; READY until {:.3} s, then the streaming program restarts",
                secs(t)
            )
        });
        let _ = writeln!(
            err,
            "{clear}{} serve --soak: {:.3} s: channel {} reset ({why}): {} accepted line(s) dropped unexecuted{restart}",
            super::out::now(),
            secs(n.tick),
            n.channel,
            n.lines_dropped
        );
    }
    if lost > 0 {
        let _ = writeln!(
            err,
            "{} serve --soak: {lost} more reset(s) not shown",
            super::out::now()
        );
    }
}

/// How often `serve --soak --http` hands the soak's counters to the live view: the
/// invariants' verdicts are worked out on the runtime's thread between ticks, so not at the
/// view's 20 Hz.
const SOAK_VIEW_PERIOD: Duration = Duration::from_millis(500);

/// Hand the soak to the live view when [`SOAK_VIEW_PERIOD`] has passed since `last`.
fn publish_soak(
    web: Option<&crate::http::HttpHandle>,
    rt: &Runtime<Supervised>,
    wall: Duration,
    last: &mut Instant,
) {
    if let Some(w) = web {
        if last.elapsed() >= SOAK_VIEW_PERIOD {
            *last = Instant::now();
            w.publish_soak(soak_view(rt, wall));
        }
    }
}

/// The soak as the live view shows it: run time, each channel's counters and the
/// invariants' verdicts so far (the report's words).
fn soak_view(rt: &Runtime<Supervised>, wall: Duration) -> serde_json::Value {
    serde_json::json!({
        "seconds": wall.as_secs_f64(),
        "blocks": rt.cycle().blocks(),
        "channels": rt.cycle().counters(),
        "invariants": rt.cycle().verdicts(None, 0),
    })
}

fn status_line(rt: &Runtime<Supervised>, wall: Duration, live: bool) {
    let c = rt.cycle().counters();
    let lines: u64 = c.iter().map(|c| c.lines_accepted).sum();
    let blocks = rt.cycle().blocks();
    let resets: u64 = c.iter().map(|c| c.resets).sum();
    let violations: u64 = rt
        .cycle()
        .verdicts(None, 0)
        .iter()
        .map(|v| v.violations)
        .sum();
    let line = format!(
        "{} serve --soak: {:.0} s, {lines} lines accepted, {blocks} blocks, {resets} resets, {violations} violations",
        super::out::now(),
        wall.as_secs_f64()
    );
    let mut err = std::io::stderr().lock();
    if live {
        let _ = write!(err, "\r{line}   ");
    } else {
        let _ = writeln!(err, "{line}");
    }
    let _ = err.flush();
}
