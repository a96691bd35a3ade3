//! The tool list: the tool data each D number selects (TF5200 "Tool data", `wz[i].*`), in the
//! kernel's list format and length unit, 0.1 µm:
//!
//! ```text
//! wz[1].gueltig        1        # P-TOOL-00005 validity flag: the data may be used
//! wz[1].radius         50000    # P-TOOL-00004 radius 5 mm (G41/G42)
//! wz[1].laenge         600000   # P-TOOL-00003 length 60 mm (on the tool axis, Z under G17)
//! wz[1].ax_versatz[0]  10000    # P-TOOL-00006 offset 1 mm on the channel's first axis
//! ```
//!
//! The start-up list names the file with `werkz_data[i]` (P-STUP-00010, channel i). Without
//! one, `tools.lis` next to the start-up list is read, ncchannel's own older file: there a
//! data set is valid unless it says `gueltig 0` (the file has radii only); in a kernel list
//! the validity flag defaults to 0 as in the kernel, so a data set without `gueltig 1` is
//! invalid and selecting it is refused. Bad entries are errors with file, line and column.

use std::path::Path;

use super::catalog::{ListKind, ListSummary, Tally};
use super::list::{read_list, ParamList};
use super::startup::{shape, warn_duplicates};
use super::zero_offsets::{int_value, MM_PER_UNIT};
use crate::diag::Diagnostic;
use crate::vocab::axis::MAX_AXES;

/// ncchannel's own tool file name, in the start-up list's folder (read when the start-up list
/// names no `werkz_data[i]`).
pub(crate) const TOOLS_FILE: &str = "tools.lis";
/// Highest D number accepted.
pub(crate) const MAX_TOOL: u32 = 10_000;
/// Axis offsets a tool may name (P-TOOL-00006: `ax_versatz[j]`, j = 0 … 31).
const MAX_LIST_AXES: u32 = 32;

/// One tool data set (TF5200 "Tool data"), mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolData {
    /// The D number selecting it (the list's index `i` of `wz[i]`).
    pub d: u32,
    /// `wz[i].radius` (P-TOOL-00004), mm.
    pub radius_mm: f64,
    /// `wz[i].laenge` (P-TOOL-00003), mm: added on the tool axis (Z under G17, Y under G18,
    /// X under G19).
    pub length_mm: f64,
    /// `wz[i].gueltig` (P-TOOL-00005): the data may be used.
    pub valid: bool,
    /// `wz[i].ax_versatz[j]` (P-TOOL-00006) on the channel's axes X Y Z A B C, mm (degrees on
    /// rotary axes).
    pub axis_offsets_mm: [f64; MAX_AXES],
}

impl ToolData {
    fn new(d: u32, valid: bool) -> Self {
        ToolData {
            d,
            radius_mm: 0.0,
            length_mm: 0.0,
            valid,
            axis_offsets_mm: [0.0; MAX_AXES],
        }
    }
}

/// Tool data by D number, sorted by D (looked up by binary search).
pub type ToolTable = Vec<ToolData>;

/// Which format a tool list is read in: the validity flag's default differs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ToolFormat {
    /// A list the start-up list names (`werkz_data[i]`): `gueltig` defaults to 0.
    Kernel,
    /// `tools.lis`: a data set is valid unless it says `gueltig 0`.
    Ncchannel,
}

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
    format: ToolFormat,
    diags: &mut Vec<Diagnostic>,
) -> Result<(ToolTable, ListSummary), Diagnostic> {
    let (list, errs) = read_list(path)?;
    diags.extend(errs);
    Ok(interpret_tools(&list, format, diags))
}

/// The field of `wz[i]` an entry sets.
enum Field {
    Radius,
    Length,
    Valid,
    AxisOffset(u32),
    Unit,
}

/// Check a parsed tool list.
pub(crate) fn interpret_tools(
    list: &ParamList,
    format: ToolFormat,
    diags: &mut Vec<Diagnostic>,
) -> (ToolTable, ListSummary) {
    warn_duplicates(list, diags);
    let mut tally = Tally::new(ListKind::Tools);
    let mut out: std::collections::BTreeMap<u32, ToolData> = Default::default();
    for e in &list.entries {
        let (d, field) = match shape(e).as_slice() {
            [("wz", Some(d)), ("radius", None)] => (*d, Field::Radius),
            [("wz", Some(d)), ("laenge", None)] => (*d, Field::Length),
            [("wz", Some(d)), ("gueltig", None)] => (*d, Field::Valid),
            [("wz", Some(d)), ("ax_versatz", Some(j))] => (*d, Field::AxisOffset(*j)),
            [("wz", Some(d)), ("mass_einheit", None)] => (*d, Field::Unit),
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
        let v = match int_value(list, e) {
            Ok(v) => v,
            Err(diag) => {
                diags.push(diag);
                continue;
            }
        };
        let tool = out
            .entry(d)
            .or_insert_with(|| ToolData::new(d, format == ToolFormat::Ncchannel));
        let bad = |what: &str| list.error_at(e, e.value_pos, format!("{}: {what}", e.name.text));
        match field {
            Field::Radius if v < 0 => {
                diags.push(bad(&format!("a radius cannot be negative (found {v})")))
            }
            Field::Radius => tool.radius_mm = v as f64 * MM_PER_UNIT,
            Field::Length => tool.length_mm = v as f64 * MM_PER_UNIT,
            Field::Valid => match v {
                0 | 1 => tool.valid = v == 1,
                _ => diags.push(bad(&format!("must be 0 or 1 (found {v})"))),
            },
            Field::AxisOffset(j) if j >= MAX_LIST_AXES => diags.push(list.error_at(
                e,
                e.name_pos,
                format!(
                    "{}: axis index must be below {MAX_LIST_AXES} (P-TOOL-00006)",
                    e.name.text
                ),
            )),
            Field::AxisOffset(j) => match tool.axis_offsets_mm.get_mut(j as usize) {
                Some(o) => *o = v as f64 * MM_PER_UNIT,
                None => {
                    diags.push(list.warning_at(
                        e,
                        e.name_pos,
                        format!(
                            "{}: kept, but the emulator's axes are X Y Z A B C \
                             (ax_versatz[0..5])",
                            e.name.text
                        ),
                    ));
                    tally.kept_unused();
                }
            },
            // P-TOOL-00008: 0 = the list's unit is 0.1 µm; inch tool data is not modelled.
            Field::Unit if v == 0 => {}
            Field::Unit => diags.push(bad(&format!(
                "only 0 (0.1 µm) is modelled; inch tool data (1) is not (found {v})"
            ))),
        }
    }
    // Sorted by D: the decoder looks data sets up by binary search.
    (out.into_values().collect(), tally.finish(list))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::list::parse_list;

    fn read(text: &str, format: ToolFormat) -> (ToolTable, Vec<Diagnostic>, ListSummary) {
        let (list, errs) = parse_list(Path::new("werkz.lis"), text);
        assert!(errs.is_empty(), "{errs:?}");
        let mut d = Vec::new();
        let (t, s) = interpret_tools(&list, format, &mut d);
        assert!(is_tool_list(&list));
        (t, d, s)
    }

    #[test]
    fn radii_in_tenths_of_a_micron_by_d_number() {
        let (t, d, _) = read(
            "wz[2].radius 25000\nwz[1].radius 50000\nwz[3].radius -1\nwz[0].radius 5\n",
            ToolFormat::Ncchannel,
        );
        let r: Vec<(u32, f64, bool)> = t.iter().map(|t| (t.d, t.radius_mm, t.valid)).collect();
        assert_eq!(r, vec![(1, 5.0, true), (2, 2.5, true), (3, 0.0, true)]);
        assert_eq!(d.len(), 2, "{d:?}");
    }

    #[test]
    fn a_kernel_list_has_length_offsets_and_the_validity_flag_defaulting_to_0() {
        let (t, d, s) = read(
            "wz[5].laenge 600000\nwz[5].radius 200000\nwz[5].gueltig 1\n\
             wz[5].ax_versatz[3] -4080000\nwz[5].mass_einheit 0\nwz[6].radius 10000\n\
             wz[5].vb_max 3000000\n",
            ToolFormat::Kernel,
        );
        assert!(d.is_empty(), "{d:?}");
        assert_eq!((t[0].d, t[0].length_mm, t[0].radius_mm), (5, 60.0, 20.0));
        assert!(t[0].valid);
        assert_eq!(t[0].axis_offsets_mm[3], -408.0);
        assert!(!t[1].valid, "no gueltig 1: invalid, as in the kernel");
        assert_eq!((s.counts.used, s.counts.inert, s.counts.unknown), (6, 1, 0));
    }

    #[test]
    fn bad_fields_name_file_line_and_column() {
        let (_, d, s) = read(
            "wz[1].gueltig 2\nwz[1].mass_einheit 1\nwz[1].ax_versatz[40] 1\nwz[1].laenge 1.5\n\
             wz[1].ax_versatz[9] 1\nwz[1].farbe 3\n",
            ToolFormat::Kernel,
        );
        let at: Vec<(usize, usize, bool)> = d
            .iter()
            .map(|x| (x.line, x.col, x.severity == crate::diag::Severity::Error))
            .collect();
        assert_eq!(
            at,
            vec![
                (1, 15, true),
                (2, 20, true),
                (3, 1, true),
                (4, 14, true),
                (5, 1, false),
                (6, 1, false)
            ],
            "{d:?}"
        );
        assert!(d[0].message.contains("0 or 1"), "{}", d[0].message);
        // ax_versatz[9]: known, not used (inert); farbe: unknown.
        assert_eq!((s.counts.inert, s.counts.unknown), (1, 1));
    }
}
