//! `ncchannel soak SCENARIO.toml...`: run soak scenarios, print the human report, write the JSON
//! one, exit 0 when every invariant held, 1 when one was violated, 2 on bad usage. One
//! scenario with one seed writes the report of that run; several, `--seeds N` or
//! `--shard I/N` make a campaign (scenarios × seeds, or shard I of it) with a campaign report
//! that `ncchannel soak merge` joins (`crate::soak::campaign`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use crate::soak::campaign::{CampaignReport, CampaignRun, CampaignSpec, Shard};
use crate::soak::report::SoakReport;
use crate::soak::scenario::{ClockSpec, Length, Scenario};
use crate::soak::{run, Options};

use super::exit;

#[derive(Debug, Clone, clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct SoakArgs {
    #[command(subcommand)]
    pub merge: Option<SoakCommand>,
    /// Scenario files (see params/soak/; outside a clone, the shipped ones built into the
    /// binary); more than one makes a campaign.
    #[arg(required = true)]
    pub scenarios: Vec<PathBuf>,
    /// Run at the cycle period in wall-clock time instead of virtual time.
    #[arg(long)]
    pub(crate) realtime: bool,
    /// The real-time mode of the runtime thread (real-time runs only).
    #[command(flatten)]
    pub(crate) rt: crate::runtime::realtime::RealtimeArgs,
    /// Replace the scenario's length: stop after this many executed blocks.
    #[arg(long)]
    pub blocks: Option<u64>,
    /// Replace the scenario's length: stop after this many ticks.
    #[arg(long)]
    pub ticks: Option<u64>,
    /// Replace the scenario's length: stop after this many wall-clock seconds.
    #[arg(long)]
    pub(crate) wall_seconds: Option<f64>,
    /// Replace the scenario's seed (with --seeds: the first seed of every scenario).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Run every scenario with this many seeds: its seed (or --seed), seed + 1, … (a campaign).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub seeds: Option<u64>,
    /// Run only shard I of N of the campaign (1-based; runs I-1, I-1+N, … in scenario × seed
    /// order), with its own report for `soak merge`.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<Shard>,
    /// No progress line.
    #[arg(long, short)]
    pub quiet: bool,
    /// Write the report JSON here (- for standard output; the human report then goes to
    /// standard error).
    #[arg(long)]
    pub report: Option<PathBuf>,
}

#[derive(Debug, Clone, clap::Subcommand)]
pub enum SoakCommand {
    /// Join the campaign reports of all shards into one verdict: exit 0 when every run held,
    /// 1 when one was violated, 2 when a report is unreadable or a shard missing or twice.
    Merge(super::soak_merge::MergeArgs),
}

fn usage(msg: impl std::fmt::Display) -> ExitCode {
    eprintln!("ncchannel soak: {msg}");
    ExitCode::from(exit::USAGE)
}

/// A run that could not start: a usage error (exit 2), or the real-time mode refused under
/// `--rt-required` (exit 5, already said).
fn failed(e: crate::soak::SoakError) -> ExitCode {
    match e {
        crate::soak::SoakError::Realtime(_) => ExitCode::from(exit::REALTIME_REFUSED),
        e => usage(e),
    }
}

/// The human report's stream: standard error when the JSON report goes to standard output.
fn human_out(report: Option<&Path>) -> Box<dyn std::io::Write> {
    if report.is_some_and(crate::destination::is_stdout) {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout())
    }
}

pub fn execute(args: SoakArgs) -> ExitCode {
    if let Some(SoakCommand::Merge(m)) = args.merge {
        return super::soak_merge::execute(m);
    }
    if args
        .wall_seconds
        .is_some_and(|s| !(s.is_finite() && s > 0.0 && s <= 1e7))
    {
        return usage("--wall-seconds must be in (0, 1e7]");
    }
    let mut scenarios = Vec::new();
    for path in &args.scenarios {
        let loaded = crate::params::shipped::locate(path)
            .map_err(|e| e.to_string())
            .and_then(|p| Scenario::load(&p).map_err(|e| e.to_string()));
        match loaded {
            Ok(s) => scenarios.push(s),
            Err(e) => return usage(e),
        }
    }
    let length = (args.blocks.is_some() || args.ticks.is_some() || args.wall_seconds.is_some())
        .then_some(Length {
            blocks: args.blocks,
            ticks: args.ticks,
            sim_seconds: None,
            wall_seconds: args.wall_seconds,
        });
    // Virtual time runs to its end (seconds); real time stops in order on SIGINT/SIGTERM.
    let realtime = args.realtime || scenarios.iter().any(|s| s.clock == ClockSpec::Realtime);
    if args.rt.any() && !realtime {
        return usage(
            "the --rt-… options of the real-time mode need --realtime (or a real-time scenario)",
        );
    }
    let signal = if realtime {
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
        rt: args.rt.clone(),
    };
    let stopped = || signal.as_ref().is_some_and(|s| s.raised());
    let campaign = scenarios.len() > 1 || args.seeds.is_some() || args.shard.is_some();
    let held = if campaign {
        match run_campaign(&args, &scenarios, opts, &stopped) {
            Ok(held) => held,
            Err(code) => return code,
        }
    } else {
        let report = match run(&scenarios[0], &opts) {
            Ok(r) => r,
            Err(e) => return failed(e),
        };
        let _ = report.print_human(&mut *human_out(args.report.as_deref()));
        if let Some(p) = &args.report {
            if !super::out::write_report("soak", p, &report.to_json()) {
                return ExitCode::from(exit::USAGE);
            }
        }
        report.all_held
    };
    ExitCode::from(if held && stopped() {
        exit::STOPPED
    } else if held {
        exit::OK
    } else {
        exit::CHANNEL_ERROR
    })
}

/// Run the campaign's runs of `--shard` (all without it), one after the other; write the
/// campaign report. Ok(every run held) or the exit code of a usage error.
fn run_campaign(
    args: &SoakArgs,
    scenarios: &[Scenario],
    mut opts: Options,
    stopped: &dyn Fn() -> bool,
) -> Result<bool, ExitCode> {
    let names = args
        .scenarios
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let spec = CampaignSpec::new(names, args.seed, args.seeds.unwrap_or(1)).map_err(usage)?;
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    let plan = spec.plan(shard, |i| scenarios[i].seed);
    let mut out = human_out(args.report.as_deref());
    let mut runs = Vec::new();
    for p in &plan {
        if stopped() {
            break;
        }
        opts.seed = Some(p.seed);
        let report: SoakReport = run(&scenarios[p.scenario], &opts).map_err(failed)?;
        let _ = report.print_human(&mut *out);
        runs.push(CampaignRun {
            index: p.index,
            report,
        });
    }
    let report = CampaignReport::new(spec, shard, plan.len(), runs);
    let _ = report.print_human(&mut *out);
    if let Some(p) = &args.report {
        if !super::out::write_report("soak", p, &report.to_json()) {
            return Err(ExitCode::from(exit::USAGE));
        }
    }
    Ok(report.all_held)
}
