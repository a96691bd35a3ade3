//! `bench --load worst`: the inputs that cost a tick the most, each run to its end (or
//! `--worst-ticks`) on channel 1, with the worst tick and what it was doing. The goal is no
//! tick over 2 ms on an idle machine for any input (README "The cycle").
//!
//! The ticks run back to back (virtual time): a tick's work is the same as in real time, and a
//! run over millions of labels takes seconds, not minutes. A wait for the program loader is
//! the simulated file system's time and counted apart (`runtime.rs`).

use std::fmt::Write as _;
use std::path::Path;
use std::process::ExitCode;
use std::sync::atomic::AtomicU64;
use std::sync::Arc;
use std::time::Duration;

use super::out::Stdout;
use crate::machine::{Machine, Op, Reply, StopWhen};
use crate::report::event::EventLog;
use crate::runtime::{Clock, Runtime, Tick};

/// The worst inputs at full size: labels, bytes of the subprogram, declared variables, blocks
/// under the notification storm.
const LABELS: usize = 4_000_000;
const SUBPROGRAM_BYTES: usize = 200_000_000;
const VARIABLES: usize = 90_000;
const STORM_BLOCKS: usize = 900;

/// At a real-time priority the ticks run in chunks of this many with [`CHUNK_PAUSE`] between:
/// Linux throttles a real-time thread that runs 950 ms of a second without a pause
/// (sched_rt_runtime_us, sched(7)) for the rest of it, a 50 ms gap that would count in a tick.
const CHUNK_TICKS: u64 = 100;
const CHUNK_PAUSE: Duration = Duration::from_millis(5);

/// The tick budget of the worst inputs' goal, µs.
const GOAL_US: f64 = 2000.0;

/// One worst input: its name, what it is, its program files.
struct Input {
    name: &'static str,
    what: String,
    files: Vec<(&'static str, String)>,
    /// Notification watches (1 ms on change) on channel 1 while it runs.
    watches: u64,
}

/// The inputs at `scale` (1 = full size).
fn inputs(scale: f64) -> Vec<Input> {
    let n = |full: usize| ((full as f64 * scale) as usize).max(1);
    vec![
        storm(n(STORM_BLOCKS)),
        labels(n(LABELS)),
        subprogram(n(SUBPROGRAM_BYTES)),
        variables(n(VARIABLES)),
    ]
}

/// A `$GOTO` over `count` string labels to the last one: the label index fills (65,536) and
/// the jump's label is searched past it.
fn labels(count: usize) -> Input {
    let mut p = String::from("%labels\nN1 G01 X0 F6000\n$GOTO [LAST]\nN2 X99\n");
    for i in 0..count {
        let _ = writeln!(p, "[L{i}] P1={i}");
    }
    p.push_str("[LAST] X5\nM30\n");
    Input {
        name: "labels",
        what: format!("$GOTO over {count} labels"),
        files: vec![("labels.nc", p)],
        watches: 0,
    }
}

/// A main program calling a subprogram of `bytes` bytes of arithmetic blocks (no motion, so
/// the decoder's budget of blocks a tick runs through the whole file).
fn subprogram(bytes: usize) -> Input {
    let mut sub = String::with_capacity(bytes + 64);
    sub.push_str("%big\nP1=0\n");
    while sub.len() < bytes {
        sub.push_str("P1=P1+1\n");
    }
    sub.push_str("M17\n");
    let main = "%sub_main\nG01 X0 Y0 F60000\nL big.nc\nM30\n".to_string();
    Input {
        name: "subprogram",
        what: format!("a subprogram of {} MB", bytes / 1_000_000),
        files: vec![("sub_main.nc", main), ("big.nc", sub)],
        watches: 0,
    }
}

/// `count` variable declarations in one `#VAR` block, then a use of the last.
fn variables(count: usize) -> Input {
    let mut p = String::from("%vars\n#VAR\n");
    for i in 0..count {
        let _ = writeln!(p, "V.L.A{i} = {i}");
    }
    let _ = write!(p, "#ENDVAR\nV.L.A{} = 1\nG01 X1 F6000\nM30\n", count - 1);
    Input {
        name: "variables",
        what: format!("{count} variable declarations"),
        files: vec![("vars.nc", p)],
        watches: 0,
    }
}

/// `blocks` collinear 1 mm moves at 60 m/min (about one a tick) with every notification
/// watch the machine holds (1 ms on change on `ncc_blocks_executed_r`, changing each tick).
fn storm(blocks: usize) -> Input {
    let mut p = String::from("%storm\nG01 X0 F60000\n");
    for i in 1..=blocks {
        let _ = writeln!(p, "X{i}");
    }
    p.push_str("M30\n");
    Input {
        name: "notifications",
        what: format!(
            "{} notifications at 1 ms over {blocks} blocks",
            crate::machine::watch::MAX_WATCHES
        ),
        files: vec![("storm.nc", p)],
        watches: crate::machine::watch::MAX_WATCHES as u64,
    }
}

/// The options of `--load worst`.
pub(super) struct WorstBench<'a> {
    pub params: &'a Path,
    pub scale: f64,
    pub max_ticks: u64,
    /// The real-time mode the inputs run in (`--rt-…`): at a real-time priority on a CPU of
    /// its own, a tick's time is its work, not the other processes' turns.
    pub mode: crate::runtime::realtime::RealtimeConfig,
}

pub(super) fn execute(b: &WorstBench<'_>) -> Result<ExitCode, String> {
    let mut out = Stdout::new();
    out.line(format_args!(
        "bench --load worst: each input on channel 1, ticks back to back, at most {} ticks; goal: no tick over {GOAL_US:.0} µs; figures in µs",
        b.max_ticks
    ));
    // One program loader for every input, started before the real-time mode so it runs off
    // the runtime's CPU at normal priority.
    let loader = crate::source::loader::Loader::start();
    let entered = crate::runtime::realtime::enter_saying(&b.mode, "bench", super::out::say)
        .map_err(|_| "the real-time mode is incomplete (--rt-required)".to_string())?;
    out.line(format_args!(
        "real-time mode: {}",
        entered.summary().map_or("off".to_string(), |s| s
            .trim_start_matches("real-time mode: ")
            .to_string())
    ));
    let mut over = 0;
    for input in inputs(b.scale) {
        let line = run_input(b, &input, &loader)?;
        if line.1 > GOAL_US {
            over += 1;
        }
        out.line(format_args!("{}", line.0));
    }
    out.line(format_args!(
        "inputs with a tick over {GOAL_US:.0} µs: {over}"
    ));
    out.finish_or_say("ncchannel bench");
    Ok(ExitCode::from(super::exit::OK))
}

/// Run one input; its report lines and its longest tick, µs.
fn run_input(
    b: &WorstBench<'_>,
    input: &Input,
    loader: &crate::source::loader::Loader,
) -> Result<(String, f64), String> {
    let dir = tempfile::tempdir().map_err(|e| format!("a temporary folder: {e}"))?;
    for (name, text) in &input.files {
        std::fs::write(dir.path().join(name), text)
            .map_err(|e| format!("{}: {e}", dir.path().join(name).display()))?;
    }
    let mut config = super::run::load_config(b.params)?;
    super::run::search_first(
        &mut config,
        0,
        dir.path().to_path_buf(),
        "ncchannel bench --load worst",
    );
    let channels = crate::setup::channels(&config, false, loader).map_err(|e| e.to_string())?;
    let period = Duration::from_micros(config.runtime.cycle_period_us);
    let mut machine = Machine::new(channels, EventLog::disabled(), StopWhen::ProgramsFinished);
    machine.keep_worst_tick();
    let samples = Arc::new(AtomicU64::new(0));
    for _ in 0..input.watches {
        let w = crate::ads::objects::bench_watch(1, Arc::clone(&samples))
            .ok_or("no encoder for ncc_blocks_executed_r")?;
        machine.watch(w);
    }
    let tick0 = Tick::first(period, Clock::Virtual);
    if let Reply::Command(Err(e)) = machine.apply(&tick0, 1, Op::Start(input.files[0].0.into())) {
        return Err(format!("{}: {e}", input.files[0].0));
    }
    let (mut rt, _tx) = Runtime::new(machine, period, Clock::Virtual);
    let summary = if b.mode.priority.is_some() {
        let mut ticks = 0;
        loop {
            let s = rt.run(Some(CHUNK_TICKS.min(b.max_ticks - ticks)));
            ticks += s.ticks;
            if s.end != crate::runtime::RunEnd::MaxTicks || ticks >= b.max_ticks {
                break crate::runtime::RunSummary { ticks, ..s };
            }
            std::thread::sleep(CHUNK_PAUSE);
        }
    } else {
        rt.run(Some(b.max_ticks))
    };
    let (machine, stats) = rt.into_inner();
    let max_us = stats.work.max_us();
    let status = machine
        .channels()
        .first()
        .map(crate::channel::Channel::status);
    let mut line = format!(
        "{:<14} {}: {} ticks{}, tick work p50 {:.1} p99 {:.1} max {:.1}{}",
        input.name,
        input.what,
        summary.ticks,
        if summary.end == crate::runtime::RunEnd::MaxTicks {
            " (stopped at the limit)"
        } else {
            ""
        },
        stats.work.quantile_us(0.5),
        stats.work.quantile_us(0.99),
        max_us,
        if max_us > GOAL_US {
            "  OVER THE GOAL"
        } else {
            ""
        },
    );
    if let Some((code, msg)) = status.and_then(|s| s.last_error) {
        let _ = write!(line, "\n{:<14} channel error {code}: {msg}", "");
    }
    if let Some(w) = machine.worst_tick() {
        let _ = write!(line, "\n{:<14} worst: {w}", "");
    }
    Ok((line, max_us))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_inputs_scale_and_name_their_size() {
        let small = inputs(0.001);
        let what: Vec<&str> = small.iter().map(|i| i.what.as_str()).collect();
        assert_eq!(
            what,
            [
                "1024 notifications at 1 ms over 1 blocks",
                "$GOTO over 4000 labels",
                "a subprogram of 0 MB",
                "90 variable declarations",
            ]
        );
        assert!(small[2].files[1].1.len() >= 200_000 && small[2].files[1].1.len() < 200_100);
        assert!(small[1].files[0]
            .1
            .ends_with("[L3999] P1=3999\n[LAST] X5\nM30\n"));
    }
}
