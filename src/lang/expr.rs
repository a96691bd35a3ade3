//! Expressions and variable references: `[P1*2+3]`, `SIN[30]`, `P[P1+5]`, `V.L.X[2]`, `@P1`.
//!
//! Precedence, lowest first (all binary operators left-associative except `**`):
//!
//! | level | operators |
//! |---|---|
//! | 1 | `\|\|` (also `OR`) |
//! | 2 | `XOR` (logical) |
//! | 3 | `&&` (also `AND`) |
//! | 4 | `\|` bitwise or |
//! | 5 | `^` bitwise xor |
//! | 6 | `&` bitwise and |
//! | 7 | `== != <> < > <= >=` |
//! | 8 | `+ -` |
//! | 9 | `* / MOD` |
//! | 10 | unary `- + NOT INV` |
//! | 11 | `**` (right-associative: `2**3**2` = `2**9`; `-2**2` = `-4`) |
//!
//! A `-` written directly before a literal folds into it (`-6.789` is one number) unless a
//! `**` follows. Grouping `[ ]` leaves no node. Keywords are case-insensitive and must not be
//! followed by a letter, digit or `_`.

use std::borrow::Cow;
use std::cell::Cell;

use nom::bytes::complete::{tag, tag_no_case, take_while, take_while1};
use nom::character::complete::char as ch;
use nom::error::{ErrorKind, ParseError};
use nom::IResult;

use super::block::{
    AxisSel, BinOp, Expr, Func, Index, StrFunc, ToolField, UnOp, VScope, VarRef, VarTest,
    MAX_STRING,
};
use super::codes::{MAX_EXPR_HEIGHT, MAX_EXPR_NESTING, STRING_TOO_LONG, SYNTAX, UNSUPPORTED};
use super::error::SyntaxError;
use super::number::{scan_unsigned, TOO_LARGE};

/// The parser's internal error: where, which ISG number, what.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PErr<'a> {
    pub input: &'a str,
    pub code: u32,
    pub msg: Cow<'static, str>,
}

impl<'a> ParseError<&'a str> for PErr<'a> {
    fn from_error_kind(input: &'a str, _kind: ErrorKind) -> Self {
        PErr {
            input,
            code: SYNTAX,
            msg: Cow::Borrowed("NC command or axis name expected"),
        }
    }

    fn append(_input: &'a str, _kind: ErrorKind, other: Self) -> Self {
        other
    }
}

pub(crate) type PResult<'a, O> = IResult<&'a str, O, PErr<'a>>;

/// A committed error: no alternative is tried after it.
pub(crate) fn fail<'a, O>(
    input: &'a str,
    code: u32,
    msg: impl Into<Cow<'static, str>>,
) -> PResult<'a, O> {
    Err(nom::Err::Failure(PErr {
        input,
        code,
        msg: msg.into(),
    }))
}

/// The committed error itself, for functions that do not return a parse result.
pub(crate) fn perr<'a>(
    input: &'a str,
    code: u32,
    msg: impl Into<Cow<'static, str>>,
) -> nom::Err<PErr<'a>> {
    nom::Err::Failure(PErr {
        input,
        code,
        msg: msg.into(),
    })
}

/// Skip blanks and tabs.
#[inline]
pub(crate) fn ws(i: &str) -> &str {
    let n = i
        .as_bytes()
        .iter()
        .position(|&b| b != b' ' && b != b'\t')
        .unwrap_or(i.len());
    // Blanks and tabs are single bytes, so `n` is a character boundary.
    &i[n..]
}

#[inline]
fn is_ident_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

/// `kw` (case-insensitive) as a whole word at the start of `i`.
pub(crate) fn keyword<'a>(i: &'a str, kw: &'static str) -> Option<&'a str> {
    let r: PResult<'a, &'a str> = tag_no_case(kw)(i);
    match r {
        Ok((rest, _)) if !rest.as_bytes().first().is_some_and(|&b| is_ident_byte(b)) => Some(rest),
        _ => None,
    }
}

/// An unsigned decimal integer that fits a `u32`.
/// Hand-written rather than nom's `digit1` and a second pass: every P number, index and
/// block number comes through here, and the combinator cost ~160 instructions a call.
pub(crate) fn uint(i: &str) -> PResult<'_, u32> {
    let b = i.as_bytes();
    // Up to seven digits, the common number, read eight bytes at once.
    let (n, digits) = super::number::digit_run(b);
    if (1..super::number::RUN).contains(&digits) {
        // ASCII digits end on a character boundary; below 10^7, `n` fits a u32.
        return Ok((&i[digits..], n as u32));
    }
    // One pass: the value only grows, so it is too large as soon as a prefix of it is.
    let mut n: u64 = 0;
    let mut digits = 0;
    while let Some(&c) = b.get(digits) {
        let d = c.wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        n = n * 10 + u64::from(d);
        if n > u64::from(u32::MAX) {
            return fail(i, SYNTAX, "number too large");
        }
        digits += 1;
    }
    if digits == 0 {
        return Err(nom::Err::Error(PErr::from_error_kind(i, ErrorKind::Digit)));
    }
    // ASCII digits end on a character boundary; `n` fits a u32 (checked above).
    Ok((&i[digits..], n as u32))
}

/// An identifier `[A-Za-z_][A-Za-z0-9_]*`, upper-cased.
pub(crate) fn name_upper(i: &str) -> PResult<'_, String> {
    let (rest, first) = take_while1(|c: char| c.is_ascii_alphabetic() || c == '_')(i)?;
    let (rest, more) = take_while(|c: char| c.is_ascii_alphanumeric() || c == '_')(rest)?;
    let mut s = String::with_capacity(first.len() + more.len());
    s.push_str(first);
    s.push_str(more);
    s.make_ascii_uppercase();
    Ok((rest, s))
}

/// [`name_upper`], or 20200 with `expected` (what the grammar wanted there) at `i`.
pub(crate) fn name_or<'a>(i: &'a str, expected: &'static str) -> PResult<'a, String> {
    match name_upper(i) {
        Err(nom::Err::Error(_)) => fail(i, SYNTAX, expected),
        r => r,
    }
}

/// Parse state for one line: the line itself (for columns) and the expression nesting depth.
pub(crate) struct Ctx<'a> {
    pub line: &'a str,
    ascii: bool,
    depth: Cell<u32>,
    /// Height of the expression tree parsed last (a literal is 0). Bounded by
    /// [`MAX_EXPR_HEIGHT`] so that evaluating, printing and dropping a tree cannot overflow
    /// the stack, however the 4000 characters are arranged.
    height: Cell<u32>,
}

/// Leaves one nesting level when dropped.
pub(crate) struct DepthGuard<'c> {
    depth: &'c Cell<u32>,
}

impl Drop for DepthGuard<'_> {
    fn drop(&mut self) {
        self.depth.set(self.depth.get() - 1);
    }
}

impl<'a> Ctx<'a> {
    pub fn new(line: &'a str) -> Self {
        Self::with_ascii(line, line.is_ascii())
    }

    /// `ascii` must say whether `line` is pure ASCII (then columns are byte offsets).
    pub(crate) fn with_ascii(line: &'a str, ascii: bool) -> Self {
        Ctx {
            line,
            ascii,
            depth: Cell::new(0),
            height: Cell::new(0),
        }
    }

    /// Record the height of the node just built; too high is 20200.
    fn set_height(&self, h: u32, at: &'a str) -> Result<(), nom::Err<PErr<'a>>> {
        if h > MAX_EXPR_HEIGHT {
            return Err(perr(at, SYNTAX, "expression too complex"));
        }
        self.height.set(h);
        Ok(())
    }

    /// The same line cut after its first `len` bytes (a char boundary): a parser that must
    /// stop there (`XP1*2 Y3`: an unbracketed word value ends at the blank) and still
    /// reports the columns of the whole line.
    pub(crate) fn cut(&self, len: usize) -> Ctx<'a> {
        Ctx::with_ascii(&self.line[..len.min(self.line.len())], self.ascii)
    }

    /// 1-based character column of the position where `rest` starts.
    pub fn col(&self, rest: &str) -> u32 {
        let off = self.line.len().saturating_sub(rest.len());
        let chars = if self.ascii {
            off
        } else {
            self.line.get(..off).map_or(off, |p| p.chars().count())
        };
        u32::try_from(chars + 1).unwrap_or(u32::MAX)
    }

    /// A committed error at 1-based character column `col` (found after the scan passed it).
    pub(crate) fn err_at(
        &self,
        col: u32,
        code: u32,
        msg: impl Into<Cow<'static, str>>,
    ) -> nom::Err<PErr<'a>> {
        perr(self.rest_at(col), code, msg)
    }

    /// The line from 1-based character column `col` on.
    pub(crate) fn rest_at(&self, col: u32) -> &'a str {
        let k = (col as usize).saturating_sub(1);
        let off = if self.ascii {
            k.min(self.line.len())
        } else {
            self.line
                .char_indices()
                .nth(k)
                .map_or(self.line.len(), |(o, _)| o)
        };
        &self.line[off..]
    }

    pub(crate) fn to_error(&self, e: nom::Err<PErr<'_>>) -> SyntaxError {
        match e {
            nom::Err::Error(p) | nom::Err::Failure(p) => {
                SyntaxError::new(p.code, self.col(p.input), p.msg.into_owned())
            }
            nom::Err::Incomplete(_) => SyntaxError::new(SYNTAX, 1, "incomplete block"),
        }
    }

    fn enter(&self, i: &'a str) -> Result<DepthGuard<'_>, nom::Err<PErr<'a>>> {
        let d = self.depth.get() + 1;
        if d > MAX_EXPR_NESTING {
            return Err(nom::Err::Failure(PErr {
                input: i,
                code: SYNTAX,
                msg: Cow::Borrowed("expression nested too deeply"),
            }));
        }
        self.depth.set(d);
        Ok(DepthGuard { depth: &self.depth })
    }

    /// A full expression. Trailing blanks are not consumed.
    ///
    /// A lone literal (`P1=12345`, the common value) is taken without the precedence climb:
    /// when no operator can follow it, the climb would return the same `Expr::Num`, rest and
    /// height.
    pub fn expr(&self, i: &'a str) -> PResult<'a, Expr> {
        if i.as_bytes().first().is_some_and(u8::is_ascii_digit) {
            if let Some((v, n)) = scan_unsigned(i.as_bytes()) {
                let rest = &i[n..];
                let no_operator = ws(rest)
                    .as_bytes()
                    .first()
                    .is_none_or(|&b| !may_start_binary_op(b));
                if v.is_finite() && no_operator {
                    self.height.set(0);
                    return Ok((rest, Expr::Num(v)));
                }
            }
        }
        self.level(0, i)
    }

    /// A word's value written without brackets (`XP1`, `X = P1*2`). Written back it is
    /// bracketed (`X[P1]`), so it counts one nesting level, or the printed block could nest
    /// past the limit and not parse again.
    pub(crate) fn unbracketed_value(&self, i: &'a str) -> PResult<'a, Expr> {
        let _g = self.enter(i)?;
        self.expr(i)
    }

    /// `[expr]`: the bracketed form words use (`X[P1*2]`).
    pub(crate) fn bracketed(&self, i: &'a str) -> PResult<'a, Expr> {
        let (i, _) = ch('[')(i)?;
        let _g = self.enter(i)?;
        let (j, e) = self.expr(ws(i))?;
        let j = ws(j);
        match ch::<&str, PErr<'a>>(']')(j) {
            Ok((k, _)) => Ok((k, e)),
            Err(_) => fail(j, SYNTAX, "`]` or operator expected"),
        }
    }

    /// Precedence climbing: an operand, then every binary operator of level `min` or tighter,
    /// each with its right operand parsed one level tighter (left associative). One operator
    /// lookup per operator position, instead of one per level per operand.
    fn level(&self, min: usize, i: &'a str) -> PResult<'a, Expr> {
        let (mut i, mut lhs) = self.unary(i)?;
        let mut h = self.height.get();
        loop {
            let j = ws(i);
            let Some((op, n, lvl)) = any_binary_op(j) else {
                break;
            };
            if lvl < min {
                break;
            }
            let (k, rhs) = self.level(lvl + 1, ws(&j[n..]))?;
            h = h.max(self.height.get()) + 1;
            self.set_height(h, j)?;
            lhs = Expr::Binary(op, Box::new(lhs), Box::new(rhs));
            i = k;
        }
        self.height.set(h);
        Ok((i, lhs))
    }

    fn unary(&self, i: &'a str) -> PResult<'a, Expr> {
        let b = i.as_bytes().first().copied();
        match b {
            Some(b'-') => {
                let _g = self.enter(i)?;
                let after = &i[1..];
                let literal = after
                    .as_bytes()
                    .first()
                    .is_some_and(|&c| c.is_ascii_digit() || c == b'.');
                let (rest, e) = if literal {
                    self.power(after)?
                } else {
                    self.unary(ws(after))?
                };
                match e {
                    Expr::Num(v) if literal => Ok((rest, Expr::Num(-v))),
                    e => {
                        self.set_height(self.height.get() + 1, i)?;
                        Ok((rest, Expr::Unary(UnOp::Neg, Box::new(e))))
                    }
                }
            }
            Some(b'+') => {
                let _g = self.enter(i)?;
                self.unary(ws(&i[1..]))
            }
            Some(b'N' | b'n' | b'I' | b'i') => {
                let (op, rest) = if let Some(rest) = keyword(i, "NOT") {
                    (UnOp::Not, rest)
                } else if let Some(rest) = keyword(i, "INV") {
                    (UnOp::Inv, rest)
                } else {
                    return self.power(i);
                };
                let _g = self.enter(i)?;
                let (rest, e) = self.unary(ws(rest))?;
                self.set_height(self.height.get() + 1, i)?;
                Ok((rest, Expr::Unary(op, Box::new(e))))
            }
            _ => self.power(i),
        }
    }

    fn power(&self, i: &'a str) -> PResult<'a, Expr> {
        let (i, base) = self.primary(i)?;
        let j = ws(i);
        if let Ok((k, _)) = tag::<&str, &str, PErr<'a>>("**")(j) {
            let hb = self.height.get();
            let _g = self.enter(j)?;
            let (k, exp) = self.unary(ws(k))?;
            self.set_height(hb.max(self.height.get()) + 1, j)?;
            return Ok((k, Expr::Binary(BinOp::Pow, Box::new(base), Box::new(exp))));
        }
        Ok((i, base))
    }

    fn primary(&self, i: &'a str) -> PResult<'a, Expr> {
        let Some(&b) = i.as_bytes().first() else {
            return fail(i, SYNTAX, "operand expected, found end of block");
        };
        match b {
            b'[' => self.bracketed(i),
            b'0'..=b'9' | b'.' => match scan_unsigned(i.as_bytes()) {
                Some((v, _)) if !v.is_finite() => fail(i, SYNTAX, TOO_LARGE),
                Some((v, n)) => {
                    self.height.set(0);
                    Ok((&i[n..], Expr::Num(v)))
                }
                None => fail(
                    i,
                    SYNTAX,
                    format!("number expected ({})", super::number::LITERAL_LIMIT),
                ),
            },
            b'@' => {
                let (rest, v) = self.var_ref(i)?;
                Ok((rest, Expr::Var(Box::new(v))))
            }
            b'P' | b'p'
                if i.as_bytes()
                    .get(1)
                    .is_some_and(|&c| c.is_ascii_digit() || c == b'[')
                    || is_pp(i.as_bytes()) =>
            {
                let (rest, v) = self.var_ref(i)?;
                Ok((rest, Expr::Var(Box::new(v))))
            }
            b'V' | b'v' if i.as_bytes().get(1) == Some(&b'.') => {
                let (rest, v) = self.var_ref(i)?;
                Ok((rest, Expr::Var(Box::new(v))))
            }
            b'"' => self.string(i),
            c if c.is_ascii_alphabetic() => self.named(i),
            _ => fail(i, SYNTAX, "operand expected"),
        }
    }

    /// `"text"` (`i` at the quote): at most [`MAX_STRING`] characters (more: the kernel's
    /// 21870 at the quote), no quote inside.
    #[cold]
    fn string(&self, i: &'a str) -> PResult<'a, Expr> {
        let q = &i[1..];
        let Some(end) = q.find('"') else {
            return fail(i, SYNTAX, "closing `\"` missing");
        };
        let len = q[..end].chars().count();
        if len > MAX_STRING {
            return fail(
                i,
                STRING_TOO_LONG,
                format!("string of {len} characters: a string holds at most {MAX_STRING}"),
            );
        }
        self.height.set(0);
        Ok((&q[end + 1..], Expr::Str(q[..end].into())))
    }

    /// `[a, b, …]` after a function's name (`rest`): the arguments (room for `expected`,
    /// at most `most`: a comma after the last allowed one is refused there) and the tallest
    /// argument's height. The caller checks the count against the function's arity.
    fn call_args(
        &self,
        name: &str,
        rest: &'a str,
        expected: usize,
        most: usize,
    ) -> PResult<'a, (Vec<Expr>, u32)> {
        let j = ws(rest);
        let Some(j) = j.strip_prefix('[') else {
            return fail(j, SYNTAX, format!("`[` expected after {name}"));
        };
        let _g = self.enter(j)?;
        let mut args = Vec::with_capacity(expected);
        let mut h = 0;
        let mut j = ws(j);
        loop {
            let (k, e) = self.expr(j)?;
            h = h.max(self.height.get());
            args.push(e);
            let k = ws(k);
            match k.as_bytes().first() {
                Some(b',') if args.len() < most => j = ws(&k[1..]),
                Some(b']') => return Ok((&k[1..], (args, h))),
                _ => return fail(k, SYNTAX, "`,` or `]` expected in function call"),
            }
        }
    }

    /// A string function's arguments after its name (`rest`; `at` is where the name starts).
    #[cold]
    fn str_func(&self, func: StrFunc, at: &'a str, rest: &'a str) -> PResult<'a, Expr> {
        let name = func.name();
        // At most three: no string function takes more.
        let (j, (args, h)) = self.call_args(name, rest, 3, 3)?;
        let (min, max) = func.arity();
        if !(min..=max).contains(&args.len()) {
            let want = if min == max {
                format!("{min}")
            } else {
                format!("{min} or {max}")
            };
            return fail(
                at,
                SYNTAX,
                format!("{name} takes {want} argument(s), got {}", args.len()),
            );
        }
        self.set_height(h + 1, at)?;
        Ok((j, Expr::StrFunc(func, args)))
    }

    /// A constant or a function call.
    fn named(&self, i: &'a str) -> PResult<'a, Expr> {
        let (rest, name) = name_upper(i)?;
        self.height.set(0);
        match name.as_str() {
            "PI" => return Ok((rest, Expr::Num(std::f64::consts::PI))),
            "TRUE" => return Ok((rest, Expr::Num(1.0))),
            "FALSE" => return Ok((rest, Expr::Num(0.0))),
            _ => {}
        }
        let Some(func) = func_by_name(&name) else {
            if let Some(test) = var_test_by_name(&name) {
                return self.var_test(test, i, rest);
            }
            if let Some(f) = STR_FUNCS.into_iter().find(|f| f.name() == name) {
                return self.str_func(f, i, rest);
            }
            return fail(i, SYNTAX, format!("unknown function or operand `{name}`"));
        };
        let (j, (args, h)) = self.call_args(&name, rest, func.arity(), usize::MAX)?;
        if args.len() != func.arity() {
            return fail(
                i,
                SYNTAX,
                format!(
                    "{name} takes {} argument(s), got {}",
                    func.arity(),
                    args.len()
                ),
            );
        }
        self.set_height(h + 1, i)?;
        Ok((j, Expr::Func(func, args)))
    }

    /// `EXIST[v]`, `IS_NUMBER[v]`, `IS_STRING[v]` after the name (`at` is where the name
    /// starts, `rest` after it): the argument is one variable, not an expression.
    #[cold]
    fn var_test(&self, test: VarTest, at: &'a str, rest: &'a str) -> PResult<'a, Expr> {
        let name = test.name();
        let j = ws(rest);
        let Some(j) = j.strip_prefix('[') else {
            return fail(j, SYNTAX, format!("`[` expected after {name}"));
        };
        let _g = self.enter(j)?;
        let j = ws(j);
        let (k, v) = match self.var_ref(j) {
            Ok(ok) => ok,
            Err(nom::Err::Failure(p)) if p.input.len() < j.len() => {
                return Err(nom::Err::Failure(p))
            }
            Err(_) => {
                return fail(
                    j,
                    SYNTAX,
                    format!("{name} takes a variable (P, V., @P), not an expression"),
                )
            }
        };
        let k = ws(k);
        let Some(k) = k.strip_prefix(']') else {
            return fail(
                k,
                SYNTAX,
                format!("`]` expected after the variable of {name}"),
            );
        };
        self.set_height(self.height.get() + 1, at)?;
        Ok((k, Expr::Test(test, Box::new(v))))
    }

    /// `P<n>` of up to seven digits and without indices at the start of `i` (the number and
    /// the rest), as [`Ctx::var_ref`] reads it, tree height included; `None` for anything
    /// else, which `var_ref` reads. The commonest assignment target of a stream, read
    /// without the general path (callgrind: about 225 instructions a `P1=` line there).
    pub(crate) fn const_p(&self, i: &'a str) -> Option<(&'a str, u32)> {
        let b = i.as_bytes();
        if !matches!(b.first(), Some(b'P' | b'p')) {
            return None;
        }
        let (n, digits) = super::number::digit_run(&b[1..]);
        if !(1..super::number::RUN).contains(&digits) || b.get(1 + digits) == Some(&b'[') {
            return None;
        }
        // `var_ref`: no indices leave the height at 0, and the reference adds one.
        self.height.set(1);
        // ASCII digits end on a character boundary; below 10^7, `n` fits a u32.
        Some((&i[1 + digits..], n as u32))
    }

    /// `P<n>`, `P[expr]`, each with optional adjacent `[i]` indices; `V.x.name[..]`; `@P<n>`.
    pub fn var_ref(&self, i: &'a str) -> PResult<'a, VarRef> {
        let bytes = i.as_bytes();
        match bytes.first() {
            Some(b'@') => {
                let Some(rest) = i.get(1..).filter(|r| r.starts_with(['P', 'p'])) else {
                    return fail(i, SYNTAX, "`@P<number>` expected");
                };
                match uint(&rest[1..]) {
                    Ok((rest, n)) => {
                        self.height.set(1);
                        Ok((rest, VarRef::CycleParam(n)))
                    }
                    Err(nom::Err::Error(_)) => {
                        fail(&rest[1..], SYNTAX, "cycle parameter number expected")
                    }
                    Err(e) => Err(e),
                }
            }
            Some(b'P' | b'p') => {
                let rest = &i[1..];
                let mut h = 0;
                let (rest, number) = if rest.starts_with('[') {
                    let (r, e) = self.bracketed(rest)?;
                    h = self.height.get();
                    (r, Index::Expr(Box::new(e)))
                } else if is_pp(i.as_bytes()) {
                    let (r, n) = self.indirect_p(rest)?;
                    h = self.height.get();
                    (r, n)
                } else {
                    match uint(rest) {
                        Ok((r, n)) => (r, Index::Const(n)),
                        Err(nom::Err::Error(_)) => {
                            return fail(rest, SYNTAX, "parameter number expected")
                        }
                        Err(e) => return Err(e),
                    }
                };
                let (rest, indices) = self.indices(rest)?;
                self.set_height(h.max(self.height.get()) + 1, i)?;
                Ok((rest, VarRef::P { number, indices }))
            }
            Some(b'V' | b'v') if bytes.get(1) == Some(&b'.') => {
                let scope = match bytes.get(2).map(u8::to_ascii_uppercase) {
                    Some(b'A') if bytes.get(3) == Some(&b'.') => return self.axis_var(i),
                    Some(b'G') if bytes.get(3) == Some(&b'.') => return self.global_var(i),
                    Some(b'P') => VScope::Program,
                    Some(b'L') => VScope::Local,
                    Some(b'S') => VScope::SelfRetaining,
                    Some(b'E') => VScope::External,
                    _ => {
                        return fail(
                            &i[2..],
                            SYNTAX,
                            "variable scope P, L, S or E expected after `V.`",
                        )
                    }
                };
                let Some(rest) = i.get(3..).filter(|r| r.starts_with('.')) else {
                    return fail(
                        i.get(3..).unwrap_or(""),
                        SYNTAX,
                        "`.` expected after the variable scope",
                    );
                };
                let rest = &rest[1..];
                let (mut rest, mut name) = name_or(rest, "variable name expected")?;
                let (r, mut indices) = self.indices(rest)?;
                let mut h = self.height.get();
                rest = r;
                // A V.E. structure member, `V.E.SCH.PREFLOW`, `V.E.INFO[1].X` (TF5200
                // External variables): the members join the name, the indices go in order.
                while scope == VScope::External
                    && rest.starts_with('.')
                    && rest[1..]
                        .bytes()
                        .next()
                        .is_some_and(|b| b.is_ascii_alphabetic() || b == b'_')
                {
                    let (r, member) = name_or(&rest[1..], "structure member expected")?;
                    name.push('.');
                    name.push_str(&member);
                    let (r, more) = self.indices(r)?;
                    h = h.max(self.height.get());
                    indices.extend(more);
                    rest = r;
                }
                self.height.set(h);
                self.set_height(self.height.get() + 1, i)?;
                Ok((
                    rest,
                    VarRef::V {
                        scope,
                        name,
                        indices,
                    },
                ))
            }
            _ => fail(i, SYNTAX, "parameter or variable expected"),
        }
    }

    /// `V.A.<field>.<axis>` or `V.A.<field>[<index>]` (`i` at the `V`): `ABS` is modelled,
    /// every other field of the manual's list is refused by name (900133).
    #[cold]
    fn axis_var(&self, i: &'a str) -> PResult<'a, VarRef> {
        let f = &i[4..];
        let (rest, field) = name_or(f, "axis variable name expected")?;
        if field != "ABS" {
            return fail(
                f,
                UNSUPPORTED,
                format!("V.A.{field} is an ISG axis variable ncchannel does not model"),
            );
        }
        let (rest, axis) = self.axis_sel(rest, "V.A.ABS")?;
        self.set_height(self.height.get() + 1, i)?;
        Ok((rest, VarRef::AxisAbs(axis)))
    }

    /// `.<axis>` or `[<index>]` after `what` (`V.A.ABS`, `V.G.NP[i].V`, `V.G.WZ_AKT.V`); the
    /// height is left at the index expression's (0 for a name).
    fn axis_sel(&self, rest: &'a str, what: &str) -> PResult<'a, AxisSel> {
        if let Some(r) = rest.strip_prefix('.') {
            match r.as_bytes().first() {
                Some(&b)
                    if b.is_ascii_alphabetic()
                        && !r.as_bytes().get(1).is_some_and(|&c| is_ident_byte(c)) =>
                {
                    self.height.set(0);
                    Ok((&r[1..], AxisSel::Name(b.to_ascii_uppercase())))
                }
                _ => fail(r, SYNTAX, format!("axis name expected after {what}.")),
            }
        } else if rest.starts_with('[') {
            let (r, e) = self.bracketed(rest)?;
            Ok((r, AxisSel::Index(Box::new(e))))
        } else {
            fail(
                rest,
                SYNTAX,
                format!("`.<axis>` or `[<index>]` expected after {what}"),
            )
        }
    }

    /// `V.G.WZ_AKT.<field>` or `V.G.WZ[<j>].<field>` (`i` at the `V`): the tool list's data,
    /// fields `R`, `L`, `OK`, `V.<axis>` / `V[<i>]` (TF5200 "Access to tool data in the NC
    /// program (V.G.WZ..)"); `V.G.NP[<i>].V.<axis>` / `.V[<j>]`, a zero-offset group's offset
    /// (programming manual, "Zero offsets (G53/G54/...G59)"). Every other V.G. variable or
    /// tool field is refused by name (900133).
    #[cold]
    fn global_var(&self, i: &'a str) -> PResult<'a, VarRef> {
        self.height.set(0);
        let f = &i[4..];
        let (rest, name) = name_or(f, "global variable name expected")?;
        if let ("M_FCT" | "H_FCT", true) = (name.as_str(), rest.starts_with('[')) {
            return self.function_sync(name.as_str() == "H_FCT", rest, i);
        }
        if name == "NP" {
            return self.zero_offset_var(rest, i);
        }
        let (rest, tool) = match name.as_str() {
            "WZ_AKT" => (rest, None),
            "WZ" if rest.starts_with('[') => {
                let (r, e) = self.bracketed(rest)?;
                (r, Some(Box::new(e)))
            }
            "WZ" => return fail(rest, SYNTAX, "`[<tool>]` expected after V.G.WZ"),
            _ => {
                return fail(
                    f,
                    UNSUPPORTED,
                    format!("V.G.{name} is an ISG global variable ncchannel does not model"),
                )
            }
        };
        let Some(r) = rest.strip_prefix('.') else {
            return fail(
                rest,
                SYNTAX,
                format!("`.<field>` expected after V.G.{name}"),
            );
        };
        let (rest, field) = name_or(r, "tool data field expected")?;
        let tool_height = self.height.get();
        let (rest, field) = match field.as_str() {
            "R" => {
                self.set_height(tool_height + 1, i)?;
                return Ok((rest, VarRef::ToolRadius(tool)));
            }
            "L" => (rest, ToolField::Length),
            "OK" => (rest, ToolField::Valid),
            "V" => {
                let (rest, axis) = self.axis_sel(rest, &format!("V.G.{name}.V"))?;
                self.height.set(self.height.get().max(tool_height));
                (rest, ToolField::AxisOffset(axis))
            }
            _ => {
                return fail(
                    r,
                    UNSUPPORTED,
                    format!(
                        "V.G.{name}.{field}: ncchannel's tool list has R, L, OK and V (axis \
                         offsets) only"
                    ),
                )
            }
        };
        self.set_height(self.height.get() + 1, i)?;
        Ok((rest, VarRef::ToolData { tool, field }))
    }

    /// `V.G.NP[<i>].V.<axis>` / `V.G.NP[<i>].V[<j>]` from the `[` on (`i` at the `V`).
    #[cold]
    fn zero_offset_var(&self, rest: &'a str, i: &'a str) -> PResult<'a, VarRef> {
        if !rest.starts_with('[') {
            return fail(rest, SYNTAX, "`[<group>]` expected after V.G.NP");
        }
        let (r, group) = self.bracketed(rest)?;
        let group_height = self.height.get();
        let (r, field) = match r.strip_prefix('.') {
            Some(r) => name_or(r, "`.V` expected after V.G.NP[<group>]")?,
            None => return fail(r, SYNTAX, "`.V` expected after V.G.NP[<group>]"),
        };
        if field != "V" {
            return fail(
                r,
                UNSUPPORTED,
                format!("V.G.NP[…].{field}: ncchannel models the offsets (V) only"),
            );
        }
        let (r, axis) = self.axis_sel(r, "V.G.NP[<group>].V")?;
        self.set_height(self.height.get().max(group_height) + 1, i)?;
        Ok((
            r,
            VarRef::ZeroOffset {
                group: Box::new(group),
                axis,
            },
        ))
    }

    /// `V.G.M_FCT[<n>].SYNCH` / `V.G.H_FCT[<n>].SYNCH` from the `[` on; `i` at the `V`.
    #[cold]
    fn function_sync(&self, h: bool, rest: &'a str, i: &'a str) -> PResult<'a, VarRef> {
        let (r, number) = self.bracketed(rest)?;
        let (r, field) = match r.strip_prefix('.') {
            Some(r) => name_or(r, "function data field expected")?,
            None => return fail(r, SYNTAX, "`.SYNCH` expected after the function number"),
        };
        if field != "SYNCH" {
            return fail(
                r,
                UNSUPPORTED,
                format!("{field}: ncchannel models the SYNCH field of V.G.M_FCT / V.G.H_FCT only"),
            );
        }
        self.set_height(self.height.get() + 1, i)?;
        Ok((
            r,
            VarRef::FunctionSync {
                h,
                number: Box::new(number),
            },
        ))
    }

    /// Array indices written directly after a variable: `[i]`, `[i][j]`.
    fn indices(&self, mut i: &'a str) -> PResult<'a, Vec<Expr>> {
        let mut v = Vec::new();
        let mut h = 0;
        while i.starts_with('[') {
            let (rest, e) = self.bracketed(i)?;
            h = h.max(self.height.get());
            v.push(e);
            i = rest;
        }
        self.height.set(h);
        Ok((i, v))
    }
}

/// The binary operator of precedence level `lvl` at the start of `i`, with its length.
#[inline]
/// The binary operator at the start of `i`, its length and its level (0 binds loosest). The
/// operators of different levels never share a prefix, so at most one level matches.
fn any_binary_op(i: &str) -> Option<(BinOp, usize, usize)> {
    let b0 = *i.as_bytes().first()?;
    // Most positions hold no operator at all: rule them out with one byte.
    if !may_start_binary_op(b0) {
        return None;
    }
    (0..LEVELS).find_map(|lvl| binary_op(lvl, i).map(|(op, n)| (op, n, lvl)))
}

/// `b` can start a binary operator (or `**`): every other byte ends an operand's operators.
#[inline]
fn may_start_binary_op(b: u8) -> bool {
    matches!(
        b,
        b'|' | b'&'
            | b'^'
            | b'='
            | b'!'
            | b'<'
            | b'>'
            | b'+'
            | b'-'
            | b'*'
            | b'/'
            | b'O'
            | b'o'
            | b'X'
            | b'x'
            | b'A'
            | b'a'
            | b'M'
            | b'm'
    )
}

/// Number of binary precedence levels.
const LEVELS: usize = 9;

fn binary_op(lvl: usize, i: &str) -> Option<(BinOp, usize)> {
    let b = i.as_bytes();
    let b0 = *b.first()?;
    let b1 = b.get(1).copied().unwrap_or(0);
    match lvl {
        0 => match (b0, b1) {
            (b'|', b'|') => Some((BinOp::Or, 2)),
            (b'O' | b'o', _) => keyword(i, "OR").map(|_| (BinOp::Or, 2)),
            _ => None,
        },
        1 => match b0 {
            b'X' | b'x' => keyword(i, "XOR").map(|_| (BinOp::Xor, 3)),
            _ => None,
        },
        2 => match (b0, b1) {
            (b'&', b'&') => Some((BinOp::And, 2)),
            (b'A' | b'a', _) => keyword(i, "AND").map(|_| (BinOp::And, 3)),
            _ => None,
        },
        3 => (b0 == b'|' && b1 != b'|').then_some((BinOp::BitOr, 1)),
        4 => (b0 == b'^').then_some((BinOp::BitXor, 1)),
        5 => (b0 == b'&' && b1 != b'&').then_some((BinOp::BitAnd, 1)),
        6 => match (b0, b1) {
            (b'=', b'=') => Some((BinOp::Eq, 2)),
            (b'!', b'=') | (b'<', b'>') => Some((BinOp::Ne, 2)),
            (b'<', b'=') => Some((BinOp::Le, 2)),
            (b'>', b'=') => Some((BinOp::Ge, 2)),
            (b'<', _) => Some((BinOp::Lt, 1)),
            (b'>', _) => Some((BinOp::Gt, 1)),
            _ => None,
        },
        7 => match b0 {
            b'+' => Some((BinOp::Add, 1)),
            b'-' => Some((BinOp::Sub, 1)),
            _ => None,
        },
        8 => match (b0, b1) {
            (b'*', b'*') => None,
            (b'*', _) => Some((BinOp::Mul, 1)),
            (b'/', _) => Some((BinOp::Div, 1)),
            (b'M' | b'm', _) => keyword(i, "MOD").map(|_| (BinOp::Mod, 3)),
            _ => None,
        },
        _ => None,
    }
}

impl BinOp {
    /// The operator's precedence level as [`binary_op`] reads it: 0 (`||`) binds loosest, 8
    /// (`* / MOD`) tightest; `**` is 10, above the unary operators' 9 (module table). The
    /// canonical printer brackets by these levels, so they are spelled once, here.
    pub(crate) fn level(self) -> u8 {
        match self {
            BinOp::Or => 0,
            BinOp::Xor => 1,
            BinOp::And => 2,
            BinOp::BitOr => 3,
            BinOp::BitXor => 4,
            BinOp::BitAnd => 5,
            BinOp::Eq | BinOp::Ne | BinOp::Lt | BinOp::Gt | BinOp::Le | BinOp::Ge => 6,
            BinOp::Add | BinOp::Sub => 7,
            BinOp::Mul | BinOp::Div | BinOp::Mod => 8,
            BinOp::Pow => 10,
        }
    }
}

impl Func {
    /// Number of arguments: ATAN2 takes two, every other function one.
    pub(crate) fn arity(self) -> usize {
        match self {
            Func::Atan2 => 2,
            _ => 1,
        }
    }

    /// The function's name as written in NC text.
    pub fn name(self) -> &'static str {
        match self {
            Func::Abs => "ABS",
            Func::Sqr => "SQR",
            Func::Sqrt => "SQRT",
            Func::Exp => "EXP",
            Func::Ln => "LN",
            Func::Log => "LOG",
            Func::Sin => "SIN",
            Func::Cos => "COS",
            Func::Tan => "TAN",
            Func::Asin => "ASIN",
            Func::Acos => "ACOS",
            Func::Atan => "ATAN",
            Func::Atan2 => "ATAN2",
            Func::Int => "INT",
            Func::Fract => "FRACT",
            Func::Round => "ROUND",
            Func::Floor => "FLOOR",
            Func::Ceil => "CEIL",
        }
    }
}

impl StrFunc {
    /// The least and most arguments: `ORD` takes its position optionally.
    pub(crate) fn arity(self) -> (usize, usize) {
        match self {
            StrFunc::Len => (1, 1),
            StrFunc::Left | StrFunc::Right | StrFunc::Find => (2, 2),
            StrFunc::Ord => (1, 2),
            StrFunc::Mid | StrFunc::Delete => (3, 3),
        }
    }

    /// The function's name as written in NC text.
    pub fn name(self) -> &'static str {
        match self {
            StrFunc::Len => "LEN",
            StrFunc::Left => "LEFT",
            StrFunc::Right => "RIGHT",
            StrFunc::Mid => "MID",
            StrFunc::Find => "FIND",
            StrFunc::Ord => "ORD",
            StrFunc::Delete => "DELETE",
        }
    }

    /// Whether the result is a string (`LEN`, `FIND`, `ORD` give numbers).
    pub(crate) fn gives_string(self) -> bool {
        matches!(
            self,
            StrFunc::Left | StrFunc::Right | StrFunc::Mid | StrFunc::Delete
        )
    }
}

/// Every string function, for lookup by name.
pub(crate) const STR_FUNCS: [StrFunc; 7] = [
    StrFunc::Len,
    StrFunc::Left,
    StrFunc::Right,
    StrFunc::Mid,
    StrFunc::Find,
    StrFunc::Ord,
    StrFunc::Delete,
];

/// Every function, for lookup by name.
pub const FUNCS: [Func; 18] = [
    Func::Abs,
    Func::Sqr,
    Func::Sqrt,
    Func::Exp,
    Func::Ln,
    Func::Log,
    Func::Sin,
    Func::Cos,
    Func::Tan,
    Func::Asin,
    Func::Acos,
    Func::Atan,
    Func::Atan2,
    Func::Int,
    Func::Fract,
    Func::Round,
    Func::Floor,
    Func::Ceil,
];

/// `PP<n>` (or `PPP<n>`, …) at the start of `b`: the parameter whose number is P<n>'s
/// value (TF5200 programming manual, "Indirect parameters": `PPnn` points to the parameter
/// whose number `Pnn` holds; `PPP…` is allowed too).
pub(crate) fn is_pp(b: &[u8]) -> bool {
    let ps = b.iter().take_while(|c| matches!(c, b'P' | b'p')).count();
    ps >= 2 && b.get(ps).is_some_and(u8::is_ascii_digit)
}

impl<'a> Ctx<'a> {
    /// The number of `PP…P<n>` from the second `P` on (`i`): `P[P…[P<n>]]`, one level a `P`,
    /// within the tree height limit.
    #[cold]
    fn indirect_p(&self, i: &'a str) -> PResult<'a, Index> {
        let ps = i.bytes().take_while(|c| matches!(c, b'P' | b'p')).count();
        let (r, n) = uint(&i[ps..])?;
        let levels = u32::try_from(ps).unwrap_or(u32::MAX);
        // Written back (a log line, `check`'s canonical text) each `P` is a bracket,
        // `P[P[…]]`: the chain nests as deep as those brackets would, or the printed block
        // would not parse again.
        if self.depth.get().saturating_add(levels) > MAX_EXPR_NESTING {
            return Err(nom::Err::Failure(PErr {
                input: i,
                code: SYNTAX,
                msg: Cow::Borrowed("expression nested too deeply"),
            }));
        }
        self.set_height(levels.saturating_mul(2), i)?;
        let mut number = Index::Const(n);
        for _ in 0..ps {
            let inner = VarRef::P {
                number,
                indices: Vec::new(),
            };
            number = Index::Expr(Box::new(Expr::Var(Box::new(inner))));
        }
        Ok((r, number))
    }
}

/// `EXIST`, `IS_NUMBER`, `IS_STRING` (upper-case `name`).
fn var_test_by_name(upper: &str) -> Option<VarTest> {
    [VarTest::Exist, VarTest::IsNumber, VarTest::IsString]
        .into_iter()
        .find(|t| t.name() == upper)
}

fn func_by_name(upper: &str) -> Option<Func> {
    FUNCS.into_iter().find(|f| f.name() == upper)
}

/// Parse a whole string as one expression (for tests and tools).
pub fn parse_expr(text: &str) -> Result<Expr, SyntaxError> {
    let ctx = Ctx::new(text);
    let (rest, e) = ctx.expr(ws(text)).map_err(|e| ctx.to_error(e))?;
    let rest = ws(rest);
    if !rest.is_empty() {
        return Err(SyntaxError::new(
            SYNTAX,
            ctx.col(rest),
            "operator or end of expression expected",
        ));
    }
    Ok(e)
}

/// An optional `[ … ]` kept verbatim (brackets may nest), trimmed. `none` is the input to
/// return when there is no bracket.
pub(crate) fn verbatim_options<'a>(i: &'a str, none: &'a str) -> PResult<'a, String> {
    if !i.starts_with('[') {
        return Ok((none, String::new()));
    }
    let mut depth = 0usize;
    for (k, b) in i.bytes().enumerate() {
        match b {
            b'[' => depth += 1,
            b']' => {
                depth -= 1;
                if depth == 0 {
                    // Only the blanks and tabs `ws` skips: a text that began with another
                    // space character (a vertical tab) must not print as a quoted one.
                    let text = i[1..k].trim_matches([' ', '\t']);
                    return Ok((&i[k + 1..], text.to_string()));
                }
            }
            _ => {}
        }
    }
    fail(i, SYNTAX, "`]` missing")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every length of digits, below and above `u32::MAX`, with a tail: the value and rest
    /// of a digit-by-digit reading, and "too large" at the number's start past `u32::MAX`.
    #[test]
    fn uint_reads_every_length_of_digits() {
        for text in [
            "0",
            "7 X",
            "12:",
            "1234567",
            "12345678",
            "123456789",
            "0000000012",
            "4294967295",
            "4294967296",
            "99999999999",
            "12345678901234567890",
            "N1",
            "",
            "9/",
            "65535=",
        ] {
            let digits = text.bytes().take_while(u8::is_ascii_digit).count();
            let value = text[..digits].parse::<u64>().ok();
            match uint(text) {
                Ok((rest, n)) => {
                    assert_eq!(rest, &text[digits..], "{text}");
                    assert_eq!(Some(u64::from(n)), value, "{text}");
                }
                Err(nom::Err::Error(_)) => assert_eq!(digits, 0, "{text}"),
                Err(nom::Err::Failure(e)) => {
                    assert!(value.is_none_or(|v| v > u64::from(u32::MAX)), "{text}");
                    assert_eq!(e.input, text, "{text}");
                }
                Err(nom::Err::Incomplete(_)) => panic!("{text}"),
            }
        }
    }

    /// The printer's levels are the parser's: every operator is found at its own level.
    #[test]
    fn operator_levels_match_the_parser() {
        use BinOp::*;
        for op in [
            Or, Xor, And, BitOr, BitXor, BitAnd, Eq, Ne, Lt, Gt, Le, Ge, Add, Sub, Mul, Div, Mod,
        ] {
            let text = format!("{} 1", op.symbol());
            let found = binary_op(usize::from(op.level()), &text).map(|(o, _)| o);
            assert_eq!(found, Some(op), "{op:?} at level {}", op.level());
            assert_eq!(
                any_binary_op(&text).map(|(o, _, l)| (o, l)),
                Some((op, usize::from(op.level())))
            );
        }
    }

    /// A lone literal skips the precedence climb: value, rest, height and errors are the
    /// climb's, whatever follows the literal (end, blanks, a next word, an operator, `**`).
    #[test]
    fn a_lone_literal_is_what_the_climb_returns() {
        for text in [
            "12345",
            "12345  ",
            "7 X10",
            "7 P2=3",
            "7 (note)",
            "7 ;c",
            "1+2",
            "1 + 2",
            "2**3",
            "2 ** 3",
            "5 MOD 2",
            "5 mod 2",
            "5 AND 1",
            "5 OR 1",
            "5 XOR 1",
            "1 == 1",
            "1.5 M3",
            "3 A10",
            "3 & 1",
            "3 / 2",
            "3.",
            "1e5",
            "1E999",
            "9999999999999999999999",
            "0",
            "12.5.5",
        ] {
            let fast = Ctx::new(text);
            let climb = Ctx::new(text);
            let a = fast.expr(text);
            let b = climb.level(0, text);
            assert_eq!(format!("{a:?}"), format!("{b:?}"), "{text}");
            assert_eq!(fast.height.get(), climb.height.get(), "{text}");
        }
    }
}
