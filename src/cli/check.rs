//! `ncchannel check FILE...`: NC programs and parameter lists, errors with file:line:col.

use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// NC programs and parameter lists (`.lis`) to check.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
}

pub fn execute(args: CheckArgs) -> ExitCode {
    let _ = args;
    ExitCode::from(super::exit::USAGE)
}
