//! `ncchannel soak SCENARIO.toml`: run a soak scenario, print the human report, write the JSON
//! one, exit 0 when every invariant held, 1 when one was violated, 2 on bad usage.

use std::path::PathBuf;
use std::process::ExitCode;

use crate::soak::scenario::{ClockSpec, Length, Scenario};
use crate::soak::{run, Options};

use super::exit;

#[derive(Debug, Clone, clap::Args)]
pub struct SoakArgs {
    /// Scenario file (see params/soak/; outside a clone, the shipped ones built into the binary).
    pub scenario: PathBuf,
    /// Run at the cycle period in wall-clock time instead of virtual time.
    #[arg(long)]
    pub(crate) realtime: bool,
    /// Replace the scenario's length: stop after this many executed blocks.
    #[arg(long)]
    pub blocks: Option<u64>,
    /// Replace the scenario's length: stop after this many ticks.
    #[arg(long)]
    pub ticks: Option<u64>,
    /// Replace the scenario's length: stop after this many wall-clock seconds.
    #[arg(long)]
    pub(crate) wall_seconds: Option<f64>,
    /// Replace the scenario's seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// No progress line.
    #[arg(long, short)]
    pub quiet: bool,
    /// Write the report JSON here.
    #[arg(long)]
    pub report: Option<PathBuf>,
}

pub fn execute(args: SoakArgs) -> ExitCode {
    let usage = |msg: String| {
        eprintln!("ncchannel soak: {msg}");
        ExitCode::from(exit::USAGE)
    };
    if args
        .wall_seconds
        .is_some_and(|s| !(s.is_finite() && s > 0.0 && s <= 1e7))
    {
        return usage("--wall-seconds must be in (0, 1e7]".into());
    }
    let path = match crate::params::shipped::locate(&args.scenario) {
        Ok(p) => p,
        Err(e) => return usage(e.to_string()),
    };
    let path = &path;
    let scenario = match Scenario::load(path) {
        Ok(s) => s,
        Err(e) => return usage(e.to_string()),
    };
    let length = (args.blocks.is_some() || args.ticks.is_some() || args.wall_seconds.is_some())
        .then_some(Length {
            blocks: args.blocks,
            ticks: args.ticks,
            sim_seconds: None,
            wall_seconds: args.wall_seconds,
        });
    // Virtual time runs to its end (seconds); real time stops in order on SIGINT/SIGTERM.
    let signal = if args.realtime || scenario.clock == ClockSpec::Realtime {
        match super::signal::StopSignal::install() {
            Ok(s) => Some(s),
            Err(e) => {
                eprintln!("ncchannel soak: cannot handle SIGINT/SIGTERM: {e}");
                None
            }
        }
    } else {
        None
    };
    let opts = Options {
        stop: signal.as_ref().map(super::signal::StopSignal::flag),
        realtime: args.realtime,
        progress: !args.quiet,
        length,
        seed: args.seed,
    };
    let report = match run(&scenario, &opts) {
        Ok(r) => r,
        Err(e) => return usage(e.to_string()),
    };
    let _ = report.print_human(&mut std::io::stdout());
    if let Some(p) = &args.report {
        if let Err(e) = std::fs::write(p, report.to_json() + "\n") {
            eprintln!("ncchannel soak: --report {}: {e}", p.display());
            return ExitCode::from(exit::USAGE);
        }
    }
    ExitCode::from(
        if report.all_held && signal.as_ref().is_some_and(|s| s.raised()) {
            exit::STOPPED
        } else if report.all_held {
            exit::OK
        } else {
            exit::CHANNEL_ERROR
        },
    )
}
