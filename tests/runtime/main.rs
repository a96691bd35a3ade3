//! The runtime and the process around it: ticks and channel time, the event log and report as
//! files, `serve` stopped by a signal, a closed standard output, the command line's outputs
//! (plots, `-` for standard output, check, completions, man page).

#[path = "../support/mod.rs"]
mod support;

mod anywhere;
mod cli_outputs;
mod closed_stdout;
mod event_log_cuts;
mod plc;
mod program_loader;
mod realtime;
mod runtime;
mod runtime_events;
mod serve_signals;
