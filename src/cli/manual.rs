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

#[derive(Debug, clap::Args)]
pub struct ManArgs {
    /// The subcommand whose page to print (`ncchannel man run > ncchannel-run.1`); without it,
    /// the main page, which lists them.
    pub subcommand: Option<String>,
    /// Write every page, `ncchannel.1` and `ncchannel-SUBCOMMAND.1` for each subcommand with
    /// its options, into DIR (e.g. `~/.local/share/man/man1`) instead of printing one.
    #[arg(long, value_name = "DIR", conflicts_with = "subcommand")]
    pub dir: Option<std::path::PathBuf>,
}

/// The command line as the pages describe it: no `help` subcommand, which has no page.
fn documented() -> clap::Command {
    let mut cmd = Cli::command().disable_help_subcommand(true);
    cmd.build();
    cmd
}

/// Print a man page (roff): `ncchannel man > ncchannel.1`, `man ./ncchannel.1`; or write
/// them all with `--dir`.
pub fn man(args: ManArgs) -> ExitCode {
    let cmd = documented();
    if let Some(dir) = args.dir {
        return match clap_mangen::generate_to(cmd, &dir) {
            Ok(()) => ExitCode::from(super::exit::OK),
            Err(e) => {
                eprintln!("ncchannel man: {}: {e}", dir.display());
                ExitCode::from(super::exit::USAGE)
            }
        };
    }
    let page = match args.subcommand {
        None => cmd,
        Some(name) => match cmd.find_subcommand(&name) {
            Some(sub) => sub.clone(),
            None => {
                let names: Vec<&str> = cmd.get_subcommands().map(|c| c.get_name()).collect();
                eprintln!(
                    "ncchannel man: no subcommand {name:?}; the pages are: {}",
                    names.join(", ")
                );
                return ExitCode::from(super::exit::USAGE);
            }
        },
    };
    let mut text = Vec::new();
    if let Err(e) = clap_mangen::Man::new(page).render(&mut text) {
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
