//! ncchannel's command line: parse and dispatch, nothing else.

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let code = ncchannel::cli::Cli::parse().execute();
    ncchannel::params::shipped::remove_private_copy();
    code
}
