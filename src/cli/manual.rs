//! `ncchannel completions SHELL` and `ncchannel man`: a shell completion script and the man
//! page, generated from the same clap definition that parses the command line, so neither
//! can fall behind an option.

use std::io::Write;
use std::process::ExitCode;

use clap::CommandFactory;

use super::Cli;

#[derive(Debug, clap::Args)]
pub struct CompletionsArgs {
    /// The shell to complete for; e.g. `ncchannel completions bash > /etc/bash_completion.d/ncchannel`.
    pub shell: clap_complete::Shell,
}

/// Print the completion script for the shell.
pub fn completions(args: CompletionsArgs) -> ExitCode {
    let mut text = Vec::new();
    clap_complete::generate(args.shell, &mut Cli::command(), "ncchannel", &mut text);
    print("completions", &text)
}

/// Print the man page (roff): `ncchannel man > ncchannel.1`, `man ./ncchannel.1`.
pub fn man() -> ExitCode {
    let mut text = Vec::new();
    if let Err(e) = clap_mangen::Man::new(Cli::command()).render(&mut text) {
        eprintln!("ncchannel man: {e}");
        return ExitCode::from(super::exit::USAGE);
    }
    print("man", &text)
}

/// `bytes` on standard output; a reader that went away (`| head`) ends it quietly.
fn print(command: &str, bytes: &[u8]) -> ExitCode {
    let mut out = std::io::stdout().lock();
    match out.write_all(bytes).and_then(|()| out.flush()) {
        Err(e) if !super::out::reader_gone(&e) => {
            eprintln!("ncchannel {command}: standard output: {e}");
            ExitCode::from(super::exit::USAGE)
        }
        _ => ExitCode::from(super::exit::OK),
    }
}
