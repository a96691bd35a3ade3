//! `ncchannel serve --soak SCENARIO.toml`: the ADS server over the supervised channels
//! (`soak::external`), a live status line on stderr, and the report at the end (`--seconds`
//! or SIGINT/SIGTERM). Exit 0 every invariant held, 1 one was violated.

use std::io::{IsTerminal, Write};
use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::ads::channel_backend::ChannelBackend;
use crate::runtime::{Clock, RunEnd, Runtime};
use crate::soak::external::{resident, ExternalCounters, Supervised};
use crate::soak::invariants::{Tally, Verdict};
use crate::soak::scenario::Scenario;

use super::exit;
use super::serve::{report as say, run_limit, usage, ServeArgs};

/// The report of one `serve --soak` run (`--report` writes it as JSON).
#[derive(Debug, Serialize)]
pub struct ServeSoakReport {
    pub scenario: String,
    pub seconds: f64,
    pub ticks: u64,
    pub channels: Vec<ExternalCounters>,
    pub invariants: Vec<Verdict>,
    pub resident_kib_after_warmup: Option<u64>,
    pub resident_kib_at_end: Option<u64>,
    pub all_held: bool,
}

impl ServeSoakReport {
    fn print_human(&self, w: &mut dyn Write) -> std::io::Result<()> {
        writeln!(w, "serve --soak {}", self.scenario)?;
        writeln!(w, "run:      {:.1} s, {} ticks", self.seconds, self.ticks)?;
        for c in &self.channels {
            writeln!(
                w,
                "channel {}: {} writes / {} lines accepted, {} blocks checked, {} resets ({} after errors), {} restarts, {} holds, {} overrides, {} forced rejections ({} writes refused)",
                c.channel, c.writes_accepted, c.lines_accepted, c.blocks, c.resets, c.error_resets,
                c.restarts, c.holds, c.overrides, c.forced_rejections, c.writes_forced_rejected
            )?;
        }
        for v in &self.invariants {
            let word = if v.held { "held    " } else { "VIOLATED" };
            writeln!(w, "{word}  {} ({} violations)", v.name, v.violations)?;
            for d in &v.details {
                writeln!(w, "          {d}")?;
            }
        }
        writeln!(
            w,
            "result:   {}",
            if self.all_held {
                "every invariant held"
            } else {
                "an invariant was violated"
            }
        )
    }
}

pub fn run(
    cycle: Supervised,
    scenario: &Scenario,
    args: &ServeArgs,
    config: &crate::params::Config,
    period: Duration,
    nch: u16,
) -> ExitCode {
    let limit = match run_limit(args.seconds) {
        Ok(l) => l,
        Err(msg) => return usage(msg),
    };
    let (mut rt, requests) = Runtime::new(cycle, period, Clock::RealTime);
    let server_config = super::serve::server_config(args, config);
    let server =
        match crate::ads::spawn(server_config, Arc::new(ChannelBackend::new(requests, nch))) {
            Ok(s) => s,
            Err(e) => return usage(format!("cannot listen: {e}")),
        };
    say(format_args!(
        "listening on {} (soak {}, {nch} channel(s), cycle {} µs)",
        server.local_addr(),
        scenario.path.display(),
        period.as_micros()
    ));
    let signal = super::signal::StopSignal::install().ok();
    if let Some(s) = &signal {
        rt.stop_on(s.flag());
    }
    let warmup = limit.map_or(Duration::from_secs(10), |l| {
        l.mul_f64(scenario.invariants.warmup)
    });
    let chunk = ((0.05 / period.as_secs_f64()) as u64).max(1);
    let live = std::io::stderr().is_terminal();
    let start = Instant::now();
    let mut last_status = start;
    let mut warm_kib = None;
    loop {
        let s = rt.run(Some(chunk));
        let wall = start.elapsed();
        if warm_kib.is_none() && wall >= warmup {
            warm_kib = resident();
        }
        if s.end == RunEnd::StopRequested || limit.is_some_and(|l| wall >= l) {
            break;
        }
        let every = if live { 500 } else { 5_000 };
        if last_status.elapsed() >= Duration::from_millis(every) {
            last_status = Instant::now();
            status_line(&rt, wall, live);
        }
    }
    server.shutdown();
    let seconds = start.elapsed().as_secs_f64();
    let ticks = rt.ticks();
    let (cycle, _stats) = rt.into_inner();
    let mut invariants = cycle.verdicts();
    let channels = cycle.counters();
    let end_kib = resident();
    let mut memory = Tally::default();
    if let (Some(a), Some(b)) = (warm_kib, end_kib) {
        if b > a + scenario.invariants.memory_slack_kib {
            memory.violate(|| format!("resident set grew {} KiB", b - a));
        }
    }
    invariants.push(memory.verdict(
        "memory steady",
        Some(format!(
            "{:?} KiB after warm-up, {:?} KiB at the end",
            warm_kib, end_kib
        )),
    ));
    let mut machine = cycle.into_machine();
    if let Err(e) = machine.finish_log() {
        say(format_args!("ncchannel serve: event log: {e}"));
    }
    let all_held = invariants.iter().all(|v| v.held);
    let report = ServeSoakReport {
        scenario: scenario.path.display().to_string(),
        seconds,
        ticks,
        channels,
        invariants,
        resident_kib_after_warmup: warm_kib,
        resident_kib_at_end: end_kib,
        all_held,
    };
    say(format_args!(""));
    let _ = report.print_human(&mut std::io::stdout());
    if let Some(p) = &args.report {
        let json = serde_json::to_string_pretty(&report).unwrap_or_default();
        if let Err(e) = std::fs::write(p, json + "\n") {
            say(format_args!(
                "ncchannel serve: --report {}: {e}",
                p.display()
            ));
            return ExitCode::from(exit::USAGE);
        }
    }
    ExitCode::from(if all_held {
        exit::OK
    } else {
        exit::CHANNEL_ERROR
    })
}

fn status_line(rt: &Runtime<Supervised>, wall: Duration, live: bool) {
    let c = rt.cycle().counters();
    let lines: u64 = c.iter().map(|c| c.lines_accepted).sum();
    let blocks: u64 = c.iter().map(|c| c.blocks).sum();
    let resets: u64 = c.iter().map(|c| c.resets).sum();
    let violations: u64 = rt.cycle().verdicts().iter().map(|v| v.violations).sum();
    let line = format!(
        "serve --soak: {:.0} s, {lines} lines accepted, {blocks} blocks, {resets} resets, {violations} violations",
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
