//! `#MSG`: operator messages with values formatted the way C's `printf` does (TF5200
//! programming manual, "Messages from the NC program": "The functionality corresponds to the
//! 'printf' function"; "Programming a message (#MSG)", "Programming message information
//! (#MSG INFO)", "Writing messages to a file (#MSG SAVE)").
//!
//! `#MSG [<mode>] [<receiver>] ["<text>", <value>, …]`, `#MSG INFO …`, `#MSG SAVE [EXCLUSIVE]
//! [CONTINUE] [...]`. The text's format elements are `%s %S %d %D %f %F` (the list the
//! kernel's diagnoses 20721, 20724 and 21232 name), with C's flags, width and precision, and
//! `%%` for a percent sign. The parser checks the elements against the values, so
//! `ncchannel check` and a run refuse the same line; the decoder evaluates the values and
//! formats the text within [`MAX_MSG_CHARS`].

use super::block::{Command, Expr, Message};
use super::codes::{MSG_ARG_COUNT, MSG_NO_VALUE, MSG_TOO_MANY_VALUES, MSG_UNKNOWN_FORMAT, SYNTAX};
use super::eval::Val;
use super::expr::verbatim_options;
use super::expr::{fail, keyword, perr, ws, Ctx, PErr};

/// Most values (format elements) one message may carry: ncchannel's limit, which 20724
/// reports as its limit value (the kernel's own limit is not published on the page).
pub const MAX_MSG_VALUES: usize = 50;

/// Longest formatted message, in bytes of UTF-8 text: ncchannel's bound (900136 beyond), so a
/// line of wide fields allocates no more than this.
pub const MAX_MSG_CHARS: usize = 4000;

/// Widest field and largest precision: two digits. A longer one is an unknown format (21232).
const MAX_FIELD: usize = 99;

/// The keywords that may stand between `#MSG` and the bracket: `SAVE` or `INFO` first, then
/// for `SAVE` its `EXCLUSIVE` / `CONTINUE`, otherwise a mode and a receiver.
const SAVE_OPTIONS: &[&str] = &["EXCLUSIVE", "CONTINUE"];
const MODES: &[&str] = &["SYN_ACK", "SYN", "ACK"];
const RECEIVERS: &[&str] = &["ISG_DIAG_BED", "DIAG", "HMI", "PLC", "EVENT_LOGGER"];

type Res<'a, T> = Result<(&'a str, T), nom::Err<PErr<'a>>>;

/// `#MSG SYN` and `#MSG SYN_ACK`: output "synchronous with processing state in interpolator",
/// when execution reaches the block; without a mode, or with `ACK`, right after decoding
/// (TF5200 programming manual, "Programming a message (#MSG)"). No receiver acknowledges
/// here, so `SYN_ACK` goes on at once as `SYN` does and `ACK` as the default.
pub(crate) fn synchronous(m: &Message) -> bool {
    m.options.iter().any(|o| o.starts_with("SYN"))
}

/// `#MSG …` after the keyword `MSG` (and its blanks).
pub(crate) fn parse_msg<'a>(ctx: &Ctx<'a>, i: &'a str) -> Res<'a, Command> {
    let (r, options) = options(i)?;
    if !r.starts_with('[') {
        return fail(r, SYNTAX, "#MSG takes [\"text\", values…]");
    }
    let (rest, (text, quoted, args)) = match quoted_body(ctx, r)? {
        Some(b) => b,
        None => {
            let (rest, text) = verbatim_options(r, r)?;
            (rest, (text, false, Vec::new()))
        }
    };
    Ok((
        rest,
        Command::Msg(Box::new(Message {
            options,
            text,
            quoted,
            args,
        })),
    ))
}

/// The keywords before the bracket, each checked against its place.
fn options(mut i: &str) -> Res<'_, Vec<&'static str>> {
    let mut out: Vec<&'static str> = Vec::new();
    let (mut mode, mut receiver) = (false, false);
    while i.as_bytes().first().is_some_and(u8::is_ascii_alphabetic) {
        let save = out.first() == Some(&"SAVE");
        let first: &[&'static str] = if out.is_empty() {
            &["SAVE", "INFO"]
        } else {
            &[]
        };
        let allowed = first
            .iter()
            .chain(if save { SAVE_OPTIONS } else { &[] })
            .chain(if save || mode { &[] } else { MODES })
            .chain(if save || receiver { &[] } else { RECEIVERS });
        let Some((kw, r)) = allowed
            .copied()
            .find_map(|kw| keyword(i, kw).map(|r| (kw, r)))
            .filter(|(kw, _)| !out.contains(kw))
        else {
            return fail(
                i,
                SYNTAX,
                "#MSG option expected (SAVE, INFO, EXCLUSIVE, CONTINUE, a mode or a receiver)",
            );
        };
        mode |= MODES.contains(&kw);
        receiver |= RECEIVERS.contains(&kw);
        out.push(kw);
        i = ws(r);
    }
    Ok((i, out))
}

type Body = (String, bool, Vec<Expr>);

/// `["text", v1, v2]`: the quoted text and its values, the format checked against them.
/// `None` when the bracket does not hold one quoted string followed by `,` or `]` (a text
/// kept verbatim, as before formatting existed).
fn quoted_body<'a>(
    ctx: &Ctx<'a>,
    i: &'a str,
) -> Result<Option<(&'a str, Body)>, nom::Err<PErr<'a>>> {
    let Some(q) = ws(&i[1..]).strip_prefix('"') else {
        return Ok(None);
    };
    let Some(end) = q.find('"') else {
        return Ok(None);
    };
    let text = &q[..end];
    let mut r = ws(&q[end + 1..]);
    if !r.starts_with([',', ']']) {
        return Ok(None);
    }
    let elements = format_elements(q, end)?;
    let mut args = Vec::new();
    loop {
        if let Some(rest) = r.strip_prefix(']') {
            if args.len() < elements {
                return Err(perr(r, MSG_ARG_COUNT, count_msg(elements, args.len())));
            }
            return Ok(Some((rest, (text.to_string(), true, args))));
        }
        let Some(after) = r.strip_prefix(',') else {
            return Err(perr(r, SYNTAX, "`,` or `]` expected in #MSG"));
        };
        let at = ws(after);
        if at.is_empty() || at.starts_with([',', ']']) {
            return Err(perr(
                at,
                MSG_NO_VALUE,
                "after a comma a value (expression) is expected",
            ));
        }
        if args.len() == elements {
            return Err(perr(at, MSG_ARG_COUNT, count_msg(elements, elements + 1)));
        }
        let (rest, e) = ctx.expr(at)?;
        args.push(e);
        r = ws(rest);
    }
}

fn count_msg(elements: usize, values: usize) -> String {
    format!("#MSG text has {elements} format element(s) but {values} value(s) are programmed")
}

/// One format element of a text: `%[flags][width][.precision]conversion`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Spec {
    left: bool,
    plus: bool,
    space: bool,
    zero: bool,
    width: usize,
    precision: Option<usize>,
    /// Upper-case conversion letter: `S`, `D` or `F`; `%` for `%%`.
    conv: u8,
}

/// The element starting at `t` (just after its `%`) and its length, or `None` if unknown.
fn spec(t: &[u8]) -> Option<(Spec, usize)> {
    let mut s = Spec {
        left: false,
        plus: false,
        space: false,
        zero: false,
        width: 0,
        precision: None,
        conv: b'%',
    };
    let mut k = 0;
    if t.first() == Some(&b'%') {
        return Some((s, 1));
    }
    while let Some(&f) = t.get(k) {
        match f {
            b'-' => s.left = true,
            b'+' => s.plus = true,
            b' ' => s.space = true,
            b'0' => s.zero = true,
            b'#' => {}
            _ => break,
        }
        k += 1;
    }
    let digits = |k: usize| t[k..].iter().take_while(|b| b.is_ascii_digit()).count();
    let n = digits(k);
    if n > 2 {
        return None;
    }
    s.width = t[k..k + n]
        .iter()
        .fold(0, |a, d| a * 10 + usize::from(d - b'0'));
    k += n;
    if t.get(k) == Some(&b'.') {
        k += 1;
        let n = digits(k);
        if n > 2 {
            return None;
        }
        s.precision = Some(
            t[k..k + n]
                .iter()
                .fold(0, |a, d| a * 10 + usize::from(d - b'0')),
        );
        k += n;
    }
    let conv = t.get(k)?.to_ascii_uppercase();
    if !matches!(conv, b'S' | b'D' | b'F') {
        return None;
    }
    s.conv = conv;
    Some((s, k + 1))
}

/// How many values the text `line[..len]` asks for (`line` runs on to the end of the line,
/// for the error's column); an unknown element is 21232 at its `%`, more than
/// [`MAX_MSG_VALUES`] 20724.
fn format_elements(line: &str, len: usize) -> Result<usize, nom::Err<PErr<'_>>> {
    let text = &line[..len];
    let b = text.as_bytes();
    let mut k = 0;
    let mut n = 0usize;
    while let Some(p) = b[k..].iter().position(|&c| c == b'%') {
        let at = k + p;
        let Some((s, len)) = spec(&b[at + 1..]) else {
            let end = text[at + 1..]
                .find(|c: char| c.is_ascii_alphabetic() || c == ' ')
                .map_or(text.len(), |e| at + 2 + e)
                .min(text.len());
            let shown: String = text[at..end].chars().take(8).collect();
            return Err(perr(
                &line[at..],
                MSG_UNKNOWN_FORMAT,
                format!("unknown format string {shown} (allowed: %s %S %d %D %f %F)"),
            ));
        };
        if s.conv != b'%' {
            n += 1;
            if n > MAX_MSG_VALUES {
                return Err(perr(
                    &line[at..],
                    MSG_TOO_MANY_VALUES,
                    format!("too many format elements in the message (limit {MAX_MSG_VALUES})"),
                ));
            }
        }
        k = at + 1 + len;
    }
    Ok(n)
}

/// Why a message could not be formatted.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum MessageError {
    /// The formatted text would exceed [`MAX_MSG_CHARS`] (900136).
    #[error("formatted #MSG text longer than {MAX_MSG_CHARS} characters")]
    TooLong,
    /// A string value for a `%d` or `%f` element (1-based value number; 900008).
    #[error("#MSG value {0} is a string, but its format element takes a number")]
    StringAsNumber(usize),
}

impl MessageError {
    /// The error id (`super::codes`).
    pub fn code(&self) -> u32 {
        match self {
            MessageError::TooLong => super::codes::MSG_TOO_LONG,
            MessageError::StringAsNumber(_) => super::codes::EVAL_STRING_AS_NUMBER,
        }
    }
}

/// The message text with `values` in place of its format elements, as `printf` writes them:
/// `%d` the value truncated toward zero, `%f` with 6 decimals unless a precision is given,
/// `%s` a string as it is and a number in its shortest form (precision cuts either). A
/// text kept verbatim (not a quoted string) is returned as it is.
pub(crate) fn format_message(m: &Message, values: &[Val]) -> Result<String, MessageError> {
    if !m.quoted {
        return Ok(m.text.clone());
    }
    let text = m.text.as_str();
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len().min(MAX_MSG_CHARS));
    let mut values = values.iter();
    let mut used = 0;
    let mut k = 0;
    while let Some(p) = b[k..].iter().position(|&c| c == b'%') {
        push(&mut out, &text[k..k + p])?;
        let at = k + p;
        let Some((s, len)) = spec(&b[at + 1..]) else {
            // The parser refused unknown elements; kept literally should one get here.
            push(&mut out, "%")?;
            k = at + 1;
            continue;
        };
        if s.conv == b'%' {
            push(&mut out, "%")?;
        } else {
            used += 1;
            match values.next() {
                Some(Val::Str(t)) if s.conv == b'S' => push(&mut out, &text_field(s, t))?,
                Some(Val::Str(_)) => return Err(MessageError::StringAsNumber(used)),
                Some(Val::Num(v)) => push(&mut out, &field(s, *v))?,
                None => push(&mut out, &field(s, 0.0))?,
            }
        }
        k = at + 1 + len;
    }
    push(&mut out, &text[k..])?;
    Ok(out)
}

fn push(out: &mut String, s: &str) -> Result<(), MessageError> {
    if out.len() + s.len() > MAX_MSG_CHARS {
        return Err(MessageError::TooLong);
    }
    out.push_str(s);
    Ok(())
}

/// One value as its element asks. Width and precision are at most 99, so a field is at
/// most a few hundred characters (the digits of the largest `f64` and 99 decimals).
fn field(s: Spec, v: f64) -> String {
    let v = if v.is_finite() { v } else { 0.0 };
    let (neg, body) = match s.conv {
        b'D' => {
            // C's conversion of a double to an integer: toward zero.
            let i = v.trunc();
            let digits = format!("{}", i.abs());
            let min = s.precision.unwrap_or(1).min(MAX_FIELD);
            let digits = if digits.len() < min {
                format!("{}{digits}", "0".repeat(min - digits.len()))
            } else {
                digits
            };
            (i < 0.0, digits)
        }
        b'F' => {
            let p = s.precision.unwrap_or(6).min(MAX_FIELD);
            let body = format!("{:.*}", p, v.abs());
            // `-0.000` prints as C does only for a value below zero that rounds to it.
            (v < 0.0, body)
        }
        _ => {
            let mut body = format!("{v}");
            if let Some(p) = s.precision {
                body.truncate(p);
            }
            return pad(s, String::new(), body, false);
        }
    };
    let sign = if neg {
        "-"
    } else if s.plus {
        "+"
    } else if s.space {
        " "
    } else {
        ""
    };
    // With a precision, `%d` pads with blanks, not zeros (C).
    let zero = s.zero && !(s.conv == b'D' && s.precision.is_some());
    pad(s, sign.to_string(), body, zero)
}

/// A string for `%s`: a precision keeps that many characters, a width pads.
fn text_field(s: Spec, t: &str) -> String {
    let body = match s.precision {
        Some(p) => t.chars().take(p).collect(),
        None => t.to_string(),
    };
    pad(s, String::new(), body, false)
}

fn pad(s: Spec, sign: String, body: String, zero: bool) -> String {
    let len = sign.chars().count() + body.chars().count();
    let fill = s.width.min(MAX_FIELD).saturating_sub(len);
    if s.left {
        format!("{sign}{body}{}", " ".repeat(fill))
    } else if zero {
        format!("{sign}{}{body}", "0".repeat(fill))
    } else {
        format!("{}{sign}{body}", " ".repeat(fill))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(text: &str) -> Message {
        Message {
            options: Vec::new(),
            text: text.to_string(),
            quoted: true,
            args: Vec::new(),
        }
    }

    fn f(text: &str, v: &[f64]) -> String {
        let v: Vec<Val> = v.iter().map(|&x| Val::Num(x)).collect();
        format_message(&msg(text), &v).unwrap()
    }

    #[test]
    fn elements_format_as_printf_does() {
        assert_eq!(f("P1= %f", &[2.5]), "P1= 2.500000");
        assert_eq!(f("%d|%D", &[7.9, -7.9]), "7|-7");
        assert_eq!(
            f("%5.2f|%-6d|%06.1F", &[3.14659, 42.0, -2.25]),
            " 3.15|42    |-002.2"
        );
        assert_eq!(f("%s %S", &[0.5, 3.0]), "0.5 3");
        assert_eq!(f("%+d % d %.3d", &[5.0, 5.0, 5.0]), "+5  5 005");
        assert_eq!(f("100%% done", &[]), "100% done");
        let s = |t: &str| Val::Str(t.to_string());
        assert_eq!(
            format_message(
                &msg("[%s|%5s|%-4S|%.2s]"),
                &[s("ab"), s("ab"), s("ab"), s("abc")]
            ),
            Ok("[ab|   ab|ab  |ab]".to_string())
        );
        assert_eq!(
            format_message(&msg("%s %d"), &[s("a"), s("b")]),
            Err(MessageError::StringAsNumber(2))
        );
    }

    #[test]
    fn elements_are_counted_and_unknown_ones_refused() {
        let t = "a %d b %5.1f %% %s";
        assert_eq!(format_elements(t, t.len()).ok(), Some(3));
        let code = |t: &str| match format_elements(t, t.len()) {
            Err(nom::Err::Failure(e)) => e.code,
            other => panic!("{other:?}"),
        };
        assert_eq!(code("%x"), MSG_UNKNOWN_FORMAT);
        assert_eq!(code("%123f"), MSG_UNKNOWN_FORMAT);
        assert_eq!(code("%"), MSG_UNKNOWN_FORMAT);
        assert_eq!(code(&"%d".repeat(MAX_MSG_VALUES + 1)), MSG_TOO_MANY_VALUES);
    }

    #[test]
    fn the_formatted_length_is_bounded() {
        let text = "%99.99f".repeat(MAX_MSG_VALUES);
        let v = vec![Val::Num(1e300); MAX_MSG_VALUES];
        assert_eq!(format_message(&msg(&text), &v), Err(MessageError::TooLong));
        assert_eq!(f(&"%99d".repeat(40), &[1.0; 40]).len(), 3960);
    }
}
