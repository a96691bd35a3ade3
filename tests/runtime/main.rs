//! The runtime and the process around it: ticks and channel time, the event log and report as
//! files, `serve` stopped by a signal, a closed standard output.

#[path = "../support/mod.rs"]
mod support;

mod closed_stdout;
mod program_loader;
mod runtime;
mod runtime_events;
mod serve_signals;
