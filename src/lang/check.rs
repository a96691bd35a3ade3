//! Static check of a whole NC program file: every line parsed, plus the structure a single
//! line cannot show — control blocks opened and closed, labels unique, `$GOTO` targets found.
//!
//! Program levels: each `%name` / `%L name` head starts a new level; labels are searched and
//! control blocks must close within their level (TF5200 programming manual). The check reads files the
//! way the decoder runs them (both jump directions allowed); streaming's extra limits
//! (no loops, forward jumps only) are the decoder's business.

use std::collections::{HashMap, HashSet};

use super::block::{Body, Command, Control, GotoTarget, Label};
use super::block::{Expr, Item, UnOp, Value};
use super::codes::{
    StrayKind, DWELL_RANGE_G04, DWELL_RANGE_TIME, LABEL_NOT_FOUND, LABEL_TWICE, OPEN_CONTROL_BLOCK,
    SYNTAX,
};
use super::join::{continuation, Joiner};
use super::parse::{is_comment_end, parse_block, parse_var_line, VarLine};
use super::range::dwell_time;

/// Most findings one check lists. A file of garbage (a binary, a log passed by mistake) has
/// one finding a line; listing millions of them helps nobody and cost gigabytes, so the
/// first ones (in reading order) are kept and the rest only counted.
pub const MAX_PROGRAM_DIAGS: usize = 1000;

/// One finding in a program: 1-based line and character column, ISG error number, message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ProgramDiag {
    pub line: usize,
    pub col: usize,
    pub code: u32,
    pub message: String,
}

impl ProgramDiag {
    fn new(line: usize, col: usize, code: u32, message: impl Into<String>) -> Self {
        ProgramDiag {
            line,
            col,
            code,
            message: message.into(),
        }
    }
}

/// The findings of one check: the first [`MAX_PROGRAM_DIAGS`] kept, all counted.
#[derive(Default)]
struct Diags {
    kept: Vec<ProgramDiag>,
    found: usize,
}

impl Diags {
    fn push(&mut self, d: ProgramDiag) {
        self.found += 1;
        if self.kept.len() < MAX_PROGRAM_DIAGS {
            self.kept.push(d);
        }
    }
}

/// An open control block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum OpenKind {
    If { else_seen: bool },
    Switch,
    For,
    While,
    Do,
    Repeat,
}

impl OpenKind {
    fn is_loop(self) -> bool {
        matches!(
            self,
            OpenKind::For | OpenKind::While | OpenKind::Do | OpenKind::Repeat
        )
    }

    fn keyword(self) -> &'static str {
        match self {
            OpenKind::If { .. } => "$IF",
            OpenKind::Switch => "$SWITCH",
            OpenKind::For => "$FOR",
            OpenKind::While => "$WHILE",
            OpenKind::Do => "$DO",
            OpenKind::Repeat => "$REPEAT",
        }
    }

    fn closer(self) -> &'static str {
        match self {
            OpenKind::If { .. } => "$ENDIF",
            OpenKind::Switch => "$ENDSWITCH",
            OpenKind::For => "$ENDFOR",
            OpenKind::While => "$ENDWHILE",
            OpenKind::Do => "$ENDDO",
            OpenKind::Repeat => "$UNTIL",
        }
    }
}

/// One program level's labels, jumps and open blocks.
#[derive(Default)]
struct Level {
    labels: HashMap<Label, usize>,
    block_numbers: HashSet<u32>,
    gotos: Vec<(GotoTarget, usize, usize)>,
    open: Vec<(OpenKind, usize, usize)>,
}

impl Level {
    fn finish(self, diags: &mut Diags) {
        for (kind, line, col) in self.open {
            diags.push(ProgramDiag::new(
                line,
                col,
                OPEN_CONTROL_BLOCK,
                format!(
                    "{} not closed by {} before the program ends",
                    kind.keyword(),
                    kind.closer()
                ),
            ));
        }
        for (target, line, col) in self.gotos {
            let label = match &target {
                GotoTarget::Number(n) => Label::Number(*n),
                GotoTarget::Name(s) => Label::Name(s.clone()),
            };
            if self.labels.contains_key(&label) {
                continue;
            }
            let hint = match target {
                GotoTarget::Number(n) if self.block_numbers.contains(&n) => {
                    format!(" (block N{n} exists but is no label: write `N{n}:`)")
                }
                _ => String::new(),
            };
            diags.push(ProgramDiag::new(
                line,
                col,
                LABEL_NOT_FOUND,
                format!("jump target {target} not found in this program level{hint}"),
            ));
        }
    }

    fn stray(&self, kind: StrayKind, line: usize, col: usize, diags: &mut Diags) {
        diags.push(ProgramDiag::new(
            line,
            col,
            kind.code(),
            format!(
                "unexpected {} without its opening statement",
                kind.keyword()
            ),
        ));
    }

    fn control(&mut self, c: &Control, line: usize, col: usize, diags: &mut Diags) {
        let top = self.open.last().map(|o| o.0);
        let pop_if = |me: &mut Self, want: fn(OpenKind) -> bool, kind, diags: &mut Diags| {
            if top.is_some_and(want) {
                me.open.pop();
            } else {
                me.stray(kind, line, col, diags);
            }
        };
        match c {
            Control::If(_) => self
                .open
                .push((OpenKind::If { else_seen: false }, line, col)),
            Control::IfGoto(_, t) | Control::Goto(t) => self.gotos.push((t.clone(), line, col)),
            Control::ElseIf(_) => {
                if top != Some(OpenKind::If { else_seen: false }) {
                    self.stray(StrayKind::ElseIf, line, col, diags);
                }
            }
            Control::Else => match self.open.last_mut() {
                Some((OpenKind::If { else_seen }, _, _)) if !*else_seen => *else_seen = true,
                _ => self.stray(StrayKind::Else, line, col, diags),
            },
            Control::EndIf => pop_if(
                self,
                |k| matches!(k, OpenKind::If { .. }),
                StrayKind::EndIf,
                diags,
            ),
            Control::Switch(_) => self.open.push((OpenKind::Switch, line, col)),
            Control::Case(_) => {
                if top != Some(OpenKind::Switch) {
                    self.stray(StrayKind::Case, line, col, diags);
                }
            }
            Control::Default => {
                if top != Some(OpenKind::Switch) {
                    self.stray(StrayKind::Default, line, col, diags);
                }
            }
            Control::Break => {
                if !self
                    .open
                    .iter()
                    .any(|o| o.0 == OpenKind::Switch || o.0.is_loop())
                {
                    self.stray(StrayKind::Break, line, col, diags);
                }
            }
            Control::Continue => {
                if !self.open.iter().any(|o| o.0.is_loop()) {
                    self.stray(StrayKind::Continue, line, col, diags);
                }
            }
            Control::EndSwitch => {
                pop_if(self, |k| k == OpenKind::Switch, StrayKind::EndSwitch, diags)
            }
            Control::For { .. } => self.open.push((OpenKind::For, line, col)),
            Control::EndFor => pop_if(self, |k| k == OpenKind::For, StrayKind::EndFor, diags),
            Control::While(_) => self.open.push((OpenKind::While, line, col)),
            Control::EndWhile => pop_if(self, |k| k == OpenKind::While, StrayKind::EndWhile, diags),
            Control::Do => self.open.push((OpenKind::Do, line, col)),
            Control::EndDo(_) => pop_if(self, |k| k == OpenKind::Do, StrayKind::EndDo, diags),
            Control::Repeat => self.open.push((OpenKind::Repeat, line, col)),
            Control::Until(_) => pop_if(self, |k| k == OpenKind::Repeat, StrayKind::Until, diags),
        }
    }
}

/// The value of a literal (`2.5`, `-2.5`), not of an expression a run evaluates.
fn literal(v: &Value) -> Option<f64> {
    match v {
        Value::Num(n) => Some(*n),
        Value::Expr(Expr::Unary(UnOp::Neg, e)) => match **e {
            Expr::Num(n) => Some(-n),
            _ => None,
        },
        Value::Expr(_) => None,
    }
}

/// A `G04` block's literal dwell time and the column of the word that gives it: `G04 2.5`
/// (the G's column) or `G04 X2.5` (the X's), as the decoder reads them.
fn literal_dwell(items: &[Item]) -> Option<(usize, f64)> {
    let mut dwell = false;
    let mut x = None;
    for it in items {
        match it {
            Item::GValue { g: 4, value, col } => return Some((*col as usize, literal(value)?)),
            Item::Word(w) if w.letter == b'G' && w.value == Value::Num(4.0) => dwell = true,
            Item::Word(w) if w.letter == b'X' => x = literal(&w.value).map(|v| (w.col as usize, v)),
            _ => {}
        }
    }
    x.filter(|_| dwell)
}

/// 1-based character column of the first `needle` in `line` (case-insensitive ASCII), or 1.
fn col_of(line: &str, needle: &str) -> usize {
    let upper = line.to_ascii_uppercase();
    upper
        .find(needle)
        .map_or(1, |b| line[..b].chars().count() + 1)
}

/// Check a whole program text. Diagnostics come sorted by line and column; at most
/// [`MAX_PROGRAM_DIAGS`] of them ([`check_program_counted`] also says how many there were).
pub fn check_program(text: &str) -> Vec<ProgramDiag> {
    check_program_counted(text).0
}

/// [`check_program`], and the number of findings in all (more than the list holds when the
/// list was cut at [`MAX_PROGRAM_DIAGS`]).
pub fn check_program_counted(text: &str) -> (Vec<ProgramDiag>, usize) {
    let mut c = Checker::default();
    let mut joiner = Joiner::default();
    let mut first = 0;
    for (idx, raw) in text.lines().enumerate() {
        let line = idx + 1;
        if c.comment_from.is_some() {
            // Comment text is not NC: no line of it continues another.
            if is_comment_end(raw) {
                c.comment_from = None;
            }
            continue;
        }
        if joiner.is_open() || continuation(raw).is_some() {
            // A block written over several lines (`\`): checked once it is complete.
            if !joiner.is_open() {
                first = line;
            }
            if joiner.push(raw) {
                c.block(joiner.text(), first, Some(&joiner));
            }
            continue;
        }
        c.block(raw, line, None);
    }
    if joiner.is_open() {
        // The text ends in a continued line: the block is what there is, as in a run.
        c.block(joiner.text(), first, Some(&joiner));
    }
    c.finish()
}

/// The state of one check between lines.
#[derive(Default)]
struct Checker {
    diags: Diags,
    level: Level,
    comment_from: Option<usize>,
    var_from: Option<(usize, usize)>,
}

/// The line and column of column `col` of a block that starts in `line`, written over
/// several lines when `joined`.
fn place(line: usize, col: usize, joined: Option<&Joiner>) -> (usize, usize) {
    match joined {
        Some(j) => {
            let (d, c) = j.position(col as u32);
            (line + d as usize, c as usize)
        }
        None => (line, col),
    }
}

impl Checker {
    fn push(&mut self, line: usize, col: usize, joined: Option<&Joiner>, code: u32, msg: String) {
        let (line, col) = place(line, col, joined);
        self.diags.push(ProgramDiag::new(line, col, code, msg));
    }

    /// One block (one line, or the lines of a block joined by `\`) starting in `line`.
    fn block(&mut self, raw: &str, line: usize, joined: Option<&Joiner>) {
        if self.var_from.is_some() {
            // The decoder reads these lines with the same function.
            match parse_var_line(raw) {
                Ok(VarLine::End) => self.var_from = None,
                Ok(VarLine::CommentBegin) => self.comment_from = Some(line),
                Ok(VarLine::Blank | VarLine::Decl(_)) => {}
                Err(e) => self.push(line, e.col as usize, joined, e.code, e.message),
            }
            return;
        }
        let block = match parse_block(raw) {
            Ok(b) => b,
            Err(e) => return self.push(line, e.col as usize, joined, e.code, e.message),
        };
        if let Some(n) = block.n {
            self.level.block_numbers.insert(n);
        }
        if let Some(label) = &block.label {
            let col = match label {
                Label::Number(_) => col_of(raw, "N"),
                Label::Name(_) => col_of(raw, "["),
            };
            if let Some(first) = self.level.labels.get(label) {
                let msg = format!("label {label} already defined in line {first}");
                self.push(line, col, joined, LABEL_TWICE, msg);
            } else {
                self.level.labels.insert(label.clone(), line);
            }
        }
        match &block.body {
            Body::Command(c) => match &**c {
                Command::CommentBegin => self.comment_from = Some(line),
                Command::Var => {
                    self.var_from = Some(place(line, col_of(raw, "#"), joined));
                }
                Command::EndVar => {
                    let msg = "#ENDVAR without #VAR".to_string();
                    self.push(line, col_of(raw, "#"), joined, SYNTAX, msg);
                }
                Command::Time(v) => {
                    if let Some(Err(e)) = literal(v).map(|s| dwell_time(s, DWELL_RANGE_TIME)) {
                        self.push(line, col_of(raw, "#"), joined, e.code, e.message);
                    }
                }
                _ => {}
            },
            Body::ProgramHead(_) => {
                std::mem::take(&mut self.level).finish(&mut self.diags);
            }
            Body::Control(c) => {
                let col = match &**c {
                    Control::IfGoto(..) => col_of(raw, "$GOTO"),
                    _ => col_of(raw, "$"),
                };
                let (line, col) = place(line, col, joined);
                self.level.control(c, line, col, &mut self.diags);
            }
            Body::Items(items) => {
                if let Some((col, Err(e))) =
                    literal_dwell(items).map(|(c, s)| (c, dwell_time(s, DWELL_RANGE_G04)))
                {
                    self.push(line, col, joined, e.code, e.message);
                }
            }
            _ => {}
        }
    }

    fn finish(mut self) -> (Vec<ProgramDiag>, usize) {
        self.level.finish(&mut self.diags);
        if let Some(line) = self.comment_from {
            self.diags.push(ProgramDiag::new(
                line,
                1,
                OPEN_CONTROL_BLOCK,
                "#COMMENT BEGIN not closed by #COMMENT END before the program ends",
            ));
        }
        if let Some((line, col)) = self.var_from {
            self.diags.push(ProgramDiag::new(
                line,
                col,
                OPEN_CONTROL_BLOCK,
                "#VAR not closed by #ENDVAR before the program ends",
            ));
        }
        let Diags { mut kept, found } = self.diags;
        kept.sort_by_key(|d| (d.line, d.col));
        (kept, found)
    }
}
