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
use crate::vocab::techno::TechnoTable;

#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// NC programs, parameter lists (`.lis`, `runtime.toml`), soak scenarios (any other
    /// `.toml`) or directories holding them.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Check the M and H functions the NC programs use against a channel's parameters: a
    /// start-up list (its channel --channel) or a channel list. Each M/H number the channel
    /// does not define (`m_synch[i]` P-CHAN-00041, `h_synch[i]` P-CHAN-00027, the spindle's
    /// M3/M4/M5/M19, the kernel's internal M functions) is an error, 20157 (M) / 20162 (H).
    #[arg(long, value_name = "LIST")]
    pub params: Option<PathBuf>,
    /// Channel (1-based) of the --params start-up list whose functions the programs use.
    #[arg(long, default_value_t = 1, requires = "params")]
    pub channel: u32,
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
    // Without the channel's table the programs are checked as before; a list that does not
    // load is reported and the M/H check left out.
    let techno = args
        .params
        .as_deref()
        .and_then(|p| match channel_techno(p, args.channel) {
            Ok(t) => Some(t),
            Err(found) => {
                diags.extend(found);
                None
            }
        });
    // Each list's counts once, also when a start-up list and a folder walk both reach it.
    let mut summaries: Vec<crate::params::catalog::ListSummary> = Vec::new();
    for file in &files {
        let (found, lists) = check_file_summarized(file);
        diags.extend(found);
        if let Some(t) = &techno {
            if !PARAM_EXTENSIONS.contains(&extension(file).as_str()) {
                diags.extend(check_functions_file(file, t));
            }
        }
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
        e @ BoundedReadError::NotRegular => e.to_string(),
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

/// The technology table of `--params`: a start-up list's channel `channel` (1-based), or a
/// channel list read alone. Its errors, when it is refused.
fn channel_techno(path: &Path, channel: u32) -> Result<TechnoTable, Vec<Diagnostic>> {
    use crate::params::list::read_list;
    let (list, mut diags) = read_list(path).map_err(|d| vec![d])?;
    if crate::params::startup::is_startup_list(&list) {
        let config = crate::params::load(path).map_err(|e| e.errors())?;
        let index = usize::try_from(channel.saturating_sub(1)).unwrap_or(usize::MAX);
        return match config.channels.get(index) {
            Some(c) if channel > 0 => Ok(c.techno.clone()),
            _ => Err(vec![Diagnostic::error(
                path,
                0,
                0,
                None,
                format!(
                    "--channel {channel}: the start-up list has {} channel(s)",
                    config.channels.len()
                ),
            )]),
        };
    }
    let folder = crate::params::search_path::list_folder(path);
    let channel = crate::params::channel::interpret_channel(list, &folder, &mut diags);
    diags.retain(|d| d.severity == Severity::Error);
    if diags.is_empty() {
        Ok(channel.techno)
    } else {
        Err(diags)
    }
}

/// The M and H functions of an NC program that `techno` does not define: one error per
/// number, at its first use (the kernel's 20157 or 20160 / 20162 when the block is decoded).
fn check_functions_file(path: &Path, techno: &TechnoTable) -> Vec<Diagnostic> {
    // An unreadable file was reported by the program check already.
    let Ok(text) = read_text(path) else {
        return Vec::new();
    };
    let lines: Vec<&str> = text.lines().collect();
    let mut diags = Vec::new();
    for f in undefined_functions(&text, techno) {
        let (code, what) = match f.letter {
            b'M' => (crate::lang::codes::unknown_m(f.number), "m_synch"),
            _ => (crate::lang::codes::UNKNOWN_H, "h_synch"),
        };
        let letter = char::from(f.letter);
        let again = match f.uses {
            1 => String::new(),
            n => format!(" (used {n} times, first here)"),
        };
        let diag = Diagnostic::error(
            path,
            f.line,
            f.col,
            Some(code),
            format!(
                "{letter}{n} is not defined in the channel's parameters ({what}[{n}] missing){again}",
                n = f.number
            ),
        );
        diags.push(match lines.get(f.line.wrapping_sub(1)) {
            Some(src) => diag.with_source(src),
            None => diag,
        });
    }
    diags
}

/// An M or H number a program uses that its channel does not define.
struct UndefinedFunction {
    letter: u8,
    number: u32,
    line: usize,
    col: usize,
    uses: usize,
}

/// Walk the program's blocks as the checker does (`\` continuations joined, `#COMMENT` and
/// `#VAR` sections skipped) and gather the M and H words `techno` does not define, by first use.
fn undefined_functions(text: &str, techno: &TechnoTable) -> Vec<UndefinedFunction> {
    use crate::lang::{continuation, is_comment_end, parse_var_line, Joiner, VarLine};
    let mut found: Vec<UndefinedFunction> = Vec::new();
    let mut note = |letter: u8, number: u32, line: usize, col: usize| {
        let defined = match letter {
            b'M' => techno.m_def(number).is_some(),
            _ => techno.h_def(number).is_some(),
        };
        if defined {
            return;
        }
        match found
            .iter_mut()
            .find(|f| f.letter == letter && f.number == number)
        {
            Some(f) => f.uses += 1,
            None => found.push(UndefinedFunction {
                letter,
                number,
                line,
                col,
                uses: 1,
            }),
        }
    };
    let mut state = Sections::default();
    let mut joiner = Joiner::default();
    let mut first = 0;
    for (idx, raw) in text.lines().enumerate() {
        let line = idx + 1;
        if state.in_comment {
            if is_comment_end(raw) {
                state.in_comment = false;
            }
            continue;
        }
        if state.in_var {
            match parse_var_line(raw) {
                Ok(VarLine::End) => state.in_var = false,
                Ok(VarLine::CommentBegin) => state.in_comment = true,
                _ => {}
            }
            continue;
        }
        if joiner.is_open() || continuation(raw).is_some() {
            // A block written over several lines: read once it is complete.
            if !joiner.is_open() {
                first = line;
            }
            if joiner.push(raw) {
                block_functions(joiner.text(), first, Some(&joiner), &mut state, &mut note);
            }
            continue;
        }
        block_functions(raw, line, None, &mut state, &mut note);
    }
    if joiner.is_open() {
        block_functions(joiner.text(), first, Some(&joiner), &mut state, &mut note);
    }
    found
}

/// Whether the lines that follow are inside `#COMMENT BEGIN … END` or `#VAR … #ENDVAR`.
#[derive(Default)]
struct Sections {
    in_comment: bool,
    in_var: bool,
}

/// The M and H words of one block (`line` is its first line), handed to `note` with their
/// line and column; a `#COMMENT BEGIN` or `#VAR` block opens its section.
fn block_functions(
    text: &str,
    line: usize,
    joined: Option<&crate::lang::Joiner>,
    state: &mut Sections,
    note: &mut impl FnMut(u8, u32, usize, usize),
) {
    use crate::lang::{parse_block, Body, Command, Item, Value, Word};
    // A block that does not parse is the program check's finding.
    let Ok(block) = parse_block(text) else {
        return;
    };
    let items = match block.body {
        Body::Command(Command::CommentBegin) => {
            state.in_comment = true;
            return;
        }
        Body::Command(Command::Var) => {
            state.in_var = true;
            return;
        }
        Body::Items(items) => items,
        _ => return,
    };
    for item in items {
        let (letter, number, col) = match item {
            Item::Word(Word {
                letter: l @ (b'M' | b'H'),
                value: Value::Num(v),
                col,
            }) if v >= 0.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX) => (l, v as u32, col),
            Item::FunctionValue {
                letter: l @ (b'M' | b'H'),
                number,
                col,
                ..
            } => (l, number, col),
            _ => continue,
        };
        let (d, c) = joined.map_or((0, col), |j| j.position(col));
        note(letter, number, line + d as usize, c as usize);
    }
}
