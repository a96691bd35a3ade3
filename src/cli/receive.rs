//! `ncchannel receive`: split a transfer into programs by start/end markers.

use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct ReceiveArgs {
    /// Input file, or `-` for standard input.
    pub input: Option<PathBuf>,
}

pub fn execute(args: ReceiveArgs) -> ExitCode {
    let _ = args;
    ExitCode::from(super::exit::USAGE)
}
