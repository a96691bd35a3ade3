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
    /// End points at a program's start are checked against its axes' software limits (21897);
    /// without --params, against those of the start-up list `run` reads.
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
    // End points at a program's start against the limits `run` would apply.
    let limits = limits_list(&args).and_then(|p| start_limits(&p, args.channel));
    // Each list's counts once, also when a start-up list and a folder walk both reach it.
    let mut summaries: Vec<crate::params::catalog::ListSummary> = Vec::new();
    for file in &files {
        let (found, lists) = check_file_summarized(file);
        diags.extend(found);
        if !PARAM_EXTENSIONS.contains(&extension(file).as_str()) {
            if let Some(t) = &techno {
                diags.extend(check_functions_file(file, t));
            }
            if let Some(l) = &limits {
                diags.extend(check_start_file(file, l));
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

/// The software limits a program's start is checked against: the channel's axes that a
/// letter names (`X` for the channel's X), by `AXIS_LETTERS` index, and their limits.
struct StartLimits {
    axes: [bool; crate::vocab::axis::MAX_AXES],
    limits: [crate::geometry::SoftLimits; crate::vocab::axis::MAX_AXES],
}

/// The limits of channel `channel` of the start-up list `params` (as `run` sets the channel
/// up), or `None` when it is no start-up list that loads (its errors are reported elsewhere
/// when it was named).
fn start_limits(params: &Path, channel: u32) -> Option<StartLimits> {
    let config = crate::params::load(params).ok()?;
    let ch = config
        .channels
        .get(usize::try_from(channel.checked_sub(1)?).ok()?)?;
    let settings = crate::setup::channel_settings(&config, ch).ok()?;
    let d = &settings.decoder;
    let letters = crate::decoder::letter_names();
    let mut axes = d.axes;
    for (i, on) in axes.iter_mut().enumerate() {
        // An axis renamed in the lists (`X1`) is not the one a letter word moves.
        *on &= d.axis_names[i] == letters[i];
    }
    Some(StartLimits {
        axes,
        limits: d.soft_limits_mm,
    })
}

/// The start-up list whose limits `check` applies: `--params`, else the one `run` reads
/// (`$NCCHANNEL_PARAMS`, else ./params/startup.lis, else the built-in set).
fn limits_list(args: &CheckArgs) -> Option<PathBuf> {
    match &args.params {
        Some(p) => Some(p.clone()),
        None => {
            let default = std::env::var_os("NCCHANNEL_PARAMS")
                .map_or_else(|| PathBuf::from("params/startup.lis"), PathBuf::from);
            crate::params::shipped::locate(&default).ok()
        }
    }
}

/// G functions that leave a program's start frame as it is (motion, dwell, plane, exact stop,
/// absolute, feed modes): the start region goes on through them.
const START_FRAME_G: &[u32] = &[0, 1, 2, 3, 4, 9, 17, 18, 19, 60, 61, 90, 94, 95];

/// End points outside the software limits at the start of an NC program, which a run refuses
/// with 21897 before the axis moves. A program starts in absolute mode with no zero offset,
/// no G92 shift, no tool offset and no transformation, so its literal axis values there are
/// machine positions; the check reads the blocks from the start up to the first that may
/// change that frame or the path through the program (any other G function, D or T, an
/// assignment, a `#` command other than `#MSG` and `#TIME`, a `$` statement, a call, a
/// second program head, a skippable block), and no further.
fn check_start_file(path: &Path, limits: &StartLimits) -> Vec<Diagnostic> {
    use crate::geometry::arc::LimitBreach;
    use crate::lang::{Body, Command, Item, Value};
    use crate::vocab::axis::AXIS_LETTERS;
    let Ok(text) = read_text(path) else {
        return Vec::new();
    };
    let lines: Vec<&str> = text.lines().collect();
    let mut diags = Vec::new();
    let mut started = false;
    walk_blocks(&text, |block, line, joined| {
        if block.skip_level.is_some() {
            return false;
        }
        let items = match &block.body {
            Body::ProgramHead(_) => return !std::mem::replace(&mut started, true),
            Body::Command(c) if matches!(**c, Command::Msg(_) | Command::Time(_)) => {
                started = true;
                return true;
            }
            Body::Items(items) => items,
            _ => return false,
        };
        started = true;
        let mut dwell = false;
        for it in items {
            match it {
                Item::Word(w) if w.letter == b'G' => match w.value {
                    Value::Num(g) if START_FRAME_G.iter().any(|&k| f64::from(k) == g) => {
                        dwell |= g == 4.0;
                    }
                    _ => return false,
                },
                Item::GValue { g: 4, .. } => dwell = true,
                Item::Word(w) if matches!(w.letter, b'D' | b'T') => return false,
                Item::Word(_) | Item::FunctionValue { .. } => {}
                _ => return false,
            }
        }
        if dwell {
            // `G04 X2`: X is the time.
            return true;
        }
        for it in items {
            let Item::Word(w) = it else { continue };
            let (Some(i), Value::Num(v)) =
                (AXIS_LETTERS.iter().position(|&l| l == w.letter), &w.value)
            else {
                continue;
            };
            if !limits.axes[i] {
                continue;
            }
            let l = limits.limits[i];
            let below = *v < l.min_mm - crate::geometry::arc::SOFT_LIMIT_SLACK_MM;
            if !below && *v <= l.max_mm + crate::geometry::arc::SOFT_LIMIT_SLACK_MM {
                continue;
            }
            let breach = LimitBreach {
                axis: i,
                value_mm: *v,
                below,
                at_end: true,
                limits: l,
            };
            let (d, c) = joined.map_or((0, w.col), |j| j.position(w.col));
            let at = line + d as usize;
            let diag = Diagnostic::error(
                path,
                at,
                c as usize,
                Some(crate::lang::codes::SOFT_LIMIT),
                breach.message("end point"),
            );
            diags.push(match lines.get(at.wrapping_sub(1)) {
                Some(src) => diag.with_source(src),
                None => diag,
            });
        }
        true
    });
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
/// `#VAR` sections skipped, blocks that do not parse left to the program check) and gather
/// the M and H words `techno` does not define, by first use.
fn undefined_functions(text: &str, techno: &TechnoTable) -> Vec<UndefinedFunction> {
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
    walk_blocks(text, |block, line, joined| {
        block_functions(block, line, joined, &mut note);
        true
    });
    found
}

/// Hand every block of a program to `visit` with its first line and, for a block written over
/// several lines, its joiner (for the line and column of a word), as the checker reads them:
/// `\` continuations joined, `#COMMENT` and `#VAR` sections skipped, blocks that do not parse
/// left out (they are the program check's findings). `visit` answers whether to go on.
fn walk_blocks(
    text: &str,
    mut visit: impl FnMut(&crate::lang::Block, usize, Option<&crate::lang::Joiner>) -> bool,
) {
    use crate::lang::{
        continuation, is_comment_end, parse_block, parse_var_line, Body, Command, Joiner, VarLine,
    };
    let mut state = Sections::default();
    // One block: false when `visit` has had enough.
    let mut block = |raw: &str, line: usize, joined: Option<&Joiner>, state: &mut Sections| {
        let Ok(block) = parse_block(raw) else {
            return true;
        };
        match &block.body {
            Body::Command(c) if **c == Command::CommentBegin => state.in_comment = true,
            Body::Command(c) if **c == Command::Var => state.in_var = true,
            _ => return visit(&block, line, joined),
        }
        true
    };
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
            if joiner.push(raw) && !block(joiner.text(), first, Some(&joiner), &mut state) {
                return;
            }
            continue;
        }
        if !block(raw, line, None, &mut state) {
            return;
        }
    }
    if joiner.is_open() {
        block(joiner.text(), first, Some(&joiner), &mut state);
    }
}

/// Whether the lines that follow are inside `#COMMENT BEGIN … END` or `#VAR … #ENDVAR`.
#[derive(Default)]
struct Sections {
    in_comment: bool,
    in_var: bool,
}

/// The M and H words of one block (`line` is its first line), handed to `note` with their
/// line and column.
fn block_functions(
    block: &crate::lang::Block,
    line: usize,
    joined: Option<&crate::lang::Joiner>,
    note: &mut impl FnMut(u8, u32, usize, usize),
) {
    use crate::lang::{Body, Item, Value, Word};
    let Body::Items(items) = &block.body else {
        return;
    };
    for item in items {
        let (letter, number, col) = match *item {
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
