//! `ncchannel soak SCENARIO.toml...`: run soak scenarios, print the human report, write the JSON
//! one, exit 0 when every invariant held, 1 when one was violated, 2 on bad usage. One
//! scenario with one seed writes the report of that run; several, `--seeds N` or
//! `--shard I/N` make a campaign (scenarios × seeds, or shard I of it) with a campaign report
//! that `ncchannel soak merge` joins (`crate::soak::campaign`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use crate::soak::campaign::{CampaignReport, CampaignRun, CampaignSpec, Shard};
use crate::soak::report::{RunStatus, SoakReport};
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
    /// standard error). Until the run ends the file holds an `incomplete` placeholder; the
    /// report replaces it whole (docs/campaigns.md).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// The campaign run this shard belongs to (a CI run number, a Job's uid), recorded in the
    /// campaign report: `soak merge` refuses shard reports of different runs.
    #[arg(long, env = "NCCHANNEL_SOAK_RUN_ID", value_name = "ID")]
    pub run_id: Option<String>,
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
    // SIGINT/SIGTERM stop the run in order, in virtual time as in real time: the report of
    // what ran, marked interrupted, and the exit code of the signal.
    let realtime = args.realtime || scenarios.iter().any(|s| s.clock == ClockSpec::Realtime);
    if args.rt.any() && !realtime {
        return usage(
            "the --rt-… options of the real-time mode need --realtime (or a real-time scenario)",
        );
    }
    let signal = match super::signal::StopSignal::install() {
        Ok(s) => Some(s),
        Err(e) => {
            eprintln!("ncchannel soak: cannot handle SIGINT/SIGTERM: {e}");
            None
        }
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
    let (held, interrupted) = if campaign {
        match run_campaign(&args, &scenarios, opts, &stopped) {
            Ok(r) => r,
            Err(code) => return code,
        }
    } else {
        let scenario = &scenarios[0];
        let placeholder =
            SoakReport::incomplete(&scenario.path, args.seed.unwrap_or(scenario.seed));
        if !super::out::mark_report_incomplete(
            "soak",
            args.report.as_deref(),
            &placeholder.to_json(),
        ) {
            return ExitCode::from(exit::USAGE);
        }
        let report = match run(scenario, &opts) {
            Ok(r) => r,
            Err(e) => return failed(e),
        };
        let _ = report.print_human(&mut *human_out(args.report.as_deref()));
        if let Some(p) = &args.report {
            if !super::out::write_report("soak", p, &report.to_json()) {
                return ExitCode::from(exit::USAGE);
            }
        }
        (report.all_held, report.status != RunStatus::Complete)
    };
    if interrupted {
        // Stopped by a signal: the report says interrupted; the exit code is the one a shell
        // gives a process the signal ended (130 for SIGINT), whatever the invariants did.
        let (name, code) = signal
            .as_ref()
            .and_then(super::signal::StopSignal::which)
            .unwrap_or(("a signal", exit::SECOND_SIGNAL));
        eprintln!("ncchannel soak: interrupted by {name}; the report covers what ran until then");
        return ExitCode::from(code);
    }
    ExitCode::from(if held { exit::OK } else { exit::CHANNEL_ERROR })
}

/// Run the campaign's runs of `--shard` (all without it), one after the other; write the
/// campaign report. Ok((every run held, a signal stopped it)) or the exit code of a usage
/// error.
fn run_campaign(
    args: &SoakArgs,
    scenarios: &[Scenario],
    mut opts: Options,
    stopped: &dyn Fn() -> bool,
) -> Result<(bool, bool), ExitCode> {
    let names = args
        .scenarios
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    let spec = CampaignSpec::new(names, args.seed, args.seeds.unwrap_or(1)).map_err(usage)?;
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    let plan = spec.plan(shard, |i| scenarios[i].seed);
    let placeholder =
        CampaignReport::incomplete(spec.clone(), shard).with_run_id(args.run_id.clone());
    if !super::out::mark_report_incomplete("soak", args.report.as_deref(), &placeholder.to_json()) {
        return Err(ExitCode::from(exit::USAGE));
    }
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
    let report =
        CampaignReport::new(spec, shard, plan.len(), runs).with_run_id(args.run_id.clone());
    let _ = report.print_human(&mut *out);
    if let Some(p) = &args.report {
        if !super::out::write_report("soak", p, &report.to_json()) {
            return Err(ExitCode::from(exit::USAGE));
        }
    }
    Ok((report.all_held, report.status != RunStatus::Complete))
}
