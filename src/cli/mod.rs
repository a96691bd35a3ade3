//! The command line: one file per subcommand, each with its clap arguments and an `execute`.
//!
//! `main.rs` only parses and dispatches; the work lives here so integration tests can call it.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

pub(crate) mod bench;
pub(crate) mod bench_ads;
mod bench_cyclictest;
pub(crate) mod bench_live;
mod bench_worst;
pub mod check;
pub(crate) mod init;
mod logger;
pub(crate) mod manual;
pub(crate) mod out;
pub mod preview;
pub(crate) mod receive;
mod receive_stop;
pub(crate) mod run;
pub(crate) mod serve;
pub(crate) mod serve_soak;
pub(crate) mod signal;
pub(crate) mod soak;
pub(crate) mod soak_merge;
pub(crate) mod stream;
mod web_view;

/// Exit codes of the command-line contract (README "Two commands").
pub mod exit {
    /// The program ended normally (or the check found nothing).
    pub const OK: u8 = 0;
    /// A channel error (or a check found errors).
    pub(crate) const CHANNEL_ERROR: u8 = 1;
    /// Bad usage or bad parameter lists.
    pub(crate) const USAGE: u8 = 2;
    /// `--max-ticks` reached before the program ended.
    pub const MAX_TICKS: u8 = 3;
    /// SIGINT or SIGTERM stopped `run --realtime` before the end (the log and summary are
    /// complete up to the stop). A soak a signal stops exits 128 + the signal's number
    /// instead (130, 143), its report marked interrupted.
    pub(crate) const STOPPED: u8 = 4;
    /// `--rt-required` (runtime.toml `realtime.required`): the system refused a part of the
    /// real-time mode; nothing ran.
    pub(crate) const REALTIME_REFUSED: u8 = 5;
    /// A second SIGINT/SIGTERM during the orderly stop: exit at once, as a shell reports a
    /// process killed by SIGINT (128 + 2).
    pub(crate) const SECOND_SIGNAL: u8 = 130;
}

/// The real-time mode entered on the calling thread (the runtime's, after the command's other
/// threads started): refusals and the mode's line said through `say`; with `required`, a
/// refusal is [`exit::REALTIME_REFUSED`] for the command to return.
pub(crate) fn enter_realtime(
    mode: &crate::runtime::realtime::RealtimeConfig,
    command: &str,
    mut say: impl FnMut(std::fmt::Arguments<'_>),
) -> Result<crate::runtime::realtime::Entered, ExitCode> {
    let done = crate::runtime::realtime::enter_saying(mode, command, &mut say)
        .map_err(|_| ExitCode::from(exit::REALTIME_REFUSED))?;
    if let Some(line) = done.summary() {
        say(format_args!("{line}"));
    }
    Ok(done)
}

#[derive(Debug, Parser)]
#[command(
    name = "ncchannel",
    version,
    about = "An emulated TwinCAT 3 CNC / ISG channel"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Measure the runtime's cycle in real time against a bare spin_sleep loop.
    Bench(bench::BenchArgs),
    /// Check NC programs, parameter lists and soak scenarios; errors as file:line:col.
    Check(check::CheckArgs),
    /// Write the shipped parameter lists, scenarios and example programs into a folder to edit.
    Init(init::InitArgs),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell).
    Completions(manual::CompletionsArgs),
    /// Print a man page (roff): the main one, a subcommand's, or write them all (`--dir`).
    Man(manual::ManArgs),
    /// Run one program on a channel, optionally streamed by the built-in feeder.
    Run(run::RunArgs),
    /// Serve the channels over ADS/TCP in real time.
    Serve(serve::ServeArgs),
    /// Split received NC data into programs by start/end markers.
    Receive(receive::ReceiveArgs),
    /// Soak test: run scenarios (params/soak/*.toml) and check their invariants; a campaign
    /// of scenarios × seeds, or one shard of it; `soak merge` joins shard reports.
    Soak(soak::SoakArgs),
    /// Stream an NC file into a channel over ADS (whole lines, CR LF, retry when busy).
    Stream(stream::StreamArgs),
}

impl Cli {
    pub fn execute(self) -> ExitCode {
        logger::init();
        match self.command {
            Some(Command::Bench(args)) => bench::execute(args),
            Some(Command::Check(args)) => check::execute(args),
            Some(Command::Init(args)) => init::execute(args),
            Some(Command::Completions(args)) => manual::completions(args),
            Some(Command::Man(args)) => manual::man(args),
            Some(Command::Receive(args)) => receive::execute(args),
            Some(Command::Run(args)) => run::execute(args),
            Some(Command::Serve(args)) => serve::execute(args),
            Some(Command::Soak(args)) => soak::execute(args),
            Some(Command::Stream(args)) => stream::execute(args),
            None => run::execute(run::RunArgs::demo()),
        }
    }
}
