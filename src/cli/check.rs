//! `ncchannel check FILE...`: NC programs and parameter lists, errors with file:line:col.
//!
//! NC programs go through [`crate::lang::check_program`]; `.lis` files and `runtime.toml`
//! through the parameter checker; any other `.toml` is a soak scenario (the parameter loader
//! reads runtime settings only from a file of that name), checked as `ncchannel soak` loads it. Directories are walked (sorted, not following the hidden `.`
//! entries) and every file with an NC or parameter extension in them is checked. Findings go
//! to stdout as `file:line:col: error <id>: message` with the line and a caret; a summary goes
//! to stderr. Exit 0 when nothing was found, 1 on any error (including an unreadable file).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use crate::diag::{Diagnostic, Severity};

#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// NC programs, parameter lists (`.lis`, `runtime.toml`), soak scenarios (any other
    /// `.toml`) or directories holding them.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
}

/// Extensions picked up when walking a directory. Files named explicitly are checked
/// whatever their extension (anything not `.lis`/`.toml` as an NC program), but Markdown.
const NC_EXTENSIONS: &[&str] = &["nc", "cyc", "sub", "spf", "mpf"];
const PARAM_EXTENSIONS: &[&str] = &["lis", "toml"];

/// Largest file we read: NC programs are far smaller; a bigger one is surely a mistake.
const MAX_FILE_BYTES: u64 = 64 * 1024 * 1024;

pub fn execute(args: CheckArgs) -> ExitCode {
    let mut files = Vec::new();
    let mut diags = Vec::new();
    for path in &args.files {
        collect(path, true, &mut files, &mut diags);
    }
    // Each list's counts once, also when a start-up list and a folder walk both reach it.
    let mut summaries: Vec<crate::params::catalog::ListSummary> = Vec::new();
    for file in &files {
        let (found, lists) = check_file_summarized(file);
        diags.extend(found);
        for l in lists {
            if !summaries.iter().any(|s| s.file == l.file) {
                summaries.push(l);
            }
        }
    }
    let errors = diags
        .iter()
        .filter(|d| d.severity == Severity::Error)
        .count();
    // A reader that stops early (`| head`) ends the findings, not the run (`super::out`).
    let mut out = super::out::Stdout::new();
    for d in &diags {
        out.line(d.render());
    }
    out.finish_or_say("ncchannel check");
    for l in &summaries {
        eprintln!("ncchannel check: {l}");
    }
    eprintln!(
        "ncchannel check: {} file(s), {} error(s), {} warning(s)",
        files.len(),
        errors,
        diags.len() - errors
    );
    if errors > 0 {
        ExitCode::from(super::exit::CHANNEL_ERROR)
    } else {
        ExitCode::from(super::exit::OK)
    }
}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Add `path` (a file, or the checkable files below a directory) to `files`.
fn collect(path: &Path, explicit: bool, files: &mut Vec<PathBuf>, diags: &mut Vec<Diagnostic>) {
    if path.is_dir() {
        let entries = match std::fs::read_dir(path) {
            Ok(rd) => rd,
            Err(e) => {
                diags.push(Diagnostic::error(
                    path,
                    0,
                    0,
                    None,
                    format!("cannot read directory: {e}"),
                ));
                return;
            }
        };
        let mut children: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                !p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with('.'))
            })
            .collect();
        children.sort();
        for child in children {
            collect(&child, false, files, diags);
        }
        return;
    }
    let ext = extension(path);
    // Markdown is documentation, never NC text: `check nc/*` must not trip on nc/README.md.
    if ext == "md" {
        if explicit {
            eprintln!(
                "ncchannel check: {}: skipped (documentation)",
                path.display()
            );
        }
        return;
    }
    if explicit || NC_EXTENSIONS.contains(&ext.as_str()) || PARAM_EXTENSIONS.contains(&ext.as_str())
    {
        files.push(path.to_path_buf());
    }
}

/// Check one file: a parameter list by extension, otherwise an NC program.
pub fn check_file(path: &Path) -> Vec<Diagnostic> {
    check_file_summarized(path).0
}

/// [`check_file`], with the used/inert/unknown counts of every parameter list it read.
fn check_file_summarized(
    path: &Path,
) -> (Vec<Diagnostic>, Vec<crate::params::catalog::ListSummary>) {
    if PARAM_EXTENSIONS.contains(&extension(path).as_str()) {
        if extension(path) == "toml" && !is_runtime_file(path) {
            return (check_scenario_file(path), Vec::new());
        }
        if extension(path) == "toml" {
            return (check_params_file(path), Vec::new());
        }
        return crate::params::config::check_list_file_summarized(path);
    }
    (check_program_file(path), Vec::new())
}

/// Is `path` a runtime settings file (the one name the parameter loader reads them from)?
fn is_runtime_file(path: &Path) -> bool {
    path.file_name()
        .is_some_and(|n| n == crate::params::config::RUNTIME_FILE)
}

/// Check a soak scenario as the command that reads it loads it (every key, every range):
/// `ncchannel soak`'s when it describes the built-in client (`[length]`, `[feeder]`, …),
/// `serve --soak`'s when it has none of those tables; and that the start-up list it names
/// exists (the list itself is checked where it is named or walked).
fn check_scenario_file(path: &Path) -> Vec<Diagnostic> {
    use crate::soak::scenario::{Scenario, ScenarioError};
    let external = read_text(path)
        .ok()
        .and_then(|t| t.parse::<toml::Table>().ok())
        .is_some_and(|doc| {
            !crate::soak::external::CLIENT_KEYS
                .iter()
                .any(|k| doc.contains_key(*k))
        });
    let loaded = if external {
        let shown = format!("{}: ", path.display());
        crate::soak::external::load_external(path).map_err(|m| {
            let m = m.strip_prefix(&shown).unwrap_or(&m);
            format!("scenario for serve --soak: {m}")
        })
    } else {
        Scenario::load(path).map_err(|e| match e {
            ScenarioError::Io { source, .. } => format!("cannot read file: {source}"),
            ScenarioError::Toml { msg, .. } | ScenarioError::Invalid { msg, .. } => {
                format!("scenario: {msg}")
            }
        })
    };
    match loaded {
        Ok(s) => {
            let params = s.params_path();
            if params.is_file() {
                Vec::new()
            } else {
                vec![Diagnostic::error(
                    path,
                    0,
                    0,
                    None,
                    format!(
                        "scenario: the start-up list {} does not exist",
                        params.display()
                    ),
                )]
            }
        }
        Err(msg) => vec![Diagnostic::error(path, 0, 0, None, msg)],
    }
}

/// Check an NC program.
fn check_program_file(path: &Path) -> Vec<Diagnostic> {
    let text = match read_text(path) {
        Ok(t) => t,
        Err(msg) => return vec![Diagnostic::error(path, 0, 0, None, msg)],
    };
    let lines: Vec<&str> = text.lines().collect();
    let (found, all) = crate::lang::check_program_counted(&text);
    let listed = found.len();
    let mut diags: Vec<Diagnostic> = found
        .into_iter()
        .map(|d| {
            let diag = Diagnostic::error(path, d.line, d.col, Some(d.code), d.message);
            match lines.get(d.line.wrapping_sub(1)) {
                Some(src) => diag.with_source(src),
                None => diag,
            }
        })
        .collect();
    if all > listed {
        diags.push(not_listed(path, all - listed));
    }
    diags
}

/// The one diagnostic that stands for the findings past the listing limit.
fn not_listed(path: &Path, more: usize) -> Diagnostic {
    Diagnostic::error(
        path,
        0,
        0,
        None,
        format!("{more} more error(s) not listed (only the first ones are)"),
    )
}

/// Read a file as text; bytes that are not UTF-8 (Latin-1 comments) become U+FFFD.
fn read_text(path: &Path) -> Result<String, String> {
    use crate::bounded::{read_file, BoundedReadError};
    let bytes = read_file(path, MAX_FILE_BYTES).map_err(|e| match e {
        BoundedReadError::TooLarge { bytes, limit } => {
            format!("file has {bytes} bytes, more than the {limit} a program may have")
        }
        BoundedReadError::Io(e) => format!("cannot read file: {e}"),
    })?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// Parameter lists (a start-up list with its channel lists and runtime.toml, or a channel
/// list alone) and runtime.toml files, through the params room's own checks.
pub(crate) fn check_params_file(path: &Path) -> Vec<Diagnostic> {
    if extension(path) == "toml" {
        return crate::params::runtime::read_runtime(path)
            .err()
            .unwrap_or_default();
    }
    crate::params::check_list_file(path)
}
