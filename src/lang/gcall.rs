//! Implicit subroutine calls with transfer parameters, `G805[-27.12, 28.955, 2.87]` (TF5200
//! programming manual, "Implicit subroutine calls (G80–G89/G800..)": "a maximum of 50
//! transfer parameters (mathematical expressions in REAL format) … separated by commas. Gaps
//! in the sequence must be marked by consecutive commas"; the subroutine reads them as
//! `@P1`, `@P2`, …). Which subroutine G800 + i calls is the channel list's
//! `g800_prog_file[i]` (P-CHAN-00187); the decoder looks it up.

use super::block::{Expr, GCall, Item};
use super::codes::SYNTAX;
use super::expr::{perr, ws, Ctx, PErr};

/// The implicit calls the parser reads a parameter bracket for.
pub const G_CALLS: std::ops::RangeInclusive<u32> = 800..=819;

/// Most transfer parameters of one call (the manual's 50).
pub(crate) const MAX_G_CALL_PARAMS: usize = 50;

/// After `G<g>` (not a fast-path G): for G800–G819 followed by `[`, the bracket as an
/// [`Item::GCall`] pushed onto `items` and the rest of the line; `None` otherwise.
pub(crate) fn g_call<'a>(
    ctx: &Ctx<'a>,
    rest: &'a str,
    g: u32,
    col: u32,
    items: &mut Vec<Item>,
) -> Result<Option<&'a str>, nom::Err<PErr<'a>>> {
    if !G_CALLS.contains(&g) {
        return Ok(None);
    }
    let Some(mut r) = ws(rest).strip_prefix('[') else {
        return Ok(None);
    };
    let mut args: Vec<Option<Expr>> = Vec::new();
    r = ws(r);
    if let Some(after) = r.strip_prefix(']') {
        items.push(Item::GCall(Box::new(GCall { g, args, col })));
        return Ok(Some(after));
    }
    loop {
        if args.len() == MAX_G_CALL_PARAMS {
            return Err(perr(
                r,
                SYNTAX,
                format!("G{g} takes at most {MAX_G_CALL_PARAMS} transfer parameters"),
            ));
        }
        if r.starts_with([',', ']']) {
            args.push(None);
        } else {
            let (after, e) = ctx.expr(r)?;
            args.push(Some(e));
            r = ws(after);
        }
        if let Some(after) = r.strip_prefix(']') {
            // Trailing gaps define nothing: `[1, ]` is `[1]`, one canonical form.
            while args.last().is_some_and(Option::is_none) {
                args.pop();
            }
            items.push(Item::GCall(Box::new(GCall { g, args, col })));
            return Ok(Some(after));
        }
        let Some(after) = r.strip_prefix(',') else {
            return Err(perr(
                r,
                SYNTAX,
                "`,` or `]` expected in the transfer parameters",
            ));
        };
        r = ws(after);
    }
}
