//! Soak tests: a scenario file drives every channel of a start-up list for millions of blocks
//! with a randomised client and injected faults, checking invariants as it goes; see
//! `ncchannel soak` and the README section "Soak and bench".

pub mod campaign;
pub(crate) mod driver;
pub(crate) mod external;
pub(crate) mod feed;
pub(crate) mod generator;
pub(crate) mod invariants;
pub mod load;
pub mod report;
pub(crate) mod rng;
pub mod scenario;

use std::time::{Duration, Instant};

use indicatif::ProgressBar;
use thiserror::Error;

use crate::machine::{Machine, StopWhen};
use crate::report::event::EventLog;
use crate::runtime::{Clock, RunEnd, Runtime};
use crate::source::loader::Loader;
use driver::{Slot, SoakCycle};
use feed::{SoakFeeder, Source};
use generator::Generator;
use invariants::resident_kib;
use report::{CycleFigures, MemoryReport, RunFigures, SoakReport};
use rng::SplitMix64;
use scenario::{ClockSpec, Length, Scenario};

/// Resolution of the progress bar (per mille of the run).
const PROGRESS_STEPS: u64 = 1000;
/// Largest file a scenario streams.
const MAX_STREAM_FILE_BYTES: u64 = 16 << 20;

#[derive(Debug, Error)]
pub enum SoakError {
    #[error(transparent)]
    Scenario(#[from] scenario::ScenarioError),
    #[error("parameter lists {path}: {msg}")]
    Params { path: String, msg: String },
    #[error("{0}")]
    Setup(String),
    /// `--rt-required`: the system refused a part of the real-time mode.
    #[error("{0}")]
    Realtime(String),
}

/// Command-line choices that override the scenario.
#[derive(Debug, Clone, Default)]
pub struct Options {
    pub realtime: bool,
    /// Print a progress line on stderr (only when it is a terminal).
    pub progress: bool,
    /// Replace the scenario's `[length]` (the CI's short runs).
    pub length: Option<Length>,
    pub seed: Option<u64>,
    /// Stop early when this flag is set (SIGINT/SIGTERM); the report covers the run so far.
    pub stop: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
    /// The real-time mode's options, over the scenario's runtime.toml `[realtime]`; applied
    /// to real-time runs only.
    pub rt: crate::runtime::realtime::RealtimeArgs,
}

/// Build the cycle of a scenario: its channels, clients and fault schedules.
pub fn build(
    scenario: &Scenario,
    seed: u64,
    target_blocks: Option<u64>,
    loader: &Loader,
) -> Result<(SoakCycle, Duration), SoakError> {
    let params = scenario.params_path();
    let config = crate::params::load(&params).map_err(|e| SoakError::Params {
        path: params.display().to_string(),
        // `ParamError` displays every diagnostic, rendered, one a line.
        msg: e.to_string(),
    })?;
    let axes = crate::setup::axes(&config).map_err(|e| SoakError::Setup(e.to_string()))?;
    let specs: Vec<scenario::ChannelSpec> = if scenario.channels.is_empty() {
        (1..=config.channels.len() as u32)
            .map(|number| scenario::ChannelSpec {
                number,
                ..Default::default()
            })
            .collect()
    } else {
        scenario.channels.clone()
    };
    // The machine has the start-up list's channels up to the highest one soaked, so channel
    // n is at its number as in `run` and `serve`; a channel no spec names stays READY.
    let highest = specs.iter().map(|s| s.number).max().unwrap_or(0) as usize;
    let mut channels = Vec::new();
    for cc in config.channels.iter().take(highest) {
        let settings = crate::setup::channel_settings(&config, cc)
            .map_err(|e| SoakError::Setup(e.to_string()))?;
        channels.push(crate::channel::Channel::new(
            settings,
            false,
            loader.clone(),
        ));
    }
    let mut machine = Machine::new(channels, EventLog::disabled(), StopWhen::Never);
    let mut rng = SplitMix64::new(seed);
    let mut slots = Vec::new();
    for spec in &specs {
        let Some(cc) = config.channels.get(spec.number as usize - 1) else {
            return Err(SoakError::Setup(format!(
                "[[channel]] number {}: the start-up list has {} channels",
                spec.number,
                config.channels.len()
            )));
        };
        let program = match (&spec.program, &cc.streaming_prog_file) {
            (Some(p), _) | (None, Some(p)) => p.clone(),
            (None, None) => {
                return Err(SoakError::Setup(format!(
                    "channel {}: no program named and streaming is off in {}",
                    spec.number,
                    cc.list_path.display()
                )))
            }
        };
        let mut ch_rng = rng.fork(u64::from(spec.number));
        let source = match &spec.file {
            Some(f) => {
                let path = scenario.dir.join(f);
                let text = crate::bounded::read_file(&path, MAX_STREAM_FILE_BYTES)
                    .map_err(|e| SoakError::Setup(format!("{}: {e}", path.display())))?;
                Source::file(&text)
                    .map_err(|e| SoakError::Setup(format!("{}: {e}", path.display())))?
            }
            None => Source::Generated(Generator::new(
                spec.program_mix
                    .clone()
                    .unwrap_or_else(|| scenario.program.clone()),
                ch_rng.fork(1),
            )),
        };
        let feeder = SoakFeeder::new(
            spec.feeder
                .clone()
                .unwrap_or_else(|| scenario.feeder.clone()),
            ch_rng.fork(2),
            source,
        );
        attach_plc(&mut machine, spec, &mut ch_rng);
        let slot = Slot::new(
            &mut machine,
            spec.number,
            program,
            feeder,
            &axes,
            ch_rng.fork(3),
        )
        .ok_or_else(|| SoakError::Setup(format!("channel {}: not built", spec.number)))?;
        slots.push(slot);
    }
    let cycle = SoakCycle::new(
        machine,
        slots,
        scenario.faults.clone(),
        scenario.invariants.expected_errors.clone(),
        target_blocks,
    );
    Ok((
        cycle,
        Duration::from_micros(config.runtime.cycle_period_us.max(1)),
    ))
}

/// The channel's simulated PLC, if its `[channel.plc]` asks for one; its delays drawn from
/// the channel's random numbers, so the scenario's seed gives the same answers.
fn attach_plc(machine: &mut Machine, spec: &scenario::ChannelSpec, ch_rng: &mut SplitMix64) {
    if let Some(plc) = &spec.plc {
        let seed = ch_rng.fork(4).next_u64() ^ plc.seed;
        machine.attach_plc(crate::machine::plc::SimulatedPlc::new(
            spec.number,
            scenario::plc_config(plc, seed),
        ));
    }
}

/// The progress bar of a run (none when `enabled` is false).
fn progress_bar(enabled: bool) -> ProgressBar {
    if enabled {
        crate::report::progress::bar(PROGRESS_STEPS, "[{bar:30}] {percent:>3}%  {msg}")
    } else {
        ProgressBar::hidden()
    }
}

/// runtime.toml's `[realtime]` of the scenario's lists (default off when it cannot be read:
/// `build` has read and checked it already).
fn realtime_file(scenario: &Scenario) -> crate::runtime::realtime::RealtimeConfig {
    crate::params::load(&scenario.params_path())
        .map(|c| c.runtime.realtime)
        .unwrap_or_default()
}

/// Run a scenario to its end and report.
pub fn run(scenario: &Scenario, opts: &Options) -> Result<SoakReport, SoakError> {
    let length = opts
        .length
        .clone()
        .unwrap_or_else(|| scenario.length.clone());
    let seed = opts.seed.unwrap_or(scenario.seed);
    // The soak's program loader: the channels' large files are read off the tick.
    let loader = Loader::start();
    let (cycle, period) = build(scenario, seed, length.blocks, &loader)?;
    let realtime = opts.realtime || scenario.clock == ClockSpec::Realtime;
    let clock = if realtime {
        Clock::RealTime
    } else {
        Clock::Virtual
    };
    let (mut rt, _tx) = Runtime::new(cycle, period, clock);
    if realtime {
        let mode = opts.rt.over(&realtime_file(scenario));
        let done = crate::runtime::realtime::enter_saying(&mode, "soak", |m| eprintln!("{m}"))
            .map_err(SoakError::Realtime)?;
        if let Some(line) = done.summary() {
            eprintln!("{line}");
        }
    }
    if let Some(flag) = &opts.stop {
        rt.stop_on(std::sync::Arc::clone(flag));
    }

    let period_s = period.as_secs_f64();
    let tick_limit = [
        length.ticks,
        length.sim_seconds.map(|s| (s / period_s).ceil() as u64),
    ]
    .into_iter()
    .flatten()
    .min();
    let wall_limit = length.wall_seconds.map(Duration::from_secs_f64);
    let chunk = if realtime {
        ((0.05 / period_s) as u64).max(1)
    } else {
        2048
    };
    let bar = progress_bar(opts.progress);
    let fraction = |rt: &Runtime<SoakCycle>, wall: Duration| -> f64 {
        let mut f: f64 = 0.0;
        if let Some(b) = length.blocks {
            f = f.max(rt.cycle().total_blocks as f64 / b.max(1) as f64);
        }
        if let Some(t) = tick_limit {
            f = f.max(rt.ticks() as f64 / t.max(1) as f64);
        }
        if let Some(w) = wall_limit {
            f = f.max(wall.as_secs_f64() / w.as_secs_f64());
        }
        f.min(1.0)
    };

    let start = Instant::now();
    let mut warmup_kib = None;
    let mut interrupted = false;
    loop {
        let n = tick_limit.map_or(chunk, |t| chunk.min(t.saturating_sub(rt.ticks())));
        if n == 0 {
            break;
        }
        let s = rt.run(Some(n));
        let wall = start.elapsed();
        let f = fraction(&rt, wall);
        if warmup_kib.is_none() && f >= scenario.invariants.warmup {
            warmup_kib = resident_kib();
        }
        interrupted = s.end == RunEnd::StopRequested;
        if matches!(s.end, RunEnd::Stopped | RunEnd::StopRequested)
            || wall_limit.is_some_and(|w| wall >= w)
        {
            break;
        }
        let blocks = rt.cycle().total_blocks;
        bar.set_position((f * PROGRESS_STEPS as f64) as u64);
        bar.set_message(format!(
            "{blocks} blocks  {:.0} blocks/s",
            blocks as f64 / wall.as_secs_f64().max(1e-9)
        ));
    }
    bar.finish_and_clear();
    let run = RunFigures {
        seed,
        realtime,
        ticks: rt.ticks(),
        sim_seconds: rt.time().as_secs_f64(),
        wall_seconds: start.elapsed().as_secs_f64(),
        blocks: rt.cycle().total_blocks,
    };
    let (mut cycle, stats) = rt.into_inner();
    cycle.end_checks();
    let report = report_of(&cycle, &stats, scenario, run, warmup_kib, period);
    // The stop flag (SIGINT/SIGTERM) ended it before its length: the report of what ran.
    Ok(if interrupted {
        report.interrupted()
    } else {
        report
    })
}

/// The report of a finished run (`warmup_kib`: resident set after warm-up).
fn report_of(
    cycle: &SoakCycle,
    stats: &crate::vocab::stats::CycleStats,
    scenario: &Scenario,
    run: RunFigures,
    warmup_kib: Option<u64>,
    period: Duration,
) -> SoakReport {
    let end_kib = resident_kib();
    let warmup_kib = warmup_kib.or(end_kib);
    let growth = warmup_kib.zip(end_kib).map(|(a, b)| b as i64 - a as i64);
    let invariants = cycle.tallies.verdicts(
        run.blocks,
        &scenario.invariants.expected_errors,
        growth,
        scenario.invariants.memory_slack_kib,
    );
    let memory = MemoryReport {
        warmup_kib,
        end_kib,
        growth_kib: growth,
    };
    SoakReport::new(
        &scenario.path,
        run,
        invariants,
        cycle.reports(),
        memory,
        CycleFigures::new(period.as_secs_f64() * 1e6, stats),
    )
}
