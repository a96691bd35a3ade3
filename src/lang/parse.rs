//! One NC line → [`Block`]: block skip, block number, label, then words and assignments or
//! one `$` statement, `#` command, call or program head (TF5200 programming manual).
//!
//! The hot path — ordinary words with literal numbers, `N123 G01 X12.345 Y-6.789` — is a
//! byte-level scan with one allocation per block (its item list, none when the caller lends
//! a kept one, [`parse_block_reusing`]); everything rarer (commands, expressions, variable
//! references) goes through the nom parsers in [`super::expr`].

use nom::bytes::complete::take_while1;
use nom::character::complete::char as ch;

use super::block::{
    AxisName, Block, Body, Call, Command, Control, CycleArg, Expr, Functions, GotoTarget, Item,
    Label, NamedAxis, ProgramHead, SplineCommand, VScope, Value, VarDecl, VarRef, VarType, Word,
    AXIS_NAME_MAX,
};
use super::codes::{
    is_known_g, is_known_m, is_word_letter, word_twice, AXIS_TWICE, CACHE_DOUBLE, CACHE_SYNTAX,
    COMMAND_NOT_ALONE, CONTROL_NOT_ALONE, DWELL_NOT_ALONE, G_WITH_VALUE, MAX_ARRAY_DIMS,
    MAX_ARRAY_ELEMENTS, MAX_BLOCK_CHARS, M_TWICE, SPINDLE_SPEED_0, SPINDLE_SPEED_NEGATIVE,
    STRING_TOO_LONG_FOR_VARIABLE, SYNTAX, S_TWICE, TOO_MANY_INDICES, UNKNOWN_COMMAND, UNKNOWN_G,
    UNKNOWN_H, UNKNOWN_M, UNSUPPORTED, VARIABLE_MEMORY_FULL,
};
use super::dialect::{command_support, g_support, Support};
use super::error::SyntaxError;
use super::expr::{
    fail, keyword, name_or, name_upper, perr, uint, verbatim_options, ws, Ctx, PErr, PResult,
};
use super::number::{scan_unsigned, TOO_LARGE};
use super::range::word_value;
use crate::vocab::flush::FlushKind;

/// Parse one NC line. A trailing CR, LF or CR LF is ignored; any other line end inside the
/// line, or more than 4000 characters, is error 20200.
pub fn parse_block(line: &str) -> Result<Block, SyntaxError> {
    parse_block_reusing(line, Vec::new())
}

/// [`parse_block`] that puts an ordinary block's items into `items` (cleared first), so a
/// caller that parses one line after another keeps one item list's allocation instead of
/// taking and freeing one a block (the decoder gets it back with [`Block::take_items`]).
pub fn parse_block_reusing(line: &str, mut items: Vec<Item>) -> Result<Block, SyntaxError> {
    items.clear();
    let (line, ascii) = checked_line(line)?;
    let ctx = Ctx::with_ascii(line, ascii);
    block(&ctx, line, items).map_err(|e| ctx.to_error(e))
}

/// Is this line `#COMMENT END` (case-insensitive, optionally after a block skip and block
/// number, optionally followed by a comment)? The decoder asks this for every line inside a
/// `#COMMENT BEGIN` block without parsing the line: comment text need not be valid NC.
pub fn is_comment_end(line: &str) -> bool {
    is_comment_command(line, "END")
}

/// Is this line `#COMMENT <word>` and nothing else (but a comment)?
fn is_comment_command(line: &str, word: &'static str) -> bool {
    let line = strip_line_end(line);
    let Ok((i, _)) = prefix(ws(line)) else {
        return false;
    };
    let Some(i) = gap(i).strip_prefix('#') else {
        return false;
    };
    let Some(i) = keyword(ws(i), "COMMENT") else {
        return false;
    };
    if !i.starts_with([' ', '\t']) {
        return false;
    }
    let Some(i) = keyword(ws(i), word) else {
        return false;
    };
    gap(i).is_empty()
}

/// Is this line empty or a comment only? Lines inside `#VAR` … `#ENDVAR` that are blank carry
/// no declaration; the decoder skips them before calling [`parse_var_declaration`].
pub fn is_blank_line(line: &str) -> bool {
    gap(strip_line_end(line)).is_empty()
}

/// Parse one declaration between `#VAR` and `#ENDVAR`: `V.L.COUNT = 5`, `V.P.TABLE[10]`,
/// `V.S.GRID[3][4] = 0`. `V.E.` variables are not declared in programs (20200).
pub fn parse_var_declaration(line: &str) -> Result<VarDecl, SyntaxError> {
    let (line, ascii) = checked_line(line)?;
    let ctx = Ctx::with_ascii(line, ascii);
    var_decl(&ctx, line).map_err(|e| ctx.to_error(e))
}

/// One line between `#VAR` and `#ENDVAR`, as the static check and the decoder both read it:
/// so a declaration `check` accepts is one a run accepts, and the other way round.
#[derive(Debug, Clone, PartialEq)]
pub enum VarLine {
    /// Empty or a comment only: declares nothing.
    Blank,
    /// `#ENDVAR` (optionally after a block number): the block ends.
    End,
    /// A declaration, validated (at most three sizes, at most `MAX_ARRAY_ELEMENTS` elements).
    Decl(VarDecl),
    /// `#COMMENT BEGIN`: a comment block inside the declarations (ISG's editor documents a
    /// variable this way, `isg-stuttgart/vscode-isg-cnc` `src/test/res/docHover1.nc`); the
    /// lines up to `#COMMENT END` are comment text, then declarations go on.
    CommentBegin,
}

/// Read one line inside a `#VAR` block.
pub fn parse_var_line(line: &str) -> Result<VarLine, SyntaxError> {
    if is_blank_line(line) {
        return Ok(VarLine::Blank);
    }
    if is_var_end(line) {
        return Ok(VarLine::End);
    }
    if is_comment_command(line, "BEGIN") {
        return Ok(VarLine::CommentBegin);
    }
    parse_var_declaration(line).map(VarLine::Decl)
}

/// Is this line `#ENDVAR`, after an optional block skip, number and label?
fn is_var_end(line: &str) -> bool {
    let line = strip_line_end(line);
    let Ok((i, _)) = prefix(ws(line)) else {
        return false;
    };
    let Some(i) = gap(i).strip_prefix('#') else {
        return false;
    };
    keyword(i, "ENDVAR").is_some_and(|r| gap(r).is_empty())
}

/// Strip one trailing CR LF, LF or CR.
fn strip_line_end(line: &str) -> &str {
    if !matches!(line.as_bytes().last(), Some(b'\r' | b'\n')) {
        return line;
    }
    line.strip_suffix("\r\n")
        .or_else(|| line.strip_suffix('\n'))
        .or_else(|| line.strip_suffix('\r'))
        .unwrap_or(line)
}

/// The line without its line end, and whether it is pure ASCII.
fn checked_line(line: &str) -> Result<(&str, bool), SyntaxError> {
    let line = strip_line_end(line);
    // One word-at-a-time pass (eight bytes a step) for both questions, where a fold over
    // the bytes cost ~6 instructions a byte (callgrind).
    let (ascii, line_end) = super::bytes::ascii_and_line_end(line.as_bytes());
    if line.len() > MAX_BLOCK_CHARS && line.chars().count() > MAX_BLOCK_CHARS {
        return Err(SyntaxError::new(
            SYNTAX,
            MAX_BLOCK_CHARS as u32 + 1,
            format!("block longer than {MAX_BLOCK_CHARS} characters"),
        ));
    }
    if line_end {
        let pos = line.find(['\r', '\n']).unwrap_or(0);
        let col = line[..pos].chars().count() as u32 + 1;
        return Err(SyntaxError::new(SYNTAX, col, "line end inside the block"));
    }
    Ok((line, ascii))
}

/// Skip blanks and comments: `( … )` nesting, an unclosed `(` to block end, `;` to line end.
///
/// One index over the bytes (callgrind: re-slicing after each blank and comment cost about
/// 30 instructions a call, most calls skipping one blank).
#[inline]
pub(crate) fn gap(i: &str) -> &str {
    let b = i.as_bytes();
    let mut k = 0;
    loop {
        match b.get(k) {
            Some(b' ' | b'\t') => k += 1,
            Some(b';') => return "",
            Some(b'(') => k = comment_end(b, k),
            // `k` stands after ASCII bytes only: a character boundary.
            _ => return i.get(k..).unwrap_or(""),
        }
    }
}

/// Where the comment opened at `b[at]` ends: after its matching `)`, or at the line's end.
fn comment_end(b: &[u8], at: usize) -> usize {
    let mut depth = 0usize;
    for (k, &c) in b.iter().enumerate().skip(at) {
        match c {
            b'(' => depth += 1,
            b')' => {
                depth -= 1;
                if depth == 0 {
                    return k + 1;
                }
            }
            _ => {}
        }
    }
    b.len()
}

/// Block skip, block number and label: what may precede every body.
fn prefix<'a>(mut i: &'a str) -> PResult<'a, (Option<u8>, Option<u32>, Option<Label>)> {
    let mut skip = None;
    if let Some(rest) = i.strip_prefix('/') {
        if rest.as_bytes().first().is_some_and(u8::is_ascii_digit) {
            let (r, level) = uint(rest)?;
            if !(1..=10).contains(&level) {
                return fail(rest, SYNTAX, "block skip level must be 1 to 10");
            }
            skip = Some(level as u8);
            i = r;
        } else {
            skip = Some(1);
            i = rest;
        }
        i = ws(i);
    }
    let mut n = None;
    let mut label = None;
    if let Some(&b) = i.as_bytes().first() {
        if b == b'N' || b == b'n' {
            let rest = &i[1..];
            if !rest.as_bytes().first().is_some_and(u8::is_ascii_digit) {
                return fail(rest, SYNTAX, "block number expected after N");
            }
            let (r, num) = uint(rest)?;
            n = Some(num);
            i = r;
            if let Some(r) = i.strip_prefix(':') {
                label = Some(Label::Number(num));
                i = r;
            }
        }
    }
    let j = gap(i);
    if label.is_none() && j.starts_with('[') {
        let (r, name) = bracket_name(j)?;
        label = Some(Label::Name(name));
        i = r;
    }
    Ok((i, (skip, n, label)))
}

/// The common prefix, `N123 ` and no block skip nor label: the number and the rest from the
/// next word (past blanks and comments), read in one step. `None` for anything else,
/// which [`prefix`] reads.
#[inline]
fn block_number_only(line: &str) -> Option<(&str, u32)> {
    let b = line.as_bytes();
    if !matches!(b.first(), Some(b'N' | b'n')) {
        return None;
    }
    let (n, digits) = super::number::digit_run(&b[1..]);
    // One to seven digits (below 10^7, a u32), then a blank: not `N40:`, not a long number.
    if !(1..super::number::RUN).contains(&digits)
        || !matches!(b.get(1 + digits), Some(b' ' | b'\t'))
    {
        return None;
    }
    // ASCII digits and a blank end on a character boundary.
    let rest = gap(line.get(1 + digits..)?);
    if rest.starts_with('[') {
        return None;
    }
    Some((rest, n as u32))
}

/// `[NAME]`: a string label or `$GOTO` target, upper-cased.
fn bracket_name(i: &str) -> PResult<'_, String> {
    let (r, _) = ch('[')(i)?;
    let r = ws(r);
    let (r, name) = match name_upper(r) {
        Ok(ok) => ok,
        Err(_) => return fail(r, SYNTAX, "label name expected"),
    };
    let r = ws(r);
    match ch::<&str, PErr<'_>>(']')(r) {
        Ok((r, _)) => Ok((r, name)),
        Err(_) => fail(r, SYNTAX, "`]` expected after the label name"),
    }
}

fn block<'a>(
    ctx: &Ctx<'a>,
    line: &'a str,
    items_list: Vec<Item>,
) -> Result<Block, nom::Err<PErr<'a>>> {
    let line = ws(line);
    let (i, (skip_level, n, label)) = match block_number_only(line) {
        Some((i, n)) => (i, (None, Some(n), None)),
        None => prefix(line)?,
    };
    let i = gap(i);
    let body = match i.as_bytes().first() {
        None => Body::Items(items_list),
        Some(b'#') => {
            let (r, c) = command(ctx, i)?;
            end_of_block(r, "nothing may follow a # command in its block")?;
            Body::Command(Box::new(c))
        }
        Some(b'$') => {
            let (r, c) = control(ctx, i)?;
            end_of_block(r, "nothing may follow a $ statement in its block")?;
            Body::Control(Box::new(c))
        }
        Some(b'%') => {
            let (r, (name, local)) = program_head(i)?;
            let (r, title) = program_title(r);
            end_of_block(r, "nothing may follow a program head in its block")?;
            Body::ProgramHead(Box::new(ProgramHead { name, local, title }))
        }
        Some(b'L' | b'l') if starts_call(i) => {
            let (r, c) = call(ctx, i)?;
            end_of_block(r, "nothing may follow L, LL or L CYCLE in its block")?;
            Body::Call(Box::new(c))
        }
        Some(_) => Body::Items(items(ctx, i, items_list)?),
    };
    Ok(Block {
        skip_level,
        n,
        label,
        body,
    })
}

fn end_of_block<'a>(i: &'a str, msg: &'static str) -> Result<(), nom::Err<PErr<'a>>> {
    let r = gap(i);
    if r.is_empty() {
        Ok(())
    } else {
        fail::<()>(r, SYNTAX, msg).map(|_| ())
    }
}

/// `L ` or `LL ` followed by a blank: a call, not an (unknown) address letter L.
fn starts_call(i: &str) -> bool {
    let b = i.as_bytes();
    let blank = |k: usize| matches!(b.get(k), Some(b' ' | b'\t'));
    blank(1) || (matches!(b.get(1), Some(b'L' | b'l')) && blank(2))
}

// ---------------------------------------------------------------------------------------
// Ordinary blocks: words and assignments
// ---------------------------------------------------------------------------------------

/// The items a list made for [`parse_block_reusing`] holds without growing: most blocks have
/// fewer, and a list this large is not sized again for each line.
pub const ITEM_LIST_CAPACITY: usize = 32;

/// An upper bound on the items in the rest of a block: the bytes before the first comment
/// that have bit 0x40, which every letter and `@` has and no digit, point, sign, blank or
/// `=` (capped; a longer block grows its list). Sizing the list once keeps the hot path at
/// one allocation per block; brackets and `_` in expressions count too, a few spare places.
///
/// Eight bytes a step (callgrind: counting letters and `@` exactly, a 16-byte chunk at a
/// time, cost about 135 instructions a line of the 3-axis benchmark program).
fn item_capacity(i: &str) -> usize {
    const CAP: usize = ITEM_LIST_CAPACITY;
    const BIT6: u64 = 0x4040_4040_4040_4040;
    // The item starts in one word, and whether a comment starts in it.
    let count = |w: u64| {
        let comment = super::bytes::equal_bytes(w, b'(') | super::bytes::equal_bytes(w, b';');
        // Only the bytes before the first comment start (the lowest flagged byte, exact).
        let before = comment.wrapping_sub(1) & !comment;
        let starts = (w & BIT6 & before) >> 6;
        // One 0 or 1 a byte: the top byte of the product is their sum.
        (
            (starts.wrapping_mul(0x0101_0101_0101_0101) >> 56) as usize,
            comment != 0,
        )
    };
    let (words, rest) = i.as_bytes().as_chunks::<8>();
    let mut n = 0usize;
    for w in words {
        let (k, comment) = count(u64::from_le_bytes(*w));
        n += k;
        if comment {
            return n.min(CAP);
        }
    }
    // The rest padded with NULs, which are neither item starts nor comment starts.
    let tail = rest
        .iter()
        .rev()
        .fold(0u64, |w, &c| (w << 8) | u64::from(c));
    (n + count(tail).0).min(CAP)
}

/// The items of an ordinary block, pushed onto `items` (empty; its capacity is reused).
fn items<'a>(
    ctx: &Ctx<'a>,
    mut i: &'a str,
    mut items: Vec<Item>,
) -> Result<Vec<Item>, nom::Err<PErr<'a>>> {
    if items.capacity() < ITEM_LIST_CAPACITY {
        items.reserve_exact(item_capacity(i));
    }
    // Letters seen so far (bit = letter - 'A'): a second F, S, axis … is double programming.
    let mut seen = 0u32;
    // The block's own M words: with two or more, each number once (20765), checked at the
    // end so the literal words' loop only counts them.
    let mut ms = 0usize;
    let mut dwell = false;
    loop {
        i = gap(i);
        let bytes = i.as_bytes();
        let Some(&b) = bytes.first() else {
            if dwell {
                dwell_alone(ctx, &items)?;
            }
            if ms > 1 {
                functions_once(ctx, &items)?;
            }
            return Ok(items);
        };
        let up = b.to_ascii_uppercase();
        let dot_follows = bytes.get(1) == Some(&b'.');
        if is_word_letter(up) && !(up == b'V' && dot_follows) {
            let at = i;
            i = word(ctx, i, up, &mut items)?;
            match up {
                b'G' => dwell |= items.last().is_some_and(is_dwell),
                b'M' => ms += 1,
                b'H' => {}
                _ if bytes.get(1) == Some(&b'[') && ends_in_function(&items) => {}
                _ => {
                    let bit = 1u32 << (up - b'A');
                    if seen & bit != 0 {
                        return Err(twice(at, up));
                    }
                    seen |= bit;
                }
            }
        } else if up == b'P' || b == b'@' || (up == b'V' && dot_follows) {
            let (r, item) = assignment(ctx, i)?;
            items.push(item);
            i = r;
        } else {
            let (code, msg) = match b {
                b'#' => (
                    COMMAND_NOT_ALONE,
                    "a # command must stand alone in its block",
                ),
                b'$' => (
                    CONTROL_NOT_ALONE,
                    "a $ statement must stand alone in its block",
                ),
                b'%' => (SYNTAX, "a program head must stand alone in its block"),
                b'N' | b'n' => (SYNTAX, "the block number must come first in the block"),
                b'L' | b'l' => (SYNTAX, "a call must stand alone in its block"),
                _ => (SYNTAX, "NC command or axis name expected"),
            };
            return Err(perr(i, code, msg));
        }
    }
}

/// `P1=10`, `P1[2]+=P3`, `V.L.X=…`, `@P1=…` at `i`: the item and the rest. `P<n>`, the
/// commonest target, is read without the general variable reader ([`Ctx::const_p`]).
fn assignment<'a>(ctx: &Ctx<'a>, i: &'a str) -> PResult<'a, Item> {
    let col = ctx.col(i);
    if let Some((r, number)) = ctx.const_p(i) {
        let (r, op, value) = assigned(ctx, r)?;
        let item = Item::AssignP {
            number,
            value,
            col,
            op,
        };
        return Ok((r, item));
    }
    let (r, target) = ctx.var_ref(i)?;
    writable(&target, i)?;
    let (r, op, value) = assigned(ctx, r)?;
    Ok((r, Item::assign(target, value, col, op)))
}

/// What follows an assignment's target: `=` or a combined operator, then the value.
fn assigned<'a>(
    ctx: &Ctx<'a>,
    r: &'a str,
) -> Result<(&'a str, Option<super::block::BinOp>, Expr), nom::Err<PErr<'a>>> {
    let r = ws(r);
    let (r, op) = match r.strip_prefix('=') {
        Some(r) => (r, None),
        None => match combined_assignment(r) {
            Some((r, op)) => (r, Some(op)),
            None => return Err(perr(r, SYNTAX, "`=` expected after the parameter")),
        },
    };
    let (r, value) = ctx.expr(ws(r))?;
    Ok((r, op, value))
}

/// A combined assignment operator at `i`, `+=` `-=` `*=` `/=` (TF5200 diagnosis ID 20574:
/// "the combined assignment operator /="), and the rest after it.
fn combined_assignment(i: &str) -> Option<(&str, super::block::BinOp)> {
    use super::block::BinOp;
    let op = match i.as_bytes() {
        [b'+', b'=', ..] => BinOp::Add,
        [b'-', b'=', ..] => BinOp::Sub,
        [b'*', b'=', ..] => BinOp::Mul,
        [b'/', b'=', ..] => BinOp::Div,
        _ => return None,
    };
    Some((&i[2..], op))
}

/// The M numbers one scope of a block programs (the channel's, or one bracket's), for the
/// kernel's 20765: the same M twice in one scope (TF5200 diagnosis ID 20765: `M10 M10` and
/// `S[M10 M10]` are refused, `M10 X[M10] S[M10]` is three functions). Blocks carry a handful;
/// past [`FunctionNumbers::KEPT`] no more are compared (the decoder bounds the count).
#[derive(Default)]
struct FunctionNumbers {
    numbers: [u32; FunctionNumbers::KEPT],
    n: usize,
}

impl FunctionNumbers {
    const KEPT: usize = 16;

    /// The M function `item` just read at `at`: refused when its number came before.
    fn add<'a>(&mut self, item: Option<&Item>, at: &'a str) -> Result<(), nom::Err<PErr<'a>>> {
        let number = match item {
            Some(Item::Word(w)) => match w.value {
                Value::Num(v) => integer_code(v),
                Value::Expr(_) => None,
            },
            Some(Item::FunctionValue { number, .. }) => Some(*number),
            _ => None,
        };
        let Some(number) = number else {
            return Ok(());
        };
        if self.numbers[..self.n].contains(&number) {
            return Err(perr(
                at,
                M_TWICE,
                format!("M{number} programmed twice in the block"),
            ));
        }
        if self.n < Self::KEPT {
            self.numbers[self.n] = number;
            self.n += 1;
        }
        Ok(())
    }
}

/// The block's own M functions (not those in an axis's or the spindle's brackets), each
/// number once: the second of one number is 20765 at its word.
#[cold]
fn functions_once<'a>(ctx: &Ctx<'a>, items: &[Item]) -> Result<(), nom::Err<PErr<'a>>> {
    let mut ms = FunctionNumbers::default();
    for it in items {
        let col = match it {
            Item::Word(w) if w.letter == b'M' => w.col,
            Item::FunctionValue {
                letter: b'M', col, ..
            } => *col,
            _ => continue,
        };
        let at = ctx.rest_at(col);
        ms.add(Some(it), at)?;
    }
    Ok(())
}

/// Was the word just read an axis's or the spindle's functions without a speed: `X[M54]`,
/// `S[M3 M10]`, which program neither the axis nor the speed (`X[M54] X10` is one X)? Asked
/// only for a word whose letter a bracket follows: the literal words of the hot path skip it.
#[inline]
fn ends_in_function(items: &[Item]) -> bool {
    match items.last() {
        Some(Item::Functions(fs)) => !fs
            .items
            .iter()
            .any(|it| matches!(it, Item::Word(w) if w.letter == b'S')),
        _ => false,
    }
}

/// Is this item the dwell `G04` (with or without its value)?
fn is_dwell(it: &Item) -> bool {
    match it {
        Item::GValue { g, .. } => *g == 4,
        Item::Word(w) => w.letter == b'G' && w.value == Value::Num(4.0),
        Item::Assign { .. }
        | Item::AssignP { .. }
        | Item::FunctionValue { .. }
        | Item::GCall(_)
        | Item::NamedAxis(_)
        | Item::Functions(_) => false,
    }
}

/// A letter programmed a second time in its block: [`AXIS_TWICE`] for an axis, [`word_twice`]
/// for the rest.
fn twice(at: &str, letter: u8) -> nom::Err<PErr<'_>> {
    let l = letter as char;
    if is_axis_letter(letter) {
        perr(
            at,
            AXIS_TWICE,
            format!("axis {l} programmed twice in the block"),
        )
    } else {
        perr(
            at,
            word_twice(letter),
            format!("{l} programmed twice in the block"),
        )
    }
}

/// A dwell stands alone in its block (TF5200 G04): besides `G04` only its time, as `G04 <t>`,
/// `G04 P1` (a parameter's value), `G04 X<t>` or `G04 F<t>`, or its spindle revolutions
/// `G04 S<n>`. Anything else — a second G, an M — is refused rather than executed as a move
/// or a feed. Axes have the kernel's ids (TF5200 diagnosis): a time given directly and by an
/// axis is 20013 (`G04 10 X2`), an axis without the first main axis 20014 (`G04 Y2`); further
/// axes beside X (`G04 X2 Y3`) pass here and are the decoder's warning 20685. A named axis
/// (`X1=2`) passes too: only the channel knows whether it is the first main axis.
fn dwell_alone<'a>(ctx: &Ctx<'a>, items: &[Item]) -> Result<(), nom::Err<PErr<'a>>> {
    use super::codes::{DWELL_DIRECT_AND_AXIS, DWELL_NOT_FIRST_AXIS};
    let direct = items
        .iter()
        .any(|it| matches!(it, Item::GValue { g: 4, .. }));
    let first_axis = items
        .iter()
        .any(|it| matches!(it, Item::Word(w) if w.letter == b'X'));
    let mut time_given = direct;
    for it in items {
        if is_dwell(it) {
            continue;
        }
        let axis_col = match it {
            Item::Word(w) if crate::vocab::axis::slot_of(w.letter).is_some() => Some(w.col),
            Item::NamedAxis(a) => Some(a.col),
            _ => None,
        };
        if let Some(col) = axis_col.filter(|_| direct) {
            return Err(ctx.err_at(
                col,
                DWELL_DIRECT_AND_AXIS,
                "dwell time programmed directly and via coordinate",
            ));
        }
        let (col, what) = match it {
            Item::Word(w) if matches!(w.letter, b'X' | b'F' | b'S') && !time_given => {
                time_given = true;
                continue;
            }
            Item::Word(w) if w.letter != b'X' && axis_col.is_some() => {
                if !first_axis {
                    return Err(ctx.err_at(
                        w.col,
                        DWELL_NOT_FIRST_AXIS,
                        format!(
                            "dwell time not programmed with the coordinate of the first axis X \
                             but of {}",
                            w.letter as char
                        ),
                    ));
                }
                continue;
            }
            Item::NamedAxis(_) => continue,
            Item::Word(w) => (w.col, format!("{}", w.letter as char)),
            Item::Assign { col, .. } | Item::AssignP { col, .. } => {
                (*col, "an assignment".to_string())
            }
            Item::GValue { g, col, .. } => (*col, format!("G{g}")),
            Item::FunctionValue {
                letter,
                number,
                col,
                ..
            } => (*col, format!("{}{number}", char::from(*letter))),
            Item::GCall(c) => (c.col, format!("G{}", c.g)),
            Item::Functions(fs) => (fs.col, format!("{}[…]", char::from(fs.owner))),
        };
        return Err(ctx.err_at(
            col,
            DWELL_NOT_ALONE,
            format!("G04 must stand alone in its block: {what} found with it"),
        ));
    }
    Ok(())
}

/// One address word at `i` (letter `up`), pushed onto `items`; returns the rest.
///
/// The literal case is the hot path and builds the item from scalars: moving a whole
/// `Value` through the stack cost store-forwarding stalls that showed in the profile.
#[inline]
fn word<'a>(
    ctx: &Ctx<'a>,
    i: &'a str,
    up: u8,
    items: &mut Vec<Item>,
) -> Result<&'a str, nom::Err<PErr<'a>>> {
    let col = ctx.col(i);
    let after = &i[1..];
    let ab = after.as_bytes();
    let slot_letter = is_axis_letter(up);
    if slot_letter
        && ab
            .first()
            .is_some_and(|&c| c.is_ascii_alphabetic() || c == b'_')
    {
        if let Some(r) = named_axis(ctx, i, col, items)? {
            return Ok(r);
        }
    }
    let (neg, skip) = match ab.first() {
        // A literal, the common word: no other form starts with a digit or a point.
        Some(b'0'..=b'9' | b'.') => (false, 0),
        Some(b'-') if ab.get(1).is_some_and(|&c| c.is_ascii_digit() || c == b'.') => (true, 1),
        Some(b'[') => return word_expr(ctx, i, up, col, after, false, items),
        Some(b'P' | b'p' | b'V' | b'v' | b'@') if starts_variable(ab) => {
            return word_unbracketed(ctx, i, up, col, after, items)
        }
        Some(b'-' | b'+') if starts_variable(&ab[1..]) => {
            return word_unbracketed(ctx, i, up, col, after, items)
        }
        Some(b'=' | b' ' | b'\t') if is_axis_letter(up) && ws(after).starts_with('=') => {
            return axis_assigned(ctx, up, col, after, items)
        }
        Some(b'-') if ab.get(1) == Some(&b'[') => {
            return word_expr(ctx, i, up, col, &after[1..], true, items)
        }
        Some(b'+') if ab.get(1) == Some(&b'[') => {
            return word_expr(ctx, i, up, col, &after[1..], false, items)
        }
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        Some(_) => (false, 0),
        None => return Err(perr(after, SYNTAX, word_value_msg(up))),
    };
    let Some((mag, n)) = scan_unsigned(&ab[skip..]) else {
        return word_function(ctx, i, up, col, (&after[skip..], neg), items);
    };
    if !mag.is_finite() {
        return Err(perr(&after[skip..], SYNTAX, TOO_LARGE));
    }
    let v = if neg { -mag } else { mag };
    let rest = &after[skip + n..];
    if slot_letter && skip == 0 && may_continue_axis_name(rest.as_bytes()) {
        // `X1=10`, `X1A = 5`: the digits began a longer axis name, not a value.
        if let Some(r) = named_axis(ctx, i, col, items)? {
            return Ok(r);
        }
    }
    match up {
        b'G' => {
            let Some(g) = integer_code(v) else {
                return Err(perr(i, UNKNOWN_G, format!("unknown G function G{v}")));
            };
            if !is_known_g(g) {
                if let Err(refused) = dialect_g(i, g) {
                    return refused_g_first(ctx, (i, rest), (g, col), items, refused);
                }
                if let Some(r) = super::gcall::g_call(ctx, rest, g, col, items)? {
                    return Ok(r);
                }
            }
            // The implemented G functions take no value but G04: G01 skips the list search.
            if (g == 4 || !is_known_g(g)) && G_WITH_VALUE.contains(&g) {
                if let Some((r, value)) = g_value(ctx, rest, g == 4)? {
                    items.push(Item::GValue { g, value, col });
                    return Ok(r);
                }
            }
        }
        b'M' if !integer_code(v).is_some_and(is_known_m) => {
            return Err(perr(i, UNKNOWN_M, format!("unknown M function M{v}")));
        }
        b'H' if !integer_code(v).is_some_and(is_known_m) => {
            return Err(perr(
                i,
                UNKNOWN_H,
                format!("H function H{v} outside 0 to 65535"),
            ));
        }
        b'M' | b'H' => {
            if let Some(r) = ws(rest).strip_prefix('=') {
                return function_value(ctx, (up, v), col, r, items);
            }
        }
        _ => {
            if let Err(e) = word_value(up, v) {
                return Err(perr(i, e.code, e.message));
            }
        }
    }
    items.push(Item::Word(Word {
        letter: up,
        value: Value::Num(v),
        col,
    }));
    Ok(rest)
}

/// G, M and H take literal numbers only.
fn literal_only(i: &str, up: u8) -> Result<(), nom::Err<PErr<'_>>> {
    match up {
        b'G' => Err(perr(i, UNKNOWN_G, "a G function needs a literal number")),
        b'M' => Err(perr(i, UNKNOWN_M, "an M function needs a literal number")),
        b'H' => Err(perr(i, UNKNOWN_H, "an H function needs a literal number")),
        _ => Ok(()),
    }
}

/// `M200=1200`: an M or H function with a value (TF5200 programming manual, "User-specific
/// technology functions"); `i` is the text after the `=`.
#[cold]
fn function_value<'a>(
    ctx: &Ctx<'a>,
    (up, number): (u8, f64),
    col: u32,
    i: &'a str,
    items: &mut Vec<Item>,
) -> Result<&'a str, nom::Err<PErr<'a>>> {
    let (r, e) = ctx.expr(ws(i))?;
    items.push(Item::FunctionValue {
        letter: up,
        number: integer_code(number).unwrap_or(0),
        value: expr_value(e),
        col,
    });
    Ok(r)
}

/// `X1=10`, `Z_ACHSE = P1*2` (`i` at the name): an axis name of more than one character,
/// which takes `=` before its value (TF5200 programming manual, "Axis commands"). `None`
/// when no `=` follows the name (`X10 Y5` is X with 10). A name longer than
/// [`AXIS_NAME_MAX`] is 20200 at the name.
#[cold]
fn named_axis<'a>(
    ctx: &Ctx<'a>,
    i: &'a str,
    col: u32,
    items: &mut Vec<Item>,
) -> Result<Option<&'a str>, nom::Err<PErr<'a>>> {
    let len = i
        .bytes()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == b'_')
        .count();
    let after = ws(&i[len..]);
    if !after.starts_with('=') || after.starts_with("==") {
        return Ok(None);
    }
    let Some(name) = AxisName::new(&i[..len]) else {
        return Err(perr(
            i,
            SYNTAX,
            format!("axis name longer than {AXIS_NAME_MAX} characters"),
        ));
    };
    let (r, e) = ctx.expr(ws(&after[1..]))?;
    items.push(Item::NamedAxis(Box::new(NamedAxis {
        name,
        value: expr_value(e),
        col,
    })));
    Ok(Some(r))
}

/// After an axis letter and its digits (`X1` of `X1=10`), could the name go on or take its
/// value? Asked for every axis word after its number is read: one byte for `X10.5` or
/// `X10 Y5`; only a letter, `_` or an `=` sends the word to [`named_axis`].
#[inline]
fn may_continue_axis_name(rest: &[u8]) -> bool {
    match rest.first() {
        Some(c) if c.is_ascii_alphanumeric() || *c == b'_' || *c == b'=' => true,
        Some(b' ' | b'\t') => rest
            .iter()
            .find(|&&c| c != b' ' && c != b'\t')
            .is_some_and(|&c| c == b'='),
        _ => false,
    }
}

/// `X=10`, `X = P1+2`: an axis given an expression after an equals sign.
#[cold]
fn axis_assigned<'a>(
    ctx: &Ctx<'a>,
    up: u8,
    col: u32,
    after: &'a str,
    items: &mut Vec<Item>,
) -> Result<&'a str, nom::Err<PErr<'a>>> {
    let (r, e) = ctx.unbracketed_value(ws(&ws(after)[1..]))?;
    items.push(Item::Word(Word {
        letter: up,
        value: expr_value(e),
        col,
    }));
    Ok(r)
}

/// An axis name: X Y Z A B C and the further axis names U V W. Longer names (`A1 = 0`, `W2 = 1`) are
/// [`named_axis`]'s.
#[inline]
fn is_axis_letter(up: u8) -> bool {
    matches!(
        up,
        b'X' | b'Y' | b'Z' | b'A' | b'B' | b'C' | b'U' | b'V' | b'W'
    )
}

/// Does a parameter or variable start here (`P1`, `P[..]`, `V.L.X`, `@P1`)?
fn starts_variable(b: &[u8]) -> bool {
    match b {
        [b'P' | b'p', c, ..] => c.is_ascii_digit() || *c == b'[' || super::expr::is_pp(b),
        [b'V' | b'v', b'.', ..] => true,
        [b'@', b'P' | b'p', ..] => true,
        _ => false,
    }
}

/// A word whose value is an expression starting with a parameter or variable, written
/// without brackets: `XP1*SIN[P2*30]`, `TV.P.TOOLNR`, `BP10+P20`. The expression runs to
/// the next blank or comment outside brackets (TF5200 programming manual, "Arithmetic
/// expressions" and "Parameters").
#[cold]
fn word_unbracketed<'a>(
    ctx: &Ctx<'a>,
    i: &'a str,
    up: u8,
    col: u32,
    after: &'a str,
    items: &mut Vec<Item>,
) -> Result<&'a str, nom::Err<PErr<'a>>> {
    literal_only(i, up)?;
    let (rest, e) = unbracketed_expr(ctx, after)?;
    items.push(Item::Word(Word {
        letter: up,
        value: Value::Expr(e),
        col,
    }));
    Ok(rest)
}

/// An expression starting with a parameter or variable, written without brackets, at
/// `after`: it runs to the next blank or comment outside brackets.
fn unbracketed_expr<'a>(
    ctx: &Ctx<'a>,
    after: &'a str,
) -> Result<(&'a str, super::block::Expr), nom::Err<PErr<'a>>> {
    let mut depth = 0usize;
    let end = after
        .bytes()
        .position(|b| match b {
            b'[' => {
                depth += 1;
                false
            }
            b']' => {
                depth = depth.saturating_sub(1);
                false
            }
            b' ' | b'\t' | b'(' | b';' => depth == 0,
            _ => false,
        })
        .unwrap_or(after.len());
    let cut = ctx.cut(ctx.line.len() - after.len() + end);
    let text = &cut.line[cut.line.len() - end..];
    let e = match cut.unbracketed_value(text) {
        Ok(("", e)) => e,
        Ok((rest, _)) => {
            return Err(ctx.err_at(cut.col(rest), SYNTAX, "operator or blank expected"));
        }
        Err(e) => {
            let e = cut.to_error(e);
            return Err(ctx.err_at(e.col, e.code, e.message));
        }
    };
    Ok((&after[end..], e))
}

/// `X SIN [P1 * 5]`, `X-SQRT[P2]`, `A SQRT [2]/2`: a word whose value is an expression that
/// starts with a function, written after the address letter without the word's brackets
/// (TF5200 programming manual, "Axis commands": "X <int, double, expr>", with the examples
/// `Z SIN [30]` and `A SQRT [2]/2`). The expression runs as far as it goes, blanks between
/// its operators included. `at` is the text after the letter and its sign. Anything else
/// there is the word's 20200.
#[cold]
fn word_function<'a>(
    ctx: &Ctx<'a>,
    i: &'a str,
    up: u8,
    col: u32,
    (at, negate): (&'a str, bool),
    items: &mut Vec<Item>,
) -> Result<&'a str, nom::Err<PErr<'a>>> {
    let start = ws(at);
    let name_len = start
        .bytes()
        .take_while(|c| c.is_ascii_alphabetic())
        .count();
    let name = &start[..name_len];
    let is_function = name_len > 0
        && super::expr::FUNCS
            .iter()
            .any(|f| f.name().eq_ignore_ascii_case(name));
    if !is_function || !ws(&start[name_len..]).starts_with('[') {
        return Err(perr(&i[1..], SYNTAX, word_value_msg(up)));
    }
    literal_only(i, up)?;
    let (rest, e) = ctx.unbracketed_value(start)?;
    let e = if negate {
        super::block::Expr::Unary(super::block::UnOp::Neg, Box::new(e))
    } else {
        e
    };
    items.push(Item::Word(Word {
        letter: up,
        value: Value::Expr(e),
        col,
    }));
    Ok(rest)
}

/// `X[M54=P1]`, `S[REV 1000 M03 M63=-789]`: the technology functions of one axis or of the
/// spindle in brackets after its name (TF5200 programming manual, "Programming in
/// spindle-specific syntax": `<spindle_name> [ [M3|M4|M5|M19] [REV..] {M..} {H..} … ]`, and
/// "User-specific M/H function for spindles"; axis-specific M functions alike). The M and H
/// functions go to the technology units as the block's own (`M63=-789` with its value), `REV`
/// is the spindle speed, as an S word. `None` when the bracket holds an expression (`X[P1*2]`);
/// any other keyword in a function bracket (`POS`, `G74`, `CALLAX`, …) is refused by name.
#[cold]
fn function_bracket<'a>(
    ctx: &Ctx<'a>,
    up: u8,
    col: u32,
    bracket: &'a str,
    items: &mut Vec<Item>,
) -> Result<Option<&'a str>, nom::Err<PErr<'a>>> {
    let starts_function = |r: &str| {
        let b = r.as_bytes();
        matches!(b.first(), Some(b'M' | b'm' | b'H' | b'h'))
            && b.get(1).is_some_and(u8::is_ascii_digit)
    };
    let first = ws(&bracket[1..]);
    let is_spindle = up == b'S';
    if !(starts_function(first) || is_spindle && keyword_prefix(first, "REV").is_some()) {
        return Ok(None);
    }
    let mut r = first;
    let mut speed = None;
    let mut ms = FunctionNumbers::default();
    let mut inner = Vec::new();
    loop {
        r = ws(r);
        if let Some(rest) = r.strip_prefix(']') {
            if let Some(value) = speed {
                inner.push(Item::Word(Word {
                    letter: b'S',
                    value,
                    col,
                }));
            }
            items.push(Item::Functions(Box::new(Functions {
                owner: up,
                items: inner,
                col,
            })));
            return Ok(Some(rest));
        }
        if starts_function(r) {
            let at = r;
            let letter = r.as_bytes()[0].to_ascii_uppercase();
            let (rest, number) = super::expr::uint(&r[1..])?;
            if !is_known_m(number) {
                let code = if letter == b'M' { UNKNOWN_M } else { UNKNOWN_H };
                return Err(perr(
                    r,
                    code,
                    format!("{}{number} outside 0 to 65535", letter as char),
                ));
            }
            let fcol = ctx.col(r);
            if let Some(v) = ws(rest).strip_prefix('=') {
                let (rest, e) = ctx.expr(ws(v))?;
                inner.push(Item::FunctionValue {
                    letter,
                    number,
                    value: expr_value(e),
                    col: fcol,
                });
                r = rest;
            } else {
                inner.push(Item::Word(Word {
                    letter,
                    value: Value::Num(f64::from(number)),
                    col: fcol,
                }));
                r = rest;
            }
            if letter == b'M' {
                ms.add(inner.last(), at)?;
            }
            if inner.len() > FunctionNumbers::KEPT {
                return Err(perr(at, SYNTAX, "too many functions in one bracket"));
            }
            continue;
        }
        match keyword_prefix(r, "REV") {
            Some(rest) if is_spindle && speed.is_none() => {
                let (after, value) = spindle_speed(ctx, rest)?;
                speed = Some(value);
                r = after;
            }
            Some(_) if is_spindle => return Err(perr(r, S_TWICE, "REV programmed twice")),
            _ => {
                let what = if is_spindle {
                    "a spindle's"
                } else {
                    "an axis's"
                };
                return Err(perr(
                    r,
                    UNSUPPORTED,
                    format!(
                        "only M and H functions{} are modelled in {what} brackets",
                        if is_spindle { " and REV" } else { "" }
                    ),
                ));
            }
        }
    }
}

/// The value after `REV` (`rest`), `=` optional: a negative literal is the kernel's 20991
/// (TF5200 diagnosis ID 20991 "Negative spindle speed not permitted.", spindle-specific
/// programming `S[...]`).
fn spindle_speed<'a>(ctx: &Ctx<'a>, rest: &'a str) -> Result<(&'a str, Value), nom::Err<PErr<'a>>> {
    let rest = ws(rest);
    let rest = rest.strip_prefix('=').map_or(rest, ws);
    let (after, e) = ctx.expr(rest)?;
    let negative = match &e {
        Expr::Num(v) => *v < 0.0,
        Expr::Unary(super::block::UnOp::Neg, inner) => matches!(**inner, Expr::Num(_)),
        _ => false,
    };
    if negative {
        return Err(perr(
            rest,
            SPINDLE_SPEED_NEGATIVE,
            "negative spindle speed in S[...] is not permitted",
        ));
    }
    Ok((after, expr_value(e)))
}

/// `kw` (any case) at the start of `r`, a number or `=` allowed right after it (`REV1000`):
/// the rest.
fn keyword_prefix<'a>(r: &'a str, kw: &str) -> Option<&'a str> {
    let head = r.get(..kw.len())?;
    let rest = &r[kw.len()..];
    let next_is_name = rest
        .as_bytes()
        .first()
        .is_some_and(|c| c.is_ascii_alphabetic() || *c == b'_');
    (head.eq_ignore_ascii_case(kw) && !next_is_name).then_some(rest)
}

/// A word with a bracketed value `X[..]` (or `X-[..]`). G and M need literal numbers.
fn word_expr<'a>(
    ctx: &Ctx<'a>,
    i: &'a str,
    up: u8,
    col: u32,
    bracket: &'a str,
    negate: bool,
    items: &mut Vec<Item>,
) -> Result<&'a str, nom::Err<PErr<'a>>> {
    literal_only(i, up)?;
    if !negate && (up == b'S' || is_axis_letter(up)) {
        if let Some(r) = function_bracket(ctx, up, col, bracket, items)? {
            return Ok(r);
        }
    }
    let (rest, e) = ctx.bracketed(bracket)?;
    let e = if negate {
        super::block::Expr::Unary(super::block::UnOp::Neg, Box::new(e))
    } else {
        e
    };
    items.push(Item::Word(Word {
        letter: up,
        value: Value::Expr(e),
        col,
    }));
    Ok(rest)
}

/// A refused G function (`refused`, from [`dialect_g`]), unless the kernel answers it with
/// its own id first: G160 with a value is read for the decoder ([`axis_zero_offsets`]), G63
/// with `S0` is 20007 ([`tapping_at_speed_0`]). `i` is at the G, `rest` after its number;
/// the rest of the block when G160 was read.
#[cold]
fn refused_g_first<'a>(
    ctx: &Ctx<'a>,
    (i, rest): (&'a str, &'a str),
    (g, col): (u32, u32),
    items: &mut Vec<Item>,
    refused: nom::Err<PErr<'a>>,
) -> Result<&'a str, nom::Err<PErr<'a>>> {
    match g {
        160 => axis_zero_offsets(ctx, rest, col, items)?.ok_or(refused),
        63 => tapping_at_speed_0(i, rest, items).and(Err(refused)),
        _ => Err(refused),
    }
}

/// G63 (tapping), which ncchannel does not model, with a literal `S0` in its block: the
/// kernel's 20007 first (TF5200 diagnosis ID 20007 "Spindle speed is 0.", whose example is
/// `G63 Z10 F300 S0`), at the S. Any other G63 is refused by name after this.
#[cold]
fn tapping_at_speed_0<'a>(
    i: &'a str,
    rest: &'a str,
    items: &[Item],
) -> Result<(), nom::Err<PErr<'a>>> {
    let err = |at: &'a str| {
        perr(
            at,
            SPINDLE_SPEED_0,
            "spindle speed 0 with G63 (tapping): the spindle speed must not be 0",
        )
    };
    let before = items
        .iter()
        .any(|it| matches!(it, Item::Word(w) if w.letter == b'S' && w.value == Value::Num(0.0)));
    if before {
        return Err(err(i));
    }
    // A later `S0` of the block: an S after a blank, then a literal that reads as 0.
    let text = rest.split([';', '(']).next().unwrap_or("");
    for (k, _) in text.match_indices(['S', 's']) {
        let after_blank = k == 0 || matches!(text.as_bytes()[k - 1], b' ' | b'\t');
        let value = scan_unsigned(&text.as_bytes()[k + 1..]);
        if after_blank && value.is_some_and(|(v, _)| v == 0.0) {
            return Err(err(&rest[k..]));
        }
    }
    Ok(())
}

/// `G160=2` (`i` after the number): the axis-specific zero offsets, which take their axes in
/// the block (TF5200 diagnosis ID 20003, whose example is `G160=2 X1 Z1`). Read with its value
/// for the decoder: without an axis it is the kernel's warning 20003 and changes nothing, with
/// one it is refused by name. `None` for `G160` without a value (refused here).
#[cold]
fn axis_zero_offsets<'a>(
    ctx: &Ctx<'a>,
    i: &'a str,
    col: u32,
    items: &mut Vec<Item>,
) -> Result<Option<&'a str>, nom::Err<PErr<'a>>> {
    let Some(r) = ws(i).strip_prefix('=') else {
        return Ok(None);
    };
    let (r, e) = ctx.expr(ws(r))?;
    items.push(Item::GValue {
        g: 160,
        value: expr_value(e),
        col,
    });
    Ok(Some(r))
}

/// A G function outside the implemented fast path: one ISG lists and ncchannel accepts
/// without effect passes; one it refuses is [`UNSUPPORTED`] by name; any other is 20131.
fn dialect_g(i: &str, g: u32) -> Result<(), nom::Err<PErr<'_>>> {
    match g_support(g) {
        Some((Support::Implemented | Support::Inert, _)) => Ok(()),
        Some((Support::Refused, name)) => Err(perr(
            i,
            UNSUPPORTED,
            format!("G{g} ({name}) is not supported by ncchannel"),
        )),
        None => Err(perr(i, UNKNOWN_G, format!("unknown G function G{g}"))),
    }
}

fn word_value_msg(letter: u8) -> String {
    format!(
        "number or [expression] expected after {} ({})",
        letter as char,
        super::number::LITERAL_LIMIT
    )
}

/// A G or M number: a non-negative whole number.
fn integer_code(n: f64) -> Option<u32> {
    // In range, the cast truncates: a whole number is the one it gives back (without
    // `fract`, a call to `trunc` on every G, M and H word).
    let k = n as u32;
    (n >= 0.0 && n <= f64::from(u32::MAX) && f64::from(k) == n).then_some(k)
}

/// The value of `G133=<expr>` / `G134=<expr>`, also written `G134 50`; with `dwell_p` (G04)
/// also `P<seconds>`.
fn g_value<'a>(
    ctx: &Ctx<'a>,
    i: &'a str,
    dwell_p: bool,
) -> Result<Option<(&'a str, Value)>, nom::Err<PErr<'a>>> {
    let j = ws(i);
    if let Some(r) = j.strip_prefix('=') {
        let (r, e) = ctx.expr(ws(r))?;
        return Ok(Some((r, expr_value(e))));
    }
    if dwell_p && starts_variable(j.as_bytes()) {
        // `G04 P1`, `G04 V.L.TIME`: the time is the parameter's or variable's value (TF5200
        // programming manual, "Dwell time (G04), (#TIME)").
        let (r, e) = unbracketed_expr(ctx, j)?;
        return Ok(Some((r, expr_value(e))));
    }
    let jb = j.as_bytes();
    let (neg, k) = match jb.first() {
        Some(b'-') => (true, 1),
        Some(b'+') => (false, 1),
        _ => (false, 0),
    };
    if j.len() == i.len() && k == 0 {
        // No blank before a bare number: `G13450` was already read as one number.
        return Ok(None);
    }
    match scan_unsigned(&jb[k..]) {
        Some((v, _)) if !v.is_finite() => Err(perr(&j[k..], SYNTAX, TOO_LARGE)),
        Some((v, n)) => Ok(Some((&j[k + n..], Value::Num(if neg { -v } else { v })))),
        None => Ok(None),
    }
}

fn expr_value(e: super::block::Expr) -> Value {
    match e {
        super::block::Expr::Num(v) => Value::Num(v),
        e => Value::Expr(e),
    }
}

// ---------------------------------------------------------------------------------------
// $ statements
// ---------------------------------------------------------------------------------------

/// The letters of a keyword after `$` or `#`, upper-cased into `buf`.
fn keyword_after<'a>(i: &'a str, buf: &mut [u8; 16]) -> Option<(&'a str, usize)> {
    let r: PResult<'a, &'a str> = take_while1(|c: char| c.is_ascii_alphabetic())(i);
    let (rest, kw) = r.ok()?;
    if kw.len() > buf.len() {
        return Some((rest, 0));
    }
    for (d, s) in buf.iter_mut().zip(kw.bytes()) {
        *d = s.to_ascii_uppercase();
    }
    Some((rest, kw.len()))
}

/// The condition of `$CASE`, `$ENDDO` or `$UNTIL` and nothing after it: another word in its
/// block is the kernel's "After 'CASE' (… 'ENDDO', 'UNTIL') only the condition is
/// permissible." (TF5200 diagnosis IDs 20222, 20241, 21470), at that word.
fn only_condition<'a>(ctx: &Ctx<'a>, i: &'a str, keyword: &'static str) -> PResult<'a, Expr> {
    use super::codes::{CASE_NOT_ALONE, ENDDO_NOT_ALONE, UNTIL_NOT_ALONE};
    let (r, e) = ctx.expr(i)?;
    let rest = gap(r);
    if rest.is_empty() {
        return Ok((r, e));
    }
    let code = match keyword {
        "$CASE" => CASE_NOT_ALONE,
        "$ENDDO" => ENDDO_NOT_ALONE,
        _ => UNTIL_NOT_ALONE,
    };
    fail(
        rest,
        code,
        format!("only the condition may follow {keyword} in its block"),
    )
}

fn control<'a>(ctx: &Ctx<'a>, i: &'a str) -> PResult<'a, Control> {
    let after = &i[1..];
    let mut buf = [0u8; 16];
    let Some((rest, len)) = keyword_after(after, &mut buf) else {
        return fail(i, SYNTAX, "control statement expected after $");
    };
    let r = ws(rest);
    let c = match &buf[..len] {
        b"IF" => {
            let (r, cond) = ctx.expr(r)?;
            let j = ws(r);
            if let Some(g) = j.strip_prefix('$') {
                let Some(g) = keyword(g, "GOTO") else {
                    return fail(j, SYNTAX, "only $GOTO may follow the condition of $IF");
                };
                let (r, target) = goto_target(ws(g))?;
                return Ok((r, Control::IfGoto(cond, target)));
            }
            return Ok((r, Control::If(cond)));
        }
        b"ELSEIF" if gap(r).is_empty() => {
            // An incomplete `$ELSEIF` (TF5200 diagnosis ID 20216: "A control block statement
            // was programmed in incomplete syntax", whose wrong program is `$ELSEIF` alone).
            return fail(
                i,
                super::codes::UNEXPECTED_ELSEIF,
                "$ELSEIF without its condition",
            );
        }
        b"ELSEIF" => return ctx.expr(r).map(|(r, e)| (r, Control::ElseIf(e))),
        b"SWITCH" => return ctx.expr(r).map(|(r, e)| (r, Control::Switch(e))),
        b"CASE" => return only_condition(ctx, r, "$CASE").map(|(r, e)| (r, Control::Case(e))),
        b"WHILE" => return ctx.expr(r).map(|(r, e)| (r, Control::While(e))),
        b"ENDDO" => return only_condition(ctx, r, "$ENDDO").map(|(r, e)| (r, Control::EndDo(e))),
        b"UNTIL" => return only_condition(ctx, r, "$UNTIL").map(|(r, e)| (r, Control::Until(e))),
        b"GOTO" => return goto_target(r).map(|(r, t)| (r, Control::Goto(t))),
        b"FOR" => return for_head(ctx, r),
        b"ELSE" => Control::Else,
        b"ENDIF" => Control::EndIf,
        b"DEFAULT" => Control::Default,
        b"BREAK" => Control::Break,
        b"ENDSWITCH" => Control::EndSwitch,
        b"ENDFOR" => Control::EndFor,
        b"ENDWHILE" => Control::EndWhile,
        b"DO" => Control::Do,
        b"REPEAT" => Control::Repeat,
        b"CONTINUE" => Control::Continue,
        _ => {
            return fail(
                i,
                UNKNOWN_COMMAND,
                format!(
                    "unknown control statement ${}",
                    &after[..after.len() - rest.len()]
                ),
            )
        }
    };
    Ok((rest, c))
}

/// A variable a program may assign: not a `V.A.` axis variable, which the kernel only lets
/// programs read (TF5200 programming manual, "Axis-specific variables (V.A.)").
fn writable<'a>(v: &VarRef, at: &'a str) -> Result<(), nom::Err<PErr<'a>>> {
    if matches!(v, VarRef::AxisAbs(_) | VarRef::ToolRadius(_)) {
        return Err(perr(at, SYNTAX, "V.A. and V.G. variables are read-only"));
    }
    Ok(())
}

/// `$FOR P1 = start, end[, step]`.
fn for_head<'a>(ctx: &Ctx<'a>, i: &'a str) -> PResult<'a, Control> {
    let (r, var) = ctx.var_ref(i)?;
    writable(&var, i)?;
    let r = ws(r);
    let Some(r) = r.strip_prefix('=') else {
        return fail(r, SYNTAX, "`=` expected after the $FOR variable");
    };
    let (r, start) = ctx.expr(ws(r))?;
    let r = ws(r);
    let Some(r) = r.strip_prefix(',') else {
        return fail(r, SYNTAX, "`,` and end value expected in $FOR");
    };
    let (r, end) = ctx.expr(ws(r))?;
    let j = ws(r);
    let (r, step) = match j.strip_prefix(',') {
        Some(s) => {
            let (r, e) = ctx.expr(ws(s))?;
            (r, Some(e))
        }
        None => (r, None),
    };
    Ok((
        r,
        Control::For {
            var: Box::new(var),
            start: Box::new(start),
            end: Box::new(end),
            step: step.map(Box::new),
        },
    ))
}

/// `N40` or `[LABEL]`.
fn goto_target(i: &str) -> PResult<'_, GotoTarget> {
    match i.as_bytes().first() {
        Some(b'N' | b'n') if i.as_bytes().get(1).is_some_and(u8::is_ascii_digit) => {
            let (r, n) = uint(&i[1..])?;
            Ok((r, GotoTarget::Number(n)))
        }
        Some(b'[') => bracket_name(i).map(|(r, s)| (r, GotoTarget::Name(s))),
        _ => fail(i, SYNTAX, "jump target N<number> or [LABEL] expected"),
    }
}

// ---------------------------------------------------------------------------------------
// # commands
// ---------------------------------------------------------------------------------------

fn command<'a>(ctx: &Ctx<'a>, i: &'a str) -> PResult<'a, Command> {
    let after = &i[1..];
    let mut buf = [0u8; 16];
    let Some((rest, len)) = keyword_after(after, &mut buf) else {
        return fail(i, UNKNOWN_COMMAND, "NC command expected after #");
    };
    let r = ws(rest);
    match &buf[..len] {
        b"FLUSH" => {
            if let Some(r) = keyword(r, "CONTINUE") {
                Ok((r, Command::Flush(FlushKind::Continue)))
            } else if let Some(r) = keyword(r, "WAIT") {
                Ok((r, Command::Flush(FlushKind::Wait)))
            } else if gap(r).is_empty() {
                Ok((r, Command::Flush(FlushKind::Stop)))
            } else {
                fail(r, SYNTAX, "#FLUSH takes CONTINUE or WAIT")
            }
        }
        b"CACHE" => cache(r),
        b"EXPL" => match keyword(r, "SYN") {
            Some(r) if gap(r).is_empty() => Ok((r, Command::ExplicitSync)),
            _ => fail(r, UNSUPPORTED, "#EXPL: ncchannel has #EXPL SYN only"),
        },
        b"COMMENT" => {
            if let Some(r) = keyword(r, "BEGIN") {
                Ok((r, Command::CommentBegin))
            } else if let Some(r) = keyword(r, "END") {
                Ok((r, Command::CommentEnd))
            } else {
                fail(r, SYNTAX, "#COMMENT takes BEGIN or END")
            }
        }
        b"SPLINE" => {
            if let Some(r) = keyword(r, "ON") {
                Ok((r, Command::Spline(SplineCommand::On)))
            } else if let Some(r) = keyword(r, "OFF") {
                Ok((r, Command::Spline(SplineCommand::Off)))
            } else if let Some(t) = keyword(r, "TYPE") {
                let t = ws(t);
                if let Some(r) = keyword(t, "AKIMA") {
                    Ok((r, Command::Spline(SplineCommand::TypeAkima)))
                } else if let Some(r) = keyword(t, "BSPLINE") {
                    Ok((r, Command::Spline(SplineCommand::TypeBspline)))
                } else {
                    fail(t, SYNTAX, "#SPLINE TYPE takes AKIMA or BSPLINE")
                }
            } else {
                fail(r, SYNTAX, "#SPLINE takes ON, OFF or TYPE")
            }
        }
        b"HSC" => {
            let (r, on) = if let Some(r) = keyword(r, "ON") {
                (r, true)
            } else if let Some(r) = keyword(r, "OFF") {
                (r, false)
            } else if r.starts_with('[') {
                return hsc_parameters(i, r);
            } else {
                return fail(r, SYNTAX, "#HSC takes ON, OFF or [parameters]");
            };
            let (r, options) = verbatim_options(ws(r), r)?;
            Ok((r, Command::Hsc { on, options }))
        }
        b"CONTOUR" => {
            let Some(m) = keyword(r, "MODE") else {
                return fail(r, SYNTAX, "#CONTOUR takes MODE");
            };
            for (kw, on) in [("ON", true), ("OFF", false)] {
                if let Some(r) = keyword(ws(m), kw) {
                    let (r, options) = verbatim_options(ws(r), r)?;
                    return Ok((r, Command::ContourSwitch { on, options }));
                }
            }
            let (r, options) = verbatim_options(ws(m), m)?;
            Ok((r, Command::ContourMode { options }))
        }
        b"FILENAME" => file_names(ctx, i, r),
        b"FILE" if keyword(r, "NAME").is_some() => file_names(ctx, i, ws(&r[4..])),
        b"VAR" => Ok((rest, Command::Var)),
        b"ENDVAR" => Ok((rest, Command::EndVar)),
        b"MSG" => super::msg::parse_msg(ctx, r),
        b"TIME" => {
            let (r, v) = ctx.expr(r)?;
            Ok((r, Command::Time(expr_value(v))))
        }
        kw @ (b"TRAFO" | b"KIN" | b"CS") => match super::transform::neutral(ctx, i, kw, r) {
            Some(parsed) => parsed,
            None => dialect_command(i, kw, &after[..after.len() - rest.len()]),
        },
        kw => dialect_command(i, kw, &after[..after.len() - rest.len()]),
    }
}

/// A `#` command of ISG's list that the parser has no rule for: accepted verbatim when
/// ncchannel treats it as a no-op, refused by name when it does not support it, 20209 when
/// ISG's list does not have it either.
fn dialect_command<'a>(i: &'a str, kw: &[u8], word: &str) -> PResult<'a, Command> {
    let rest = &i[1 + word.len()..];
    match command_support(kw).map(|s| super::dialect::form_support(s, kw, rest)) {
        Some(Support::Inert) => {
            // The whole command to the comment: options in brackets may hold anything.
            let text = i[1..].split([';', '(']).next().unwrap_or("").trim_end();
            Ok((
                &i[1 + text.len()..],
                Command::Inert {
                    text: text.to_string(),
                },
            ))
        }
        Some(_) => fail(
            i,
            UNSUPPORTED,
            format!("#{word} is an ISG command ncchannel does not support"),
        ),
        None => fail(i, UNKNOWN_COMMAND, format!("unknown NC command #{word}")),
    }
}

/// The command from its `#` (`i`) up to `rest` as an inert command, verbatim.
fn inert_to<'a>(i: &'a str, rest: &'a str) -> PResult<'a, Command> {
    let text = i[1..i.len() - rest.len()].trim_end().to_string();
    Ok((rest, Command::Inert { text }))
}

/// `#HSC [BSPLINE PATH_DEV 0.2 …]` / `#HSC [OPMODE 1 CONTERROR 0.01]` (TF5200 programming
/// manual, "Trim a contour (#HSC ON/OFF)": ON and OFF are optional): parameters of the HSC
/// smoothing without switching it, which ncchannel does not model: inert.
#[cold]
fn hsc_parameters<'a>(i: &'a str, r: &'a str) -> PResult<'a, Command> {
    let (rest, _) = verbatim_options(r, r)?;
    inert_to(i, rest)
}

/// `#FILENAME [MSG="prog_flow.txt"]` and `#FILE NAME [...]` (TF5200 programming manual,
/// German edition, "Definition von Dateinamen (#FILE NAME)"; the older TwinCAT CNC
/// programming manual's "Definition of file names" writes `#FILENAME`): `MSG` names the file `#MSG SAVE` writes to, and
/// ncchannel writes none, so it is inert. The other file ids (`M6`, `D`, `G80`–`G89`,
/// `G800`–`G839`) rename implicit subroutines, which is refused by name (900133). A file
/// name held by a string variable, `MSG=V.E.TEACH_FILE_NAME`, is read when the block runs
/// ([`Command::MsgFileName`]).
#[cold]
fn file_names<'a>(ctx: &Ctx<'a>, i: &'a str, r: &'a str) -> PResult<'a, Command> {
    let Some(mut j) = r.strip_prefix('[') else {
        return fail(r, SYNTAX, "#FILENAME takes [<id>=\"<file name>\" …]");
    };
    let mut var = None;
    loop {
        j = ws(j);
        if let Some(rest) = j.strip_prefix(']') {
            return match var {
                Some(v) => Ok((rest, Command::MsgFileName(Box::new(v)))),
                None => inert_to(i, rest),
            };
        }
        let (k, id) = name_or(j, "file id (MSG, M6, D, G80…) or `]` expected")?;
        if id != "MSG" {
            let known = matches!(id.as_str(), "M6" | "D")
                || id
                    .strip_prefix('G')
                    .and_then(|n| n.parse::<u32>().ok())
                    .is_some_and(|g| (80..=89).contains(&g) || (800..=839).contains(&g));
            if known {
                return fail(
                    j,
                    UNSUPPORTED,
                    format!("#FILENAME {id}=… renames an implicit subroutine, which ncchannel does not support"),
                );
            }
            return fail(j, SYNTAX, format!("unknown file id {id} in #FILENAME"));
        }
        let k = ws(k);
        let k = ws(k.strip_prefix('=').unwrap_or(k));
        if matches!(k.as_bytes(), [b'V' | b'v', b'.', ..]) {
            let (rest, v) = ctx.var_ref(k)?;
            var = Some(v);
            j = rest;
            continue;
        }
        let Some(body) = k.strip_prefix('"') else {
            return fail(k, SYNTAX, "quoted file name expected in #FILENAME");
        };
        let Some(end) = body.find('"') else {
            return fail(k, SYNTAX, "closing `\"` missing in #FILENAME");
        };
        j = &body[end + 1..];
    }
}

/// `#CACHE LOAD [FILE=name]`, `#CACHE CLEAR [FILE=name]`, `#CACHE CLEAR ALL` (TF5200 File Caching;
/// its examples write no blank before the bracket). Bad form 21560, a second target 21561.
fn cache(i: &str) -> PResult<'_, Command> {
    let (r, load) = if let Some(r) = keyword(i, "LOAD") {
        (r, true)
    } else if let Some(r) = keyword(i, "CLEAR") {
        (r, false)
    } else {
        return fail(i, CACHE_SYNTAX, "#CACHE takes LOAD or CLEAR");
    };
    let r = ws(r);
    if !load {
        if let Some(a) = keyword(r, "ALL") {
            let j = gap(a);
            if j.starts_with('[') {
                return fail(j, CACHE_DOUBLE, "#CACHE CLEAR ALL takes no FILE");
            }
            if !j.is_empty() {
                return fail(j, CACHE_SYNTAX, "unexpected text after #CACHE CLEAR ALL");
            }
            return Ok((a, Command::CacheClearAll));
        }
    }
    let Some(mut j) = r.strip_prefix('[') else {
        return fail(r, CACHE_SYNTAX, "[FILE=<name>] expected");
    };
    let mut file: Option<String> = None;
    loop {
        j = ws(j);
        if let Some(rest) = j.strip_prefix(']') {
            let Some(file) = file else {
                return fail(j, CACHE_SYNTAX, "FILE=<name> missing");
            };
            let k = gap(rest);
            if k.starts_with('[') {
                return fail(k, CACHE_DOUBLE, "#CACHE programmed twice in one block");
            }
            if !k.is_empty() {
                return fail(k, CACHE_SYNTAX, "unexpected text after #CACHE");
            }
            let cmd = if load {
                Command::CacheLoad { file }
            } else {
                Command::CacheClear { file }
            };
            return Ok((rest, cmd));
        }
        let Some(f) = keyword(j, "FILE") else {
            return fail(j, CACHE_SYNTAX, "FILE=<name> expected");
        };
        let f = ws(f);
        let Some(f) = f.strip_prefix('=') else {
            return fail(f, CACHE_SYNTAX, "`=` expected after FILE");
        };
        let (rest, name) = file_name(ws(f), true);
        if name.is_empty() {
            return fail(f, CACHE_SYNTAX, "file name expected after FILE=");
        }
        if file.is_some() {
            return fail(j, CACHE_DOUBLE, "FILE programmed twice in #CACHE");
        }
        file = Some(name.to_string());
        j = rest;
    }
}

/// A file name: `"quoted"` or a run of characters up to a blank, comment start or, inside
/// brackets, `]`. An opening quote without its closing one gives no name (the caller's
/// "name expected" error at the quote): a name never starts with `"`, so the canonical text
/// of every name parses back to the same name.
fn file_name(i: &str, in_bracket: bool) -> (&str, &str) {
    if let Some(q) = i.strip_prefix('"') {
        return match q.find('"') {
            Some(end) => (&q[end + 1..], &q[..end]),
            None => (i, ""),
        };
    }
    let end = i
        .find(|c: char| c == ' ' || c == '\t' || c == '(' || c == ';' || (in_bracket && c == ']'))
        .unwrap_or(i.len());
    (&i[end..], &i[..end])
}

// ---------------------------------------------------------------------------------------
// Calls and program heads
// ---------------------------------------------------------------------------------------

fn call<'a>(ctx: &Ctx<'a>, i: &'a str) -> PResult<'a, Call> {
    let local = matches!(i.as_bytes().get(1), Some(b'L' | b'l'));
    let r = ws(&i[if local { 2 } else { 1 }..]);
    if local {
        if let Some(c) = keyword(r, "CYCLE").map(ws).filter(|c| c.starts_with('[')) {
            return cycle(ctx, c, true);
        }
        let (rest, name) = file_name(r, false);
        if name.is_empty() {
            return fail(r, SYNTAX, "subroutine name expected after LL");
        }
        return Ok((
            rest,
            Call::Local {
                name: name.to_ascii_uppercase(),
            },
        ));
    }
    if let Some(c) = keyword(r, "CYCLE") {
        let c = ws(c);
        if c.starts_with('[') {
            return cycle(ctx, c, false);
        }
        return fail(
            c,
            SYNTAX,
            "[NAME=<file> @P<n>=<value> …] expected after L CYCLE",
        );
    }
    let (rest, file) = file_name(r, false);
    if file.is_empty() {
        return fail(r, SYNTAX, "subroutine file name expected after L");
    }
    Ok((
        rest,
        Call::Global {
            file: file.to_string(),
        },
    ))
}

/// `[NAME=file.cyc @P1=0 @P2=[P5*2] @P3="text"]`: blanks or commas between the entries
/// (TF5200 programming manual, "Cycles as global or local subroutines (Call L | LL CYCLE)";
/// `local` for `LL CYCLE`). A modal call (`MODAL`, `MODAL_MOVE`, `MODAL_BLOCK`) is refused
/// by name: ncchannel does not repeat a cycle after later blocks.
fn cycle<'a>(ctx: &Ctx<'a>, i: &'a str, local: bool) -> PResult<'a, Call> {
    let open = i;
    let mut j = &i[1..];
    let mut name: Option<String> = None;
    let mut params: Vec<(u32, CycleArg)> = Vec::new();
    loop {
        j = j.trim_start_matches([' ', '\t', ',']);
        if let Some(rest) = j.strip_prefix(']') {
            let Some(name) = name else {
                return fail(open, SYNTAX, "NAME=<file> missing in L CYCLE");
            };
            return Ok((
                rest,
                Call::Cycle {
                    name,
                    local,
                    params,
                },
            ));
        }
        if let Some(n) = keyword(j, "NAME") {
            let n = ws(n);
            let Some(n) = n.strip_prefix('=') else {
                return fail(n, SYNTAX, "`=` expected after NAME");
            };
            let (rest, file) = file_name(ws(n), true);
            if file.is_empty() {
                return fail(n, SYNTAX, "cycle file name expected after NAME=");
            }
            if name.is_some() {
                return fail(j, SYNTAX, "NAME programmed twice in L CYCLE");
            }
            name = Some(file.to_string());
            j = rest;
        } else if j.starts_with('@') {
            let (r, v) = ctx.var_ref(j)?;
            let VarRef::CycleParam(p) = v else {
                return fail(j, SYNTAX, "@P<number> expected");
            };
            if params.iter().any(|(q, _)| *q == p) {
                return fail(j, SYNTAX, format!("@P{p} programmed twice in L CYCLE"));
            }
            let r = ws(r);
            let Some(r) = r.strip_prefix('=') else {
                return fail(r, SYNTAX, "`=` expected after the cycle parameter");
            };
            let r = ws(r);
            let (r, a) = if r.starts_with('"') {
                cycle_string(r)?
            } else {
                let (r, e) = ctx.expr(r)?;
                (r, CycleArg::Expr(e))
            };
            params.push((p, a));
            j = r;
        } else if ["MODAL_MOVE", "MODAL_BLOCK", "MODAL"]
            .into_iter()
            .any(|kw| keyword(j, kw).is_some())
        {
            return fail(
                j,
                UNSUPPORTED,
                "a modal cycle call (MODAL, MODAL_MOVE, MODAL_BLOCK) is not supported by ncchannel",
            );
        } else if j.is_empty() {
            return fail(j, SYNTAX, "`]` missing after L CYCLE [");
        } else {
            return fail(j, SYNTAX, "NAME=<file> or @P<n>=<value> expected");
        }
    }
}

/// `"text"` as a cycle parameter's value: everything up to the next `"` (a block holds no
/// line break, so the text is bounded by the block).
#[cold]
fn cycle_string(i: &str) -> PResult<'_, CycleArg> {
    let body = &i[1..];
    let Some(end) = body.find('"') else {
        return fail(
            i,
            SYNTAX,
            "closing `\"` missing in the cycle parameter's string",
        );
    };
    Ok((&body[end + 1..], CycleArg::Str(body[..end].to_string())))
}

/// `%name`, `% name` or `%L name` (TF5200 programming manual, "NC block structure": `% 100`).
fn program_head(i: &str) -> PResult<'_, (String, bool)> {
    let after = ws(&i[1..]);
    let ab = after.as_bytes();
    if matches!(ab.first(), Some(b'L' | b'l')) && matches!(ab.get(1), Some(b' ' | b'\t')) {
        let r = ws(&after[1..]);
        let (rest, name) = file_name(r, false);
        if name.is_empty() {
            return fail(r, SYNTAX, "subroutine name expected after %L");
        }
        return Ok((rest, (name.to_ascii_uppercase(), true)));
    }
    let (rest, name) = file_name(after, false);
    Ok((rest, (name.to_string(), false)))
}

/// The text after a program head's name up to a comment, trimmed: the program's title
/// (`% TestProgram for streaming mode`, `%Test - Achsen`). Kept, never interpreted.
fn program_title(i: &str) -> (&str, String) {
    let t = ws(i);
    let end = t.find([';', '(']).unwrap_or(t.len());
    (&t[end..], t[..end].trim_end().to_string())
}

// ---------------------------------------------------------------------------------------
// #VAR declarations
// ---------------------------------------------------------------------------------------

fn var_decl<'a>(ctx: &Ctx<'a>, line: &'a str) -> Result<VarDecl, nom::Err<PErr<'a>>> {
    // A line of a #VAR block may carry a block number (`N50 V.S.EXAMPLE[5] = [1,2,3,4,5]`).
    let (i, _) = prefix(ws(line))?;
    let i = gap(i);
    let b = i.as_bytes();
    if !(matches!(b.first(), Some(b'V' | b'v')) && b.get(1) == Some(&b'.')) {
        return Err(perr(
            i,
            SYNTAX,
            "variable declaration V.P., V.L. or V.S. expected",
        ));
    }
    let (r, v) = ctx.var_ref(i)?;
    let VarRef::V {
        scope,
        name,
        indices,
    } = v
    else {
        return Err(perr(i, SYNTAX, "variable declaration expected"));
    };
    if scope == VScope::External {
        return Err(perr(
            i,
            SYNTAX,
            "V.E. variables are not declared in programs",
        ));
    }
    if indices.len() > MAX_ARRAY_DIMS {
        return Err(perr(
            i,
            TOO_MANY_INDICES,
            format!(
                "{} indices declared: an array has at most {MAX_ARRAY_DIMS}",
                indices.len()
            ),
        ));
    }
    let mut dims = Vec::with_capacity(indices.len());
    let mut elements: u64 = 1;
    for e in indices {
        match e {
            super::block::Expr::Num(n) if n >= 1.0 && n.fract() == 0.0 => {
                // Saturating: three sizes of up to 2^32 cannot wrap a u64 product anyway,
                // and anything above the limit is refused below.
                let n = n.min(f64::from(u32::MAX)) as u32;
                elements = elements.saturating_mul(u64::from(n));
                dims.push(n)
            }
            _ => {
                return Err(perr(
                    i,
                    SYNTAX,
                    "array size must be a whole number from 1 (a literal)",
                ))
            }
        }
    }
    if elements > MAX_ARRAY_ELEMENTS {
        return Err(perr(
            i,
            VARIABLE_MEMORY_FULL,
            format!(
                "array V.{}.{name} of {elements} elements: a variable holds at most {MAX_ARRAY_ELEMENTS}",
                scope.letter()
            ),
        ));
    }
    let (r, ty) = var_type(ws(r), r)?;
    let j = ws(r);
    let mut text = None;
    let (r, init, values) = match j.strip_prefix('=') {
        Some(k) if matches!(ty, Some(VarType::String(_))) => {
            let (r, t) = string_init(ws(k), ty)?;
            text = Some(t.to_string());
            (r, None, Vec::new())
        }
        Some(k) if !dims.is_empty() && is_list(ws(k)) => {
            let (r, values) = init_list(ctx, ws(k), elements)?;
            (r, None, values)
        }
        Some(k) => {
            let (r, e) = ctx.expr(ws(k))?;
            (r, Some(e), Vec::new())
        }
        None => (r, None, Vec::new()),
    };
    end_of_block(r, "nothing may follow a declaration")?;
    Ok(VarDecl {
        scope,
        name,
        dims,
        ty,
        init,
        text,
        values,
    })
}

/// `: <type>` after a declared name (`: UNS32`, `: STRING[20]`), if there is one; `none` is
/// the input to go on from when there is not.
fn var_type<'a>(i: &'a str, none: &'a str) -> PResult<'a, Option<VarType>> {
    let Some(t) = i.strip_prefix(':') else {
        return Ok((none, None));
    };
    let t = ws(t);
    let len = t
        .bytes()
        .take_while(u8::is_ascii_alphanumeric)
        .count()
        .min(16);
    let upper = t[..len].to_ascii_uppercase();
    let ty = match upper.as_str() {
        "STRING" => {
            let s = &t[len..];
            let size = s.strip_prefix('[').and_then(|n| {
                let (rest, n) = uint(n).ok()?;
                let rest = rest.strip_prefix(']')?;
                (1..=126).contains(&n).then_some((rest, n as u8))
            });
            return match size {
                Some((rest, n)) => Ok((rest, Some(VarType::String(n)))),
                None => fail(s, SYNTAX, "STRING[<length 1 to 126>] expected"),
            };
        }
        name => match VarType::numeric(name) {
            Some(ty) => ty,
            None => {
                return fail(
                    t,
                    SYNTAX,
                    "data type BOOLEAN, SGN08, UNS08, SGN16, UNS16, SGN32, UNS32, REAL64 or STRING[n] expected",
                )
            }
        },
    };
    Ok((&t[len..], Some(ty)))
}

/// The quoted start value of a `STRING[n]` variable, at most n characters (longer: the
/// kernel's 21462 at the quote); the rest of the line and the text without its quotes.
fn string_init(i: &str, ty: Option<VarType>) -> Result<(&str, &str), nom::Err<PErr<'_>>> {
    let Some(q) = i.strip_prefix('"') else {
        return Err(perr(
            i,
            SYNTAX,
            "a STRING variable starts with a \"quoted\" text",
        ));
    };
    let Some(end) = q.find('"') else {
        return Err(perr(i, SYNTAX, "closing `\"` missing"));
    };
    let max = match ty {
        Some(VarType::String(n)) => usize::from(n),
        _ => 0,
    };
    let len = q[..end].chars().count();
    if len > max {
        return Err(perr(
            i,
            STRING_TOO_LONG_FOR_VARIABLE,
            format!("text of {len} characters longer than the STRING[{max}] declared"),
        ));
    }
    Ok((&q[end + 1..], &q[..end]))
}

/// Does `[` open a list (`[10, 11, 12]`: a comma outside inner brackets) rather than a
/// bracketed expression (`[P1*2]`, the value of every element)?
fn is_list(i: &str) -> bool {
    if !i.starts_with('[') {
        return false;
    }
    let mut depth = 0usize;
    for b in i.bytes() {
        match b {
            b'[' => depth += 1,
            b']' => {
                depth -= 1;
                if depth == 0 {
                    return false;
                }
            }
            b',' if depth == 1 => return true,
            _ => {}
        }
    }
    false
}

/// `[e1, e2, …]`: an array's first `elements` values at most.
fn init_list<'a>(ctx: &Ctx<'a>, i: &'a str, elements: u64) -> PResult<'a, Vec<Expr>> {
    let open = i;
    let mut values = Vec::new();
    let mut j = &i[1..];
    loop {
        j = ws(j);
        let (r, e) = ctx.expr(j)?;
        if values.len() as u64 == elements {
            return fail(
                j,
                SYNTAX,
                format!("more values than the {elements} elements declared"),
            );
        }
        values.push(e);
        let r = ws(r);
        if let Some(r) = r.strip_prefix(',') {
            j = r;
        } else if let Some(r) = r.strip_prefix(']') {
            return Ok((r, values));
        } else if r.is_empty() {
            return fail(open, SYNTAX, "`]` missing after the values");
        } else {
            return fail(r, SYNTAX, "`,` or `]` expected");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{block_number_only, gap, item_capacity, prefix};
    use proptest::prelude::*;

    /// The one-step block number reads as [`prefix`] does, and leaves the rest (labels,
    /// block skips, long numbers, errors) to it.
    #[test]
    fn block_number_only_reads_as_the_prefix() {
        let mut taken = Vec::new();
        for line in [
            "N10 G01 X1",
            "n10\tX1",
            "N10",
            "N10 ",
            "N10:",
            "N10: X1",
            "N10 [LOOP]",
            "N10 (c) X1",
            "N10(c) X1",
            "N1234567 X1",
            "N12345678 X1",
            "N99999999999 X1",
            "N X1",
            "N-1 X1",
            "/N10 X1",
            "/2 N10 X1",
            "N10 ;c",
            "N0 M30",
            "N10 é",
            "X1",
            "",
        ] {
            if let Some((rest, n)) = block_number_only(line) {
                taken.push(line);
                let (i, (skip, pn, label)) = prefix(line).unwrap();
                assert_eq!((skip, pn, label), (None, Some(n), None), "{line}");
                assert_eq!(gap(i), rest, "{line}");
            }
        }
        assert_eq!(
            taken,
            [
                "N10 G01 X1",
                "n10\tX1",
                "N10 ",
                "N10 (c) X1",
                "N1234567 X1",
                "N10 ;c",
                "N0 M30",
                "N10 é"
            ]
        );
    }

    /// The definition, a byte at a time: bytes with bit 0x40 before the first `(` or `;`.
    fn item_capacity_bytewise(i: &str) -> usize {
        i.bytes()
            .take_while(|&b| b != b'(' && b != b';')
            .filter(|b| b & 0x40 != 0)
            .count()
            .min(32)
    }

    /// Every letter and `@` is counted, so the list is sized once for every item.
    #[test]
    fn item_capacity_bounds_the_items() {
        for line in [
            "G01 X1 Y2 Z3 F100",
            "X1Y2Z3A4B5C6",
            "@P1=2 x1",
            "M3 S1000 ( X Y Z ) X1",
        ] {
            let letters = line
                .bytes()
                .take_while(|&b| b != b'(')
                .filter(|b| b.is_ascii_alphabetic() || *b == b'@')
                .count();
            assert!(item_capacity(line) >= letters, "{line}");
        }
    }

    proptest! {
        #[test]
        fn item_capacity_counts_as_the_definition(
            line in "[A-Za-z0-9@ .=(;\\-\\[\\]`{é€\\x7f\\x01]{0,80}"
        ) {
            prop_assert_eq!(item_capacity(&line), item_capacity_bytewise(&line));
        }
    }
}
