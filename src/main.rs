//! ncchannel's command line: parse and dispatch, nothing else.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    ncchannel::cli::Cli::parse().execute()
}
