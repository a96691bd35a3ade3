//! The ISG parameter-list format: `name value` lines parsed with nom, every name and value
//! pinned to its line and column so later checks can point at the exact spot.
//!
//! The format knows no types: whether `0x03` is a number or `streaming.nc` a string is decided
//! here only lexically (a token that reads as a number is a number). The typed views
//! (`startup.rs`, `channel.rs`) ask each [`Value`] for the type their parameter needs.

use std::path::{Path, PathBuf};

use nom::branch::alt;
use nom::bytes::complete::{tag_no_case, take_while, take_while1};
use nom::character::complete::{char, digit1, hex_digit1};
use nom::combinator::{opt, recognize};
use nom::sequence::{delimited, pair};
use nom::{IResult, Parser};

use crate::diag::Diagnostic;

/// Largest list file we read. Real start-up lists are a few KiB; 16 MiB leaves room for
/// generated lists and keeps a wrong path (a disk image, a log) from being slurped.
pub(crate) const MAX_LIST_BYTES: u64 = 16 * 1024 * 1024;

/// Most entries one list may hold. Bounds memory independent of line length.
pub(crate) const MAX_ENTRIES: usize = 100_000;

/// Largest index inside `[...]`. ISG tables are small; a huge index is a typo.
pub(crate) const MAX_INDEX: u32 = 65_535;

/// A 1-based line and character column in a list file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Pos {
    pub line: usize,
    pub col: usize,
}

/// One part of a dotted name: `prg[1]` is `{ ident: "prg", index: Some(1) }`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Segment {
    pub ident: String,
    pub index: Option<u32>,
}

/// A parameter name such as `pfad[0].prg[1]`, kept both as written and split into segments.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Name {
    pub text: String,
    pub segments: Vec<Segment>,
}

/// How a value was written, which decides how its comment was cut off.
#[derive(Debug, Clone, PartialEq)]
pub enum ValueKind {
    /// Decimal integer, e.g. `4096` or `-1`.
    Int(i64),
    /// `0x…` hexadecimal, e.g. `0x03`.
    Hex(u64),
    /// Decimal with a fraction or exponent, e.g. `2.5`.
    Float(f64),
    /// Unquoted text without blanks, e.g. `streaming.nc`.
    Word,
    /// `"…"` text; may contain blanks and `(`.
    Quoted,
    /// The value of another parameter, named by its P number: `P-AXIS-00008.0` is
    /// P-AXIS-00008 (of gear 0). Resolved by the typed view that reads the entry.
    Ref(ParamRef),
}

/// A reference to another parameter by its P number, as ISG lists write it:
/// `P-<GROUP>-<number>[.<index>]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamRef {
    /// `AXIS`, `CHAN`, `STUP` …
    pub group: String,
    pub number: u32,
    /// The `.n` suffix: the index of the referenced table entry (the gear for axis data).
    pub index: Option<u32>,
}

/// A value as read: its kind and its text (without quotes and without the comment).
#[derive(Debug, Clone, PartialEq)]
pub struct Value {
    pub kind: ValueKind,
    pub text: String,
}

impl Value {
    /// The value as a string parameter. Numbers written unquoted are strings too
    /// (a program may be called `1234`).
    pub fn as_str(&self) -> &str {
        &self.text
    }

    /// The value as a signed integer, if it was written as one (decimal or hex).
    pub fn as_int(&self) -> Option<i64> {
        match self.kind {
            ValueKind::Int(v) => Some(v),
            ValueKind::Hex(v) => i64::try_from(v).ok(),
            _ => None,
        }
    }
}

/// One `name value` line.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    pub name: Name,
    pub name_pos: Pos,
    pub value: Value,
    pub value_pos: Pos,
    /// The whole line (without line end), for caret diagnostics.
    pub(crate) line_text: String,
}

/// A parsed list file: its path and its entries in file order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParamList {
    pub file: PathBuf,
    pub entries: Vec<Entry>,
}

impl ParamList {
    /// The last entry with this exact name (a later line overrides an earlier one).
    pub fn get(&self, name: &str) -> Option<&Entry> {
        self.entries.iter().rev().find(|e| e.name.text == name)
    }

    /// An error diagnostic pointing at `pos` on `entry`'s line.
    pub fn error_at(&self, entry: &Entry, pos: Pos, message: impl Into<String>) -> Diagnostic {
        Diagnostic::error(&self.file, pos.line, pos.col, None, message)
            .with_source(&entry.line_text)
    }

    /// A warning diagnostic pointing at `pos` on `entry`'s line.
    pub(crate) fn warning_at(
        &self,
        entry: &Entry,
        pos: Pos,
        message: impl Into<String>,
    ) -> Diagnostic {
        Diagnostic::warning(&self.file, pos.line, pos.col, None, message)
            .with_source(&entry.line_text)
    }
}

/// A file-level problem (unreadable, too large) as a diagnostic at 1:1.
pub(crate) fn file_error(file: &Path, message: impl Into<String>) -> Diagnostic {
    Diagnostic::error(file, 1, 1, None, message)
}

/// Read a list file with the size bound. Text that is not UTF-8 is taken as Latin-1, the
/// encoding German installations write umlauts in comments with.
pub(crate) fn read_list_text(file: &Path) -> Result<String, Diagnostic> {
    let meta = std::fs::metadata(file)
        .map_err(|e| file_error(file, format!("cannot read parameter list: {e}")))?;
    if !meta.is_file() {
        return Err(file_error(file, "cannot read parameter list: not a file"));
    }
    use crate::bounded::{read_file, BoundedReadError};
    let bytes = read_file(file, MAX_LIST_BYTES).map_err(|e| {
        file_error(
            file,
            match e {
                BoundedReadError::TooLarge { bytes, limit } => {
                    format!("parameter list is {bytes} bytes, more than the limit of {limit} bytes")
                }
                BoundedReadError::Io(e) => format!("cannot read parameter list: {e}"),
                e @ BoundedReadError::NotRegular => format!("parameter list is {e}"),
            },
        )
    })?;
    // A NUL byte is in no text list, UTF-8 or Latin-1: the file is UTF-16 or binary.
    if memchr::memchr(0, &bytes).is_some() {
        return Err(file_error(file, "parameter list is not UTF-8 text"));
    }
    Ok(match String::from_utf8(bytes) {
        Ok(s) => s,
        Err(e) => e.into_bytes().iter().map(|&b| char::from(b)).collect(),
    })
}

/// Read and parse a list file. Malformed lines become errors; parsing goes on after them so
/// one run reports every bad line.
pub(crate) fn read_list(file: &Path) -> Result<(ParamList, Vec<Diagnostic>), Diagnostic> {
    let text = read_list_text(file)?;
    Ok(parse_list(file, &text))
}

/// Parse list text. Returns the entries of every good line and an error for every bad one.
pub fn parse_list(file: &Path, text: &str) -> (ParamList, Vec<Diagnostic>) {
    let mut list = ParamList {
        file: file.to_path_buf(),
        entries: Vec::new(),
    };
    let mut errors = Vec::new();
    // Malformed lines past MAX_LIST_ERRORS: how many, and the first of them.
    let mut unlisted = 0usize;
    let mut first_unlisted = 0usize;
    // A leading byte-order mark is an editor artefact, not part of the first name.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut ended_at: Option<usize> = None;
    for (idx, raw) in text.split('\n').enumerate() {
        let line_no = idx + 1;
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        if let Some(end_line) = ended_at {
            // The kernel stops reading at `Ende`; entries after it would be silently lost.
            if !matches!(parse_line(line), Ok(None)) {
                errors.push(
                    Diagnostic::warning(
                        file,
                        line_no,
                        1,
                        None,
                        format!("after `{END_OF_LIST}` on line {end_line}: not read"),
                    )
                    .with_source(line),
                );
                break;
            }
            continue;
        }
        if is_end_of_list(line) {
            ended_at = Some(line_no);
            continue;
        }
        match parse_line(line) {
            Ok(None) => {}
            Ok(Some(parsed)) => {
                if list.entries.len() >= MAX_ENTRIES {
                    errors.push(
                        Diagnostic::error(
                            file,
                            line_no,
                            1,
                            None,
                            format!("more than {MAX_ENTRIES} entries in one list"),
                        )
                        .with_source(line),
                    );
                    break;
                }
                list.entries.push(Entry {
                    name: parsed.name,
                    name_pos: Pos {
                        line: line_no,
                        col: col_of(line, parsed.name_off),
                    },
                    value: parsed.value,
                    value_pos: Pos {
                        line: line_no,
                        col: col_of(line, parsed.value_off),
                    },
                    line_text: line.to_string(),
                });
            }
            Err(_) if errors.len() >= MAX_LIST_ERRORS => {
                if unlisted == 0 {
                    first_unlisted = line_no;
                }
                unlisted += 1;
            }
            Err(e) => errors.push(
                Diagnostic::error(file, line_no, col_of(line, e.offset), None, e.message)
                    .with_source(line),
            ),
        }
    }
    if unlisted > 0 {
        errors.push(Diagnostic::error(
            file,
            first_unlisted,
            1,
            None,
            format!(
                "{unlisted} more malformed line(s) from here on, not listed (the first {MAX_LIST_ERRORS} are)"
            ),
        ));
    }
    (list, errors)
}

/// The word that ends a list (German "end"): the kernel reads no further.
pub(crate) const END_OF_LIST: &str = "Ende";

/// `Ende` alone on a line (blanks and a comment after a blank allowed).
fn is_end_of_list(line: &str) -> bool {
    let t = line.trim_start_matches(is_blank);
    t.strip_prefix(END_OF_LIST)
        .is_some_and(|rest| rest.is_empty() || rest.starts_with(is_blank))
}

/// Most malformed lines one list reports. A file of garbage has an error a line; the first
/// ones say what is wrong, and listing millions costs gigabytes and minutes, so the rest are
/// counted in one closing diagnostic.
pub const MAX_LIST_ERRORS: usize = 1000;

/// 1-based character column of byte offset `off` in `line`.
fn col_of(line: &str, off: usize) -> usize {
    line.get(..off).map_or(1, |s| s.chars().count() + 1)
}

/// A line that parsed to an entry; offsets are byte offsets into the line.
struct ParsedLine {
    name: Name,
    name_off: usize,
    value: Value,
    value_off: usize,
}

/// Why a line is malformed and where (byte offset into the line).
#[derive(Debug)]
struct LineError {
    offset: usize,
    message: String,
}

fn is_blank(c: char) -> bool {
    c == ' ' || c == '\t'
}

fn blanks(i: &str) -> IResult<&str, &str> {
    take_while(is_blank)(i)
}

fn ident(i: &str) -> IResult<&str, &str> {
    recognize(pair(
        take_while1(|c: char| c.is_ascii_alphabetic() || c == '_'),
        take_while(|c: char| c.is_ascii_alphanumeric() || c == '_'),
    ))
    .parse(i)
}

/// `ident` or `ident[digits]`.
fn segment(i: &str) -> IResult<&str, (&str, Option<&str>)> {
    pair(ident, opt(delimited(char('['), digit1, char(']')))).parse(i)
}

/// A number token: `0x…`, or a decimal with optional sign, fraction and exponent.
fn number(i: &str) -> IResult<&str, &str> {
    alt((
        recognize(pair(tag_no_case("0x"), hex_digit1)),
        recognize((
            opt(alt((char('-'), char('+')))),
            alt((
                recognize((
                    digit1,
                    opt(pair(char('.'), take_while(|c: char| c.is_ascii_digit()))),
                )),
                recognize(pair(char('.'), digit1)),
            )),
            opt((
                alt((char('e'), char('E'))),
                opt(alt((char('-'), char('+')))),
                digit1,
            )),
        )),
    ))
    .parse(i)
}

/// Characters that end an unquoted token.
fn ends_token(c: char) -> bool {
    is_blank(c) || c == '(' || c == '"'
}

/// Parse one line (without line end). `Ok(None)` for blank and comment lines.
fn parse_line(line: &str) -> Result<Option<ParsedLine>, LineError> {
    let (rest, _) = blanks(line).map_err(|_| line_error(line, line, "unreadable line".into()))?;
    if is_comment(rest) {
        return Ok(None);
    }
    let name_off = line.len() - rest.len();
    let (name, cur) = parse_name(line, rest)?;
    let (value, value_off) = parse_value(line, &name.text, cur)?;
    Ok(Some(ParsedLine {
        name,
        name_off,
        value,
        value_off,
    }))
}

/// A line error at `rest`, the unread tail of `line` (its offset is where `rest` starts).
fn line_error(line: &str, rest: &str, message: String) -> LineError {
    LineError {
        offset: line.len() - rest.len(),
        message,
    }
}

/// Line step 1: whether the line (from its first non-blank, `rest`) is blank or a comment.
/// Every line that starts with `#` is one: `#name value` is how installations comment an
/// entry out (`#spindel[0].range_way 0`), `# text`, `#####` rulers; so are `;` lines as in
/// the source documents' examples.
fn is_comment(rest: &str) -> bool {
    rest.is_empty() || rest.starts_with('#') || rest.starts_with(';')
}

/// Line step 2: the name, segments separated by dots, each with an optional `[index]`;
/// returns it with the rest of the line after it.
fn parse_name<'a>(line: &'a str, rest: &'a str) -> Result<(Name, &'a str), LineError> {
    let err = |rest: &str, message: String| line_error(line, rest, message);
    let name_off = line.len() - rest.len();
    let mut segments = Vec::new();
    let mut cur = rest;
    loop {
        let (after, (id, index)) = segment(cur).map_err(|_| {
            err(
                cur,
                if segments.is_empty() {
                    "expected a parameter name".to_string()
                } else {
                    "expected a name part after `.`".to_string()
                },
            )
        })?;
        let index = match index {
            None => None,
            Some(digits) => {
                let idx_rest = &cur[id.len() + 1..];
                match digits.parse::<u32>() {
                    Ok(v) if v <= MAX_INDEX => Some(v),
                    _ => {
                        return Err(err(
                            idx_rest,
                            format!("index {digits} is larger than {MAX_INDEX}"),
                        ))
                    }
                }
            }
        };
        // A `[` that did not close as `[digits]` is a malformed index, not the value.
        if after.starts_with('[') {
            return Err(err(
                after,
                "index must be a decimal number in `[...]`".into(),
            ));
        }
        segments.push(Segment {
            ident: id.to_string(),
            index,
        });
        match after.strip_prefix('.') {
            Some(next) => cur = next,
            None => {
                cur = after;
                break;
            }
        }
    }
    let name_text = &line[name_off..line.len() - cur.len()];
    let name = Name {
        text: name_text.to_string(),
        segments,
    };
    Ok((name, cur))
}

/// Line step 3: the blank(s) after the name, then the value (quoted string, number or
/// word) and what may follow it; returns the value with its offset in the line.
fn parse_value(line: &str, name_text: &str, cur: &str) -> Result<(Value, usize), LineError> {
    let err = |rest: &str, message: String| line_error(line, rest, message);
    // Blank(s) between name and value.
    let (value_start, sep) = blanks(cur).map_err(|_| err(cur, "unreadable line".into()))?;
    if sep.is_empty() {
        let message = if cur.is_empty() {
            format!("`{name_text}` has no value")
        } else {
            format!(
                "expected a blank after `{name_text}`, found `{}`",
                first_char(cur)
            )
        };
        return Err(err(cur, message));
    }
    if value_start.is_empty() {
        return Err(err(value_start, format!("`{name_text}` has no value")));
    }
    let value_off = line.len() - value_start.len();

    // Quoted string: up to the closing quote; a `(` comment may follow.
    if let Some(body) = value_start.strip_prefix('"') {
        let Some(end) = body.find('"') else {
            return Err(err(value_start, "string has no closing `\"`".into()));
        };
        let text = &body[..end];
        let after = &body[end + 1..];
        check_tail(after)
            .map_err(|at| err(at, "expected a blank after the closing `\"`".into()))?;
        let value = Value {
            kind: ValueKind::Quoted,
            text: text.to_string(),
        };
        return Ok((value, value_off));
    }
    if value_start.starts_with('(') {
        return Err(err(
            value_start,
            format!("`{name_text}` has no value (a value starting with `(` must be quoted)"),
        ));
    }

    let (after_tok, token) = take_while1::<_, _, nom::error::Error<&str>>(|c| !ends_token(c))
        .parse(value_start)
        .map_err(|_| err(value_start, "expected a value".into()))?;

    // A number is a number only if the whole token reads as one; `12abc` is a word.
    if let Ok(("", num)) = number(token) {
        let kind = number_kind(num)
            .ok_or_else(|| err(value_start, format!("number `{num}` is out of range")))?;
        // After a number, anything after a blank (or a `(`) is a comment.
        if after_tok.starts_with('"') {
            return Err(err(after_tok, "unexpected `\"` after a number".into()));
        }
        let value = Value {
            kind,
            text: num.to_string(),
        };
        return Ok((value, value_off));
    }

    if let Some(r) = param_ref(token) {
        let value = Value {
            kind: ValueKind::Ref(r),
            text: token.to_string(),
        };
        return Ok((value, value_off));
    }

    // Unquoted word, or a `|` list of words with blanks around the bars
    // (`FCT_DEFAULT | FCT_M_PRE_OUTPUT`); after it, text after a blank is a comment.
    let mut end = value_off + token.len();
    let mut rest = after_tok;
    loop {
        let trimmed = rest.trim_start_matches(is_blank);
        let Some(after_bar) = trimmed.strip_prefix('|') else {
            break;
        };
        let next = after_bar.trim_start_matches(is_blank);
        let (after_next, _) =
            take_while1::<_, _, nom::error::Error<&str>>(|c| !ends_token(c) && c != '|')
                .parse(next)
                .map_err(|_| err(next, "expected a name after `|`".into()))?;
        end = line.len() - after_next.len();
        rest = after_next;
    }
    let text = &line[value_off..end];
    let value = Value {
        kind: ValueKind::Word,
        text: text.to_string(),
    };
    Ok((value, value_off))
}

/// `P-AXIS-00008` or `P-AXIS-00008.0`: another parameter's value by its P number.
fn param_ref(token: &str) -> Option<ParamRef> {
    let rest = token.strip_prefix("P-")?;
    let (group, rest) = rest.split_once('-')?;
    if group.is_empty() || !group.bytes().all(|b| b.is_ascii_uppercase()) {
        return None;
    }
    let (number, index) = match rest.split_once('.') {
        Some((n, i)) => (n, Some(i)),
        None => (rest, None),
    };
    if number.len() != 5 || !number.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let index = match index {
        Some(i) if !i.is_empty() && i.len() <= 5 && i.bytes().all(|b| b.is_ascii_digit()) => {
            Some(i.parse().ok()?)
        }
        Some(_) => return None,
        None => None,
    };
    Some(ParamRef {
        group: group.to_string(),
        number: number.parse().ok()?,
        index,
    })
}

fn first_char(s: &str) -> char {
    s.chars().next().unwrap_or(' ')
}

/// After a quoted string: nothing, a blank (what follows a blank is a comment) or a `(`.
/// On failure returns the rest starting at the offending character.
fn check_tail(after: &str) -> Result<(), &str> {
    if after.is_empty() || after.starts_with(is_blank) || after.starts_with('(') {
        Ok(())
    } else {
        Err(after)
    }
}

fn number_kind(num: &str) -> Option<ValueKind> {
    if let Some(hex) = num.strip_prefix("0x").or_else(|| num.strip_prefix("0X")) {
        return u64::from_str_radix(hex, 16).ok().map(ValueKind::Hex);
    }
    if num.contains(['.', 'e', 'E']) {
        return num
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .map(ValueKind::Float);
    }
    num.parse::<i64>().ok().map(ValueKind::Int)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_utf16_list_is_refused_as_not_utf8_text() {
        let dir = tempfile::tempdir().expect("tempdir");
        let p = dir.path().join("sda_mds1.lis");
        let utf16: Vec<u8> = "kanal_id 1\n"
            .encode_utf16()
            .flat_map(u16::to_le_bytes)
            .collect();
        std::fs::write(&p, [&[0xFF, 0xFE][..], &utf16].concat()).expect("write");
        let d = read_list_text(&p).expect_err("refused");
        assert!(d.render().contains("not UTF-8 text"), "{}", d.render());
    }

    fn one(line: &str) -> Entry {
        let (list, errs) = parse_list(Path::new("t.lis"), line);
        assert!(errs.is_empty(), "{errs:?}");
        assert_eq!(list.entries.len(), 1);
        list.entries.into_iter().next().unwrap()
    }

    fn bad(line: &str) -> Diagnostic {
        let (list, errs) = parse_list(Path::new("t.lis"), line);
        assert!(list.entries.is_empty());
        assert_eq!(errs.len(), 1, "{errs:?}");
        errs.into_iter().next().unwrap()
    }

    #[test]
    fn indexed_name_and_positions() {
        let e = one("  pfad[0].prg[12]\t../nc");
        assert_eq!(e.name.text, "pfad[0].prg[12]");
        assert_eq!(
            e.name.segments,
            vec![
                Segment {
                    ident: "pfad".into(),
                    index: Some(0)
                },
                Segment {
                    ident: "prg".into(),
                    index: Some(12)
                }
            ]
        );
        assert_eq!(e.name_pos, Pos { line: 1, col: 3 });
        assert_eq!(e.value_pos, Pos { line: 1, col: 19 });
        assert_eq!(e.value.as_str(), "../nc");
        assert_eq!(e.value.kind, ValueKind::Word);
    }

    #[test]
    fn numbers_hex_and_comments() {
        assert_eq!(one("a 4096 bytes per file").value.as_int(), Some(4096));
        assert_eq!(one("a 0x03 (both)").value.kind, ValueKind::Hex(3));
        assert_eq!(one("a 0X1f").value.as_int(), Some(31));
        assert_eq!(one("a -5").value.as_int(), Some(-5));
        assert_eq!(one("a 2.5e3 x").value.kind, ValueKind::Float(2500.0));
        assert_eq!(one("a 12(comment)").value.as_int(), Some(12));
        // A token that is not entirely a number is a word.
        assert_eq!(one("a 12abc").value.kind, ValueKind::Word);
        assert_eq!(one("a 0xZZ").value.kind, ValueKind::Word);
    }

    #[test]
    fn strings_quoted_and_with_comments() {
        let e = one("s \"my prog (v2).nc\" (the program)");
        assert_eq!(e.value.kind, ValueKind::Quoted);
        assert_eq!(e.value.as_str(), "my prog (v2).nc");
        assert_eq!(
            one("s streaming.nc (name of streaming program)")
                .value
                .as_str(),
            "streaming.nc"
        );
        assert_eq!(one("s \"\"").value.as_str(), "");
    }

    #[test]
    fn comments_blank_lines_crlf_tabs() {
        let text =
            "# comment\r\n#\r\n\r\n\t \r\n##########\r\n; semicolon style\r\nname\tvalue\r\n";
        let (list, errs) = parse_list(Path::new("t.lis"), text);
        assert!(errs.is_empty(), "{errs:?}");
        assert_eq!(list.entries.len(), 1);
        assert_eq!(list.entries[0].name_pos.line, 7);
        assert_eq!(list.entries[0].value.as_str(), "value");
        assert_eq!(list.entries[0].line_text, "name\tvalue");
    }

    #[test]
    fn malformed_lines_point_at_the_column() {
        let d = bad("kanal_anzahl");
        assert_eq!((d.line, d.col), (1, 13));
        assert!(d.message.contains("no value"));
        let d = bad("pfad[x].prg[0] a");
        assert_eq!(d.col, 5);
        let d = bad("s \"open");
        assert_eq!(d.col, 3);
        let d = bad("s \"x\"y");
        assert_eq!(d.col, 6);
        let d = bad("s A | ");
        assert_eq!(d.col, 7);
        let d = bad("a.b. 3");
        assert_eq!(d.col, 5);
        let d = bad("9abc 3");
        assert_eq!(d.col, 1);
        let d = bad("a[99999999999] 3");
        assert_eq!(d.col, 3);
        let d = bad("a 99999999999999999999999");
        assert!(d.message.contains("out of range"));
        let d = bad("a=3");
        assert_eq!(d.col, 2);
        let d = bad("a (x)");
        assert_eq!(d.col, 3);
    }

    #[test]
    fn errors_do_not_stop_the_parse() {
        let (list, errs) = parse_list(Path::new("t.lis"), "a 1\nb\nc 3\nd \"x\n");
        assert_eq!(list.entries.len(), 2);
        assert_eq!(errs.iter().map(|d| d.line).collect::<Vec<_>>(), vec![2, 4]);
    }

    #[test]
    fn column_counts_characters_not_bytes() {
        let d = bad("ä");
        assert_eq!(d.col, 1);
        let (_, errs) = parse_list(Path::new("t.lis"), "a \"ü\"x");
        assert_eq!(errs[0].col, 6);
    }

    #[test]
    fn the_kernels_own_list_constructs() {
        // `#` glued to a name comments the entry out.
        let (list, errs) = parse_list(Path::new("t.lis"), "#spindel[0].range_way 0\n#comment\n");
        assert!(errs.is_empty() && list.entries.is_empty(), "{errs:?}");
        // Unquoted `|` lists with blanks, then a comment.
        let e = one("configuration.decoder.function FCT_DEFAULT | FCT_M_PRE_OUTPUT |FCT_SURFACE ( P-CHAN-00087");
        assert_eq!(e.value.kind, ValueKind::Word);
        assert_eq!(
            e.value.as_str(),
            "FCT_DEFAULT | FCT_M_PRE_OUTPUT |FCT_SURFACE"
        );
        // Text after a word and a blank is a comment, as after a number.
        assert_eq!(one("s two words").value.as_str(), "two");
        // An unclosed `(` comment after a number.
        let e =
            one("kenngr.swe_pos 15000000 ( P-AXIS-00178 : [0.1um] Positive software limit switch");
        assert_eq!(e.value.as_int(), Some(15_000_000));
        // A reference to another parameter by its P number.
        let e = one("getriebe[0].slope_profil.a_brems P-AXIS-00008.0");
        assert_eq!(
            e.value.kind,
            ValueKind::Ref(ParamRef {
                group: "AXIS".into(),
                number: 8,
                index: Some(0)
            })
        );
        assert!(matches!(
            one("a P-CHAN-00158").value.kind,
            ValueKind::Ref(ParamRef {
                number: 158,
                index: None,
                ..
            })
        ));
        assert_eq!(one("a P-AXIS-8").value.kind, ValueKind::Word);
        // `Ende` ends the list; an entry after it is not read, with a warning.
        let (list, errs) = parse_list(Path::new("t.lis"), "a 1\nEnde\n\n# x\n");
        assert!(errs.is_empty(), "{errs:?}");
        assert_eq!(list.entries.len(), 1);
        let (list, errs) = parse_list(Path::new("t.lis"), "a 1\nEnde\nb 2\n");
        assert_eq!(list.entries.len(), 1);
        assert_eq!(errs.len(), 1);
        assert_eq!(errs[0].severity, crate::diag::Severity::Warning);
        assert_eq!(errs[0].line, 3);
        // `Ende` with a value is an ordinary entry.
        assert_eq!(one("Endeffektor 3").value.as_int(), Some(3));
    }

    #[test]
    fn later_entry_wins_in_get() {
        let (list, _) = parse_list(Path::new("t.lis"), "a 1\na 2\n");
        assert_eq!(list.get("a").unwrap().value.as_int(), Some(2));
    }

    #[test]
    fn a_list_of_garbage_reports_a_bounded_number_of_lines() {
        // 16 MiB of bad lines: the first MAX_LIST_ERRORS, then one line that counts the rest.
        let line = "!!! not a parameter line\n";
        let text = line.repeat((16 << 20) / line.len());
        let (list, errors) = parse_list(Path::new("bad.lis"), &text);
        assert!(list.entries.is_empty());
        assert_eq!(errors.len(), MAX_LIST_ERRORS + 1);
        assert!(errors[MAX_LIST_ERRORS]
            .message
            .contains("more malformed line(s)"));
    }
}
