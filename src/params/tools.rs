//! The tool list: the radius of each tool data set the D word selects, for tool radius
//! compensation (G41/G42), in the ISG list style of the other lists (`name value`, `#`
//! comments) and the kernel's length unit, 0.1 µm:
//!
//! ```text
//! # D1: radius 5 mm; D2: radius 2.5 mm
//! wz[1].radius   50000
//! wz[2].radius   25000
//! ```
//!
//! It is read at start-up from `tools.lis` next to the start-up list, if present (none: only
//! D0, radius 0, exists). Bad entries are errors with file, line and column.

use std::path::Path;

use super::catalog::{ListKind, ListSummary, Tally};
use super::list::{read_list, ParamList};
use super::startup::{shape, warn_duplicates};
use super::zero_offsets::{int_value, MM_PER_UNIT};
use crate::diag::Diagnostic;

/// The tool list's file name, in the start-up list's folder.
pub(crate) const TOOLS_FILE: &str = "tools.lis";
/// Highest D number accepted.
pub(crate) const MAX_TOOL: u32 = 10_000;

/// Radius by D number, mm, sorted by D.
pub(crate) type ToolRadii = Vec<(u32, f64)>;

/// Does this list look like a tool list? (It names `wz[…]`.)
pub(crate) fn is_tool_list(list: &ParamList) -> bool {
    list.entries.iter().any(|e| {
        e.name
            .segments
            .first()
            .is_some_and(|s| s.ident == "wz" && s.index.is_some())
    })
}

/// Read and check a tool list. `Err` when the file cannot be read; entry problems go to
/// `diags`.
pub(crate) fn read_tools(
    path: &Path,
    diags: &mut Vec<Diagnostic>,
) -> Result<(ToolRadii, ListSummary), Diagnostic> {
    let (list, errs) = read_list(path)?;
    diags.extend(errs);
    Ok(interpret_tools(&list, diags))
}

/// Check a parsed tool list.
pub(crate) fn interpret_tools(
    list: &ParamList,
    diags: &mut Vec<Diagnostic>,
) -> (ToolRadii, ListSummary) {
    warn_duplicates(list, diags);
    let mut tally = Tally::new(ListKind::Tools);
    let mut out: ToolRadii = Vec::new();
    for e in &list.entries {
        let d = match shape(e).as_slice() {
            [("wz", Some(d)), ("radius", None)] => *d,
            _ => {
                tally.not_read(list, e, diags);
                continue;
            }
        };
        if d == 0 || d > MAX_TOOL {
            diags.push(list.error_at(
                e,
                e.name_pos,
                format!("{}: D number must be 1 … {MAX_TOOL}", e.name.text),
            ));
            continue;
        }
        match int_value(list, e) {
            Ok(v) if v >= 0 => {
                out.retain(|(n, _)| *n != d);
                out.push((d, v as f64 * MM_PER_UNIT));
            }
            Ok(v) => diags.push(list.error_at(
                e,
                e.value_pos,
                format!("{}: a radius cannot be negative (found {v})", e.name.text),
            )),
            Err(diag) => diags.push(diag),
        }
    }
    out.sort_by_key(|(d, _)| *d);
    (out, tally.finish(list))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::list::parse_list;

    #[test]
    fn radii_in_tenths_of_a_micron_by_d_number() {
        let (list, errs) = parse_list(
            Path::new("tools.lis"),
            "wz[2].radius 25000\nwz[1].radius 50000\nwz[3].radius -1\nwz[0].radius 5\n",
        );
        assert!(errs.is_empty());
        let mut d = Vec::new();
        let (t, _) = interpret_tools(&list, &mut d);
        assert!(is_tool_list(&list));
        assert_eq!(t, vec![(1, 5.0), (2, 2.5)]);
        assert_eq!(d.len(), 2, "{d:?}");
    }
}
