//! `ncchannel bench`: the runtime in real time under a streaming load, against a bare
//! spin_sleep loop measured in the same run, so lateness is compared on the same machine at
//! the same moment.
//!
//! The load is real: `--channels N` channels, each streaming its own endless generated
//! program at full rate through its own stream interface, decoder and motion (the soak cycle
//! without faults, so the invariants are checked too).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use super::out::{say, Stdout};
use crate::runtime::realtime::{RealtimeArgs, RealtimeConfig, ThreadSched};
use crate::runtime::{bare_loop, Clock, Runtime};
use crate::soak::load::{streaming_channels, Mix};
use crate::vocab::stats::Histogram;

use super::bench_ads::{AdsBench, LineKind};

/// What the bench measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum BenchLoad {
    /// The cycle's work and lateness against a bare spin_sleep loop, channels streaming
    /// in-process (default start-up list params/soak/startup4.lis).
    Cycle,
    /// The stream interface's throughput over a real ADS/TCP connection: one sequential
    /// client streaming 17-byte lines into channel 1 (default start-up list params/startup.lis,
    /// the shipped settings).
    AdsStream,
    /// What the live web view of `serve --http` costs the runtime: tick work with no page and
    /// with --pages pages on the event stream, alternating, and the update rate a page gets
    /// (default start-up list params/startup.lis).
    LiveView,
    /// The inputs that cost a tick the most (4 M labels under a `$GOTO`, a 200 MB
    /// subprogram, 90,000 variable declarations, every notification handle at 1 ms), each
    /// on channel 1 with its worst tick and what it was doing (default start-up list
    /// params/startup.lis).
    Worst,
}

#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// What to measure.
    #[arg(long, value_enum, default_value_t = BenchLoad::Cycle)]
    pub load: BenchLoad,
    /// Cycle time in microseconds.
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u64).range(10..=1_000_000))]
    pub period_us: u64,
    /// Seconds to run the runtime (the bare loop runs as long again, the two alternating
    /// about every second).
    #[arg(long, default_value_t = 5.0)]
    pub seconds: f64,
    /// Channels streaming at full rate (a 992-byte write attempt each tick), each with its
    /// own generated program, stream, decoder and motion.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=12))]
    pub channels: u32,
    /// Start-up list the channels are built from (its channels are reused in turn when it
    /// has fewer than --channels); default by --load (outside a clone, the shipped lists built
    /// into the binary).
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// --load cycle: what the channels' generated programs hold.
    #[arg(long, value_enum, default_value_t = Mix::Params)]
    pub mix: Mix,
    /// --load ads-stream: what the streamed 17-byte lines do.
    #[arg(long, value_enum, default_value_t = LineKind::Params)]
    pub lines: LineKind,
    /// --load ads-stream: pause before a write answered busy (0x708) is sent again, µs.
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u64).range(0..=1_000_000))]
    pub retry_us: u64,
    /// --load live-view: pages reading the event stream while measured.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=crate::http::MAX_PAGE_CONNECTIONS as u64))]
    pub pages: u64,
    /// --load cycle: notification handles evaluated in the cycle while measured, 1 ms on
    /// change on each channel's object of --notify-on in turn (as the ADS server registers
    /// them, samples counted instead of sent).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u64).range(0..=crate::machine::watch::MAX_WATCHES as u64))]
    pub notifications: u64,
    /// --load cycle: what the --notifications handles watch: COM `ncc_blocks_executed_r`, or
    /// the HLI symbol `…mode_and_state.state_r` (by handle, as pyads and ads-client subscribe
    /// a symbol by name).
    #[arg(long, value_enum, default_value_t = NotifyOn::Com)]
    pub notify_on: NotifyOn,
    /// --load worst: the inputs' size, a fraction of the full one (1 = 4 M labels, 200 MB, ...).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// --load worst: most ticks each input runs.
    #[arg(long, default_value_t = 200_000, value_parser = clap::value_parser!(u64).range(1..))]
    pub max_ticks: u64,
    /// Seed of the generated programs and packet sizes.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write a lateness histogram (runtime, bare loop and cyclictest) here: SVG for
    /// FILE.svg, PNG for FILE.png.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// The real-time mode of the runtime thread, the bare loop and cyclictest (over the
    /// start-up list's runtime.toml `[realtime]`).
    #[command(flatten)]
    pub rt: RealtimeArgs,
}

/// What `--notifications` handles watch (`--notify-on`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum NotifyOn {
    /// COM `ncc_blocks_executed_r` of each channel (changes as blocks execute).
    Com,
    /// HLI `…mode_and_state.state_r` of each channel (a symbol read live from the status).
    Hli,
}

fn print_hist(out: &mut Stdout, name: &str, h: &Histogram) {
    out.line(format_args!(
        "{name:<20} p50 {:>8.2}  p99 {:>8.2}  p99.9 {:>8.2}  max {:>9.2}  (n = {})",
        h.quantile_us(0.5),
        h.quantile_us(0.99),
        h.quantile_us(0.999),
        h.max_us(),
        h.count()
    ));
}

/// The options checked before anything runs: `--plot`'s format and `--seconds`.
fn check_args(args: &BenchArgs) -> Result<(), String> {
    if let Some(p) = &args.plot {
        if crate::destination::is_stdout(p) {
            return Err("--plot -: the figures go to standard output; name a file".into());
        }
        crate::report::picture::Format::of(p).map_err(|e| format!("--plot {e}"))?;
    }
    if !(args.seconds.is_finite() && args.seconds > 0.0 && args.seconds <= 3600.0) {
        return Err("--seconds must be in (0, 3600]".into());
    }
    if !(args.scale.is_finite() && args.scale > 0.0 && args.scale <= 1.0) {
        return Err("--scale must be in (0, 1]".into());
    }
    Ok(())
}

/// The start-up list: --params, else `default` (from the current folder or the shipped set).
fn start_list(args: &BenchArgs, default: &str) -> Result<PathBuf, String> {
    let given = args
        .params
        .clone()
        .unwrap_or_else(|| PathBuf::from(default));
    crate::params::shipped::locate(&given).map_err(|e| e.to_string())
}

/// A usage error of `bench`: said on stderr, exit 2.
fn usage(msg: String) -> ExitCode {
    eprintln!("ncchannel bench: {msg}");
    ExitCode::from(super::exit::USAGE)
}

pub fn execute(args: BenchArgs) -> ExitCode {
    if let Err(msg) = check_args(&args) {
        return usage(msg);
    }
    let default_list = match args.load {
        BenchLoad::Cycle => "params/soak/startup4.lis",
        BenchLoad::AdsStream | BenchLoad::LiveView | BenchLoad::Worst => "params/startup.lis",
    };
    let params = match start_list(&args, default_list) {
        Ok(p) => p,
        Err(e) => return usage(e),
    };
    match args.load {
        BenchLoad::Cycle => cycle(&args, &params),
        BenchLoad::AdsStream => super::bench_ads::execute(&AdsBench {
            params: &params,
            seconds: args.seconds,
            lines: args.lines,
            retry: Duration::from_micros(args.retry_us),
        }),
        BenchLoad::LiveView => super::bench_live::execute(&super::bench_live::LiveBench {
            params: &params,
            seconds: args.seconds,
            pages: args.pages as usize,
        })
        .unwrap_or_else(usage),
        BenchLoad::Worst => super::bench_worst::execute(&super::bench_worst::WorstBench {
            params: &params,
            scale: args.scale,
            max_ticks: args.max_ticks,
            mode: args.rt.over(
                &crate::params::load(&params)
                    .map(|c| c.runtime.realtime)
                    .unwrap_or_default(),
            ),
        })
        .unwrap_or_else(usage),
    }
}

/// `--notifications` handles on `--notify-on` objects of the channels in turn, counting their
/// samples into `samples`.
fn add_watches(
    args: &BenchArgs,
    cycle: &mut crate::soak::driver::SoakCycle,
    samples: &Arc<AtomicU64>,
) -> Result<(), String> {
    let watches = match args.notify_on {
        NotifyOn::Com => (0..args.notifications)
            .filter_map(|k| {
                let ch = (k % u64::from(args.channels)) as u16 + 1;
                crate::ads::objects::bench_watch(ch, Arc::clone(samples))
            })
            .collect(),
        NotifyOn::Hli => crate::ads::objects::bench_hli_watches(
            args.channels as u16,
            args.notifications as usize,
            samples,
        ),
    };
    if watches.len() as u64 != args.notifications {
        return Err(format!("no encoder for {:?}", args.notify_on));
    }
    for w in watches {
        if !cycle.machine_mut().watch(w) {
            return Err(format!(
                "more than {} notifications",
                crate::machine::watch::MAX_WATCHES
            ));
        }
    }
    Ok(())
}

/// `--load cycle`: the runtime with channels streaming in-process against a bare loop and,
/// when installed, cyclictest, in slices of about a second taking turns, so a change of load
/// on a shared machine (another build starting) hits all alike.
fn cycle(args: &BenchArgs, params: &Path) -> ExitCode {
    let loader = crate::source::loader::Loader::start();
    let (cycle, _) = match streaming_channels(params, args.channels, args.seed, args.mix, &loader) {
        Ok(c) => c,
        Err(e) => return usage(format!("{}: {e}", params.display())),
    };
    let period = Duration::from_micros(args.period_us);
    let ticks = ((args.seconds * 1e6) / args.period_us as f64)
        .ceil()
        .max(1.0) as u64;
    let slices = (ticks / (1_000_000 / args.period_us).max(1)).clamp(1, 3600);
    let mut out = Stdout::new();
    let cyclictest = super::bench_cyclictest::find();
    out.line(format_args!(
        "bench: period {} µs, {} channels streaming ({}), {ticks} ticks runtime + {ticks} ticks bare spin_sleep loop{}, taking turns in {slices} slices",
        args.period_us,
        args.channels,
        match args.mix {
            Mix::Params => "parameter blocks",
            Mix::Soak => "the soak's mix of moves, arcs and M8/M9",
        },
        if cyclictest.is_some() { format!(" + {ticks} cyclictest loops") } else { String::new() }
    ));
    let samples = Arc::new(AtomicU64::new(0));
    let mut cycle = cycle;
    cycle.machine_mut().keep_worst_tick();
    if let Err(msg) = add_watches(args, &mut cycle, &samples) {
        return usage(msg);
    }
    if args.notifications > 0 {
        out.line(format_args!(
            "notifications: {} handles on {:?} objects, 1 ms on change, evaluated in the cycle",
            args.notifications, args.notify_on
        ));
    }
    // Every thread of the bench runs by now (the loader): the real-time mode keeps them off
    // the runtime's CPU; the bare loop and cyclictest get the same mode.
    let file_mode = crate::params::load(params)
        .map(|c| c.runtime.realtime)
        .unwrap_or_default();
    let entered =
        match crate::runtime::realtime::enter_saying(&args.rt.over(&file_mode), "bench", say) {
            Ok(e) => e,
            Err(_) => return ExitCode::from(super::exit::REALTIME_REFUSED),
        };
    out.line(format_args!(
        "real-time mode: {}",
        entered.summary().map_or_else(
            || "off (--rt-priority, --rt-cpu, --rt-lock-memory; README \"The cycle\")".to_string(),
            |s| s.trim_start_matches("real-time mode: ").to_string()
        )
    ));
    let (mut rt, _tx) = Runtime::new(cycle, period, Clock::RealTime);
    let plan = Slices {
        period,
        ticks,
        slices,
        mode: &entered.effective,
        cyclictest: cyclictest.as_deref(),
    };
    let m = match measure(&mut rt, &plan) {
        Ok(m) => m,
        Err(msg) => return usage(msg),
    };
    let (cycle, stats) = rt.into_inner();
    let warm = match warm_work(args, params, &loader, period, ticks) {
        Ok(h) => h,
        Err(e) => return usage(format!("{}: {e}", params.display())),
    };
    print_figures(&mut out, &stats, &m, cyclictest.is_some());
    print_hist(&mut out, "tick work, warm", &warm);
    out.line(
        "(warm: the same ticks back to back in virtual time, the caches left warm by the tick before; the real-time figure adds the memory other work on the machine evicted between ticks)",
    );
    print_load(&mut out, &cycle, m.wall, args, &samples);
    if let Some(p) = &args.plot {
        let picture = crate::report::lateness::Lateness {
            runtime: &stats.lateness,
            bare: &m.bare,
            cyclictest: cyclictest.is_some().then_some(&m.cyclictest),
            period,
        };
        if let Err(e) = crate::report::picture::write(p, &picture) {
            return usage(format!("--plot {e}"));
        }
        out.line(format_args!("histogram written to {}", p.display()));
    }
    out.finish_or_say("ncchannel bench");
    ExitCode::from(super::exit::OK)
}

/// The tick work of the same load run back to back (virtual time): the same channels, seed,
/// notification handles and ticks, so the same work in each tick, with the caches kept warm by the tick before.
/// Set beside the real-time tick work, it tells the work itself from the cost of coming
/// back to caches that other processes (or other guests of the host) used in between: a
/// tick that takes a block runs code and data unused for many ticks, which on a shared
/// machine are no longer cached, whether the runtime slept or spun in between.
fn warm_work(
    args: &BenchArgs,
    params: &Path,
    loader: &crate::source::loader::Loader,
    period: Duration,
    ticks: u64,
) -> Result<Histogram, String> {
    let (mut cycle, _) = streaming_channels(params, args.channels, args.seed, args.mix, loader)?;
    // The same notification handles too: their evaluation is part of each tick's work.
    add_watches(args, &mut cycle, &Arc::new(AtomicU64::new(0)))?;
    let (mut rt, _tx) = Runtime::new(cycle, period, Clock::Virtual);
    rt.run(Some(ticks));
    Ok(rt.take_stats().work)
}

/// How the measured time is cut: `ticks` of each of the runtime, the bare loop and cyclictest
/// (when found), in `slices` turns.
struct Slices<'a> {
    period: Duration,
    ticks: u64,
    slices: u64,
    mode: &'a RealtimeConfig,
    cyclictest: Option<&'a Path>,
}

/// What the slices measured besides the runtime's own statistics.
struct Measured {
    bare: Histogram,
    cyclictest: Histogram,
    /// Wall time of the runtime's slices.
    wall: Duration,
    /// Minor page faults of the runtime thread during its slices.
    page_faults: Option<u64>,
}

fn measure(
    rt: &mut Runtime<crate::soak::driver::SoakCycle>,
    plan: &Slices<'_>,
) -> Result<Measured, String> {
    let mut m = Measured {
        bare: Histogram::new(),
        cyclictest: Histogram::new(),
        wall: Duration::ZERO,
        page_faults: Some(0),
    };
    let (ticks, slices) = (plan.ticks, plan.slices);
    for k in 0..slices {
        let n = ticks * (k + 1) / slices - ticks * k / slices;
        m.bare.merge(&bare_loop(plan.period, n));
        if let Some(program) = plan.cyclictest {
            let period_us = plan.period.as_micros() as u64;
            super::bench_cyclictest::run_slice(
                program,
                period_us,
                n,
                plan.mode,
                &mut m.cyclictest,
            )?;
        }
        // The bare loop ran in between: this slice keeps no schedule from the last one.
        rt.restart_schedule();
        let before = ThreadSched::current();
        m.wall += rt.run(Some(n)).wall;
        let after = ThreadSched::current();
        m.page_faults = match (m.page_faults, before, after) {
            (Some(sum), Some(b), Some(a)) => {
                Some(sum + a.minor_faults.saturating_sub(b.minor_faults))
            }
            _ => None,
        };
    }
    Ok(m)
}

/// p99 and max of `a` over those of `b` (NaN when `b`'s are 0).
fn ratios(a: &Histogram, b: &Histogram) -> (f64, f64) {
    let r = |x: f64, y: f64| if y > 0.0 { x / y } else { f64::NAN };
    (
        r(a.quantile_us(0.99), b.quantile_us(0.99)),
        r(a.max_us(), b.max_us()),
    )
}

fn print_figures(
    out: &mut Stdout,
    stats: &crate::vocab::stats::CycleStats,
    m: &Measured,
    cyclictest: bool,
) {
    out.line("all figures in µs");
    print_hist(out, "tick work", &stats.work);
    print_hist(out, "tick lateness", &stats.lateness);
    print_hist(out, "bare loop lateness", &m.bare);
    if cyclictest {
        print_hist(out, "cyclictest latency", &m.cyclictest);
    }
    out.line(format_args!("overruns             {}", stats.overruns));
    let (p99, max) = ratios(&stats.lateness, &m.bare);
    out.line(format_args!(
        "lateness ratio runtime / bare loop: p99 {p99:.2} (target ≤ 1.2), max {max:.2}"
    ));
    if cyclictest {
        let (p99, max) = ratios(&stats.lateness, &m.cyclictest);
        out.line(format_args!(
            "lateness ratio runtime / cyclictest: p99 {p99:.2}, max {max:.2}"
        ));
    } else {
        out.line(super::bench_cyclictest::INSTALL_HINT);
    }
    if let Some(f) = m.page_faults {
        out.line(format_args!(
            "page faults of the runtime thread during its ticks: {f}"
        ));
    }
}

/// The streaming load the runtime carried, its worst tick and the invariants.
fn print_load(
    out: &mut Stdout,
    cycle: &crate::soak::driver::SoakCycle,
    wall: Duration,
    args: &BenchArgs,
    samples: &AtomicU64,
) {
    let blocks = cycle.total_blocks;
    let (mut ok, mut rejected, mut bytes) = (0, 0, 0);
    for c in cycle.feed_counters() {
        ok += c.writes_ok;
        rejected += c.writes_rejected;
        bytes += c.bytes;
    }
    let wall = wall.as_secs_f64();
    out.line(format_args!(
        "load: {blocks} blocks executed ({:.0}/s), {ok} writes ok, {rejected} rejected (buffer full), {:.1} MB streamed in {wall:.2} s",
        blocks as f64 / wall.max(1e-9),
        bytes as f64 / 1e6,
    ));
    if let Some(w) = cycle.machine().worst_tick() {
        out.line(format_args!("worst tick of the machine: {w}"));
    }
    if args.notifications > 0 {
        out.line(format_args!(
            "notifications: {} samples queued",
            samples.load(Ordering::Relaxed)
        ));
    }
    let t = &cycle.tallies;
    let violations = t.order.violations + t.errors.violations + t.limits.violations;
    if violations > 0 {
        out.line(format_args!(
            "invariant violations during the bench: {violations}"
        ));
    }
}
