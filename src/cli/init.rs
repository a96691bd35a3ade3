//! `ncchannel init DIR`: write the shipped parameter lists, soak scenarios and example
//! programs (`DIR/params/`, `DIR/nc/`) to edit; `cd DIR` and every command reads them.

use std::path::PathBuf;
use std::process::ExitCode;

use super::exit;
use super::out::say;

#[derive(Debug, Clone, clap::Args)]
pub struct InitArgs {
    /// Folder to write params/ and nc/ into (created when missing; refused when either exists).
    #[arg(default_value = ".")]
    pub dir: PathBuf,
}

pub fn execute(args: InitArgs) -> ExitCode {
    match crate::params::shipped::init(&args.dir) {
        Ok(n) => {
            say(format_args!(
                "ncchannel init: wrote {n} files into {0}/params and {0}/nc; `cd {0}` and run `ncchannel`",
                args.dir.display()
            ));
            ExitCode::from(exit::OK)
        }
        Err(e) => {
            eprintln!("ncchannel init: {e}");
            ExitCode::from(exit::USAGE)
        }
    }
}
