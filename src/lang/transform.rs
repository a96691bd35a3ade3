//! The neutral forms of ISG's transformation commands: the ones that leave the path as it is,
//! accepted so the programs that write them run (TF5200 programming manual):
//!
//! - `#TRAFO OFF`, `#TRAFO [OFF]`, `#TRAFO [NONE, NONE]` ("Combined preselection and
//!   activation": OFF deactivates a step, NONE deselects its kinematic);
//! - `#KIN ID [NONE]`, `#KIN ID [NONE, NONE]` ("Separate preselection and activation": NONE
//!   deselects the kinematic ID);
//! - `#CS OFF`, `#CS OFF ALL` ("Definition of a machining coordinate system (CS)": deselection);
//! - `#CS DEF [id] [v1,v2,v3,φ1,φ2,φ3]`, `#CS ON [id] [..]`, `#CS ON [id]`, `#CS ON`: a
//!   coordinate system whose shift and angles are all 0, defined and selected. The values are
//!   expressions; the decoder evaluates them and refuses a CS that would move the path.
//!
//! Every other form (`#TRAFO ON`, a kinematic ID, `#CS ADD`, …) stays refused by name
//! ([`super::dialect`]).

use super::block::{Command, Expr, Transform};
use super::codes::{SYNTAX, UNSUPPORTED};
use super::expr::{fail, keyword, ws, Ctx, PResult};

/// Most values a `#CS` bracket holds: the three shifts and the three angles.
const CS_VALUES: usize = 6;

/// `#TRAFO`, `#KIN` or `#CS` (`kw`) at `i` (its `#`), `r` after the keyword: the neutral form
/// as a [`Command::Transform`], or `None` for any other form.
#[cold]
pub(crate) fn neutral<'a>(
    ctx: &Ctx<'a>,
    i: &'a str,
    kw: &[u8],
    r: &'a str,
) -> Option<PResult<'a, Command>> {
    let text = |rest: &'a str| i[1..i.len() - rest.len()].trim_end().to_string();
    let off = |rest: &'a str| {
        Some(Ok((
            rest,
            Command::Transform(Box::new(Transform::Off { text: text(rest) })),
        )))
    };
    match kw {
        b"TRAFO" => {
            if let Some(rest) = keyword(r, "OFF") {
                return off(rest);
            }
            let rest = keywords_in_brackets(r, &["OFF", "NONE"])?;
            off(rest)
        }
        b"KIN" => {
            let rest = keywords_in_brackets(ws(keyword(r, "ID")?), &["NONE"])?;
            off(rest)
        }
        b"CS" => {
            if let Some(rest) = keyword(r, "OFF") {
                let rest = keyword(ws(rest), "ALL").unwrap_or(rest);
                return off(rest);
            }
            let (rest, select) = match keyword(r, "DEF") {
                Some(rest) => (rest, false),
                None => (keyword(r, "ON")?, true),
            };
            cs_definition(ctx, i, ws(rest), select, &text)
        }
        _ => None,
    }
}

/// `[K]` or `[K, K]` with each K one of `allowed`: the text after the bracket.
fn keywords_in_brackets<'a>(r: &'a str, allowed: &[&'static str]) -> Option<&'a str> {
    let mut r = ws(r.strip_prefix('[')?);
    for n in 0..2 {
        r = ws(allowed.iter().find_map(|k| keyword(r, k))?);
        if let Some(rest) = r.strip_prefix(']') {
            return Some(rest);
        }
        if n == 0 {
            r = ws(r.strip_prefix(',')?);
        }
    }
    None
}

/// After `#CS DEF` / `#CS ON` (`r`): an optional `[id]`, then (required after DEF) the
/// `[v1,…,φ3]` bracket; `#CS ON` alone or with its id selects a defined CS. `None` for any
/// other form (refused by name). A literal value other than 0 is refused here, so `check`
/// sees it; values computed from expressions are the decoder's to check.
fn cs_definition<'a>(
    ctx: &Ctx<'a>,
    i: &'a str,
    r: &'a str,
    select: bool,
    text: &dyn Fn(&'a str) -> String,
) -> Option<PResult<'a, Command>> {
    let mut brackets: Vec<Vec<Expr>> = Vec::new();
    let mut rest = r;
    while ws(rest).starts_with('[') && brackets.len() < 2 {
        let (k, list) = expr_list(ctx, ws(rest)).ok()?;
        brackets.push(list);
        rest = k;
    }
    let (id, values) = match brackets.as_mut_slice() {
        [] if select => (None, None),
        [one] if one.len() == 1 && select => (one.pop(), None),
        [values] if values.len() == CS_VALUES => (None, Some(std::mem::take(values))),
        [id, values] if id.len() == 1 && values.len() == CS_VALUES => {
            (id.pop(), Some(std::mem::take(values)))
        }
        _ => return None,
    };
    let t = text(rest);
    let command = match values {
        Some(values) => {
            if values
                .iter()
                .any(|v| matches!(v, Expr::Num(n) if *n != 0.0))
            {
                return Some(fail(i, UNSUPPORTED, not_identity(&t)));
            }
            Transform::CsDefine {
                text: t,
                id,
                values,
                select,
            }
        }
        None => Transform::CsSelect { text: t, id },
    };
    Some(Ok((rest, Command::Transform(Box::new(command)))))
}

/// The refusal of a coordinate system that would move the path (`text`: after `#`).
pub(crate) fn not_identity(text: &str) -> String {
    format!(
        "#{text}: a coordinate system with a shift or a rotation is not modelled by ncchannel \
         (only one whose six values are all 0)"
    )
}

/// `[e1, e2, …]`: at most [`CS_VALUES`] expressions.
fn expr_list<'a>(ctx: &Ctx<'a>, i: &'a str) -> PResult<'a, Vec<Expr>> {
    let mut r = &i[1..];
    let mut list = Vec::new();
    loop {
        let (k, e) = ctx.expr(ws(r))?;
        list.push(e);
        let k = ws(k);
        if let Some(k) = k.strip_prefix(']') {
            return Ok((k, list));
        }
        match k.strip_prefix(',') {
            Some(k) if list.len() < CS_VALUES => r = k,
            _ => return fail(k, SYNTAX, "`,` or `]` expected"),
        }
    }
}
