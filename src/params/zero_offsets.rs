//! The zero-offset list: the offsets G54 … G59 select, per axis, in the kernel's list format
//! (`np_grp[i].achse[j].versch`, P-ZERO-00003; `np_grp[i].achse[j].inaktiv`, P-ZERO-00004).
//!
//! Group `i` is the kernel's numbering (TF5200 "Zero offset group (np_grp[i].*)"): 0 is the
//! G53 data set (G159 = 0), 1 … 6 are G54 … G59 (G159 = 1 … 6), as `V.G.NP[i]` numbers them
//! in a program and over ADS. G53 deselects every offset (the kernel's default,
//! P-ZERO-00001 `g53_verfuegbar` 0), so group 0's entries are kept with a warning. Axis `j`
//! is the channel axis index in X Y Z A B C order. Offsets are whole numbers in the kernel's
//! position unit: 0.1 µm for linear axes, 0.0001° for rotary axes (`100000` = 10 mm). The
//! start-up list names the file with `nullp_data[i] <file>` (P-STUP-00011, channel i), or
//! ncchannel's older `zero_offset_list <file>` (every channel) / `zero_offset_list[i] <file>`.

use std::path::Path;

use super::catalog::{ListKind, ListSummary, Tally};
use super::list::{read_list, Entry, ParamList, ValueKind};
use super::startup::{shape, warn_duplicates};
use crate::diag::Diagnostic;
use crate::vocab::axis::MAX_AXES;

/// Zero-offset groups the emulator selects: G54 … G59, the list's groups 1 … 6.
pub(crate) const GROUPS: usize = 6;
/// Groups and axes the kernel's list may name (more groups exist for G159; 32 axes a channel):
/// accepted with a warning, not used.
const MAX_LIST_GROUPS: u32 = 100;
const MAX_LIST_AXES: u32 = 32;
/// mm per list unit (0.1 µm).
pub(crate) const MM_PER_UNIT: f64 = 1e-4;

/// Offsets by row (G54 = row 0, the list's group 1) and axis, mm (degrees for rotary axes).
pub(crate) type ZeroOffsetTable = [[f64; MAX_AXES]; GROUPS];

/// Does this list look like a zero-offset list? (It names `np_grp[…]`.)
pub(crate) fn is_zero_offset_list(list: &ParamList) -> bool {
    list.entries.iter().any(|e| {
        e.name
            .segments
            .first()
            .is_some_and(|s| s.ident == "np_grp" && s.index.is_some())
    })
}

/// Read and check a zero-offset list. `Err` when the file cannot be read; entry problems go to
/// `diags` (the table then holds the good entries).
pub(crate) fn read_zero_offsets(
    path: &Path,
    diags: &mut Vec<Diagnostic>,
) -> Result<(ZeroOffsetTable, ListSummary), Diagnostic> {
    let (list, errs) = read_list(path)?;
    diags.extend(errs);
    Ok(interpret_zero_offsets(&list, diags))
}

/// Check a parsed zero-offset list.
pub(crate) fn interpret_zero_offsets(
    list: &ParamList,
    diags: &mut Vec<Diagnostic>,
) -> (ZeroOffsetTable, ListSummary) {
    warn_duplicates(list, diags);
    let mut tally = Tally::new(ListKind::ZeroOffsets);
    let mut offsets = [[0.0; MAX_AXES]; GROUPS];
    let mut inactive = [[false; MAX_AXES]; GROUPS];
    for e in &list.entries {
        let (i, j, field) = match shape(e).as_slice() {
            [("np_grp", Some(i)), ("achse", Some(j)), (f @ ("versch" | "inaktiv"), None)] => {
                (*i, *j, *f)
            }
            _ => {
                tally.not_read(list, e, diags);
                continue;
            }
        };
        if i >= MAX_LIST_GROUPS || j >= MAX_LIST_AXES {
            diags.push(list.error_at(
                e,
                e.name_pos,
                format!(
                    "{}: group index must be below {MAX_LIST_GROUPS} and axis index below \
                     {MAX_LIST_AXES}",
                    e.name.text
                ),
            ));
            continue;
        }
        let value = match int_value(list, e) {
            Ok(v) => v,
            Err(d) => {
                diags.push(d);
                continue;
            }
        };
        if i == 0 {
            diags.push(list.warning_at(
                e,
                e.name_pos,
                format!(
                    "{}: kept, but group 0 is G53, which deselects every offset \
                     (P-ZERO-00001 g53_verfuegbar 0); G54 is np_grp[1]",
                    e.name.text
                ),
            ));
            tally.kept_unused();
            continue;
        }
        if i as usize > GROUPS || j as usize >= MAX_AXES {
            diags.push(list.warning_at(
                e,
                e.name_pos,
                format!(
                    "{}: kept, but the emulator selects only np_grp[1..6] (G54 … G59) on the \
                     axes X Y Z A B C (achse[0..5])",
                    e.name.text
                ),
            ));
            tally.kept_unused();
            continue;
        }
        // The list's group 1 (G54) is row 0.
        let (i, j) = (i as usize - 1, j as usize);
        match field {
            "versch" => offsets[i][j] = value as f64 * MM_PER_UNIT,
            _ => match value {
                0 | 1 => inactive[i][j] = value == 1,
                v => diags.push(list.error_at(
                    e,
                    e.value_pos,
                    format!("{}: must be 0 or 1 (found {v})", e.name.text),
                )),
            },
        }
    }
    for (g, row) in offsets.iter_mut().enumerate() {
        for (a, v) in row.iter_mut().enumerate() {
            if inactive[g][a] {
                *v = 0.0;
            }
        }
    }
    (offsets, tally.finish(list))
}

/// A signed 32-bit whole number (the kernel's SGN32), decimal or `0x…`.
pub(crate) fn int_value(list: &ParamList, e: &Entry) -> Result<i64, Diagnostic> {
    let v = match e.value.kind {
        ValueKind::Int(v) => v,
        ValueKind::Hex(v) => i64::try_from(v).unwrap_or(i64::MAX),
        ValueKind::Float(_) => {
            return Err(list.error_at(
                e,
                e.value_pos,
                format!(
                    "{}: must be a whole number in 0.1 µm (found {}; 10 mm is 100000)",
                    e.name.text, e.value.text
                ),
            ))
        }
        ValueKind::Ref(_) => return Err(super::value::unresolved(list, e)),
        ValueKind::Word | ValueKind::Quoted => {
            return Err(list.error_at(
                e,
                e.value_pos,
                format!(
                    "{}: expected a number, found `{}`",
                    e.name.text, e.value.text
                ),
            ))
        }
    };
    if v < i64::from(i32::MIN) || v > i64::from(i32::MAX) {
        return Err(list.error_at(
            e,
            e.value_pos,
            format!("{}: {v} is outside the 32-bit range", e.name.text),
        ));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::list::parse_list;

    fn read(text: &str) -> (ZeroOffsetTable, Vec<Diagnostic>) {
        let (t, d, _) = read_counted(text);
        (t, d)
    }

    fn read_counted(text: &str) -> (ZeroOffsetTable, Vec<Diagnostic>, ListSummary) {
        let (list, errs) = parse_list(Path::new("np.lis"), text);
        assert!(errs.is_empty(), "{errs:?}");
        let mut d = Vec::new();
        let (t, s) = interpret_zero_offsets(&list, &mut d);
        (t, d, s)
    }

    #[test]
    fn offsets_in_tenths_of_a_micron_by_group_and_axis() {
        let (t, d) = read(
            "np_grp[1].achse[0].versch 100000\n\
             np_grp[1].achse[1].versch -25000\n\
             np_grp[6].achse[2].versch 0x10\n\
             np_grp[2].achse[0].versch 50000\n\
             np_grp[2].achse[0].inaktiv 1\n",
        );
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(t[0][0], 10.0, "group 1 is G54");
        assert_eq!(t[0][1], -2.5);
        assert!((t[5][2] - 0.0016).abs() < 1e-12, "group 6 is G59");
        assert_eq!(t[1][0], 0.0, "inaktiv switches the offset off");
    }

    #[test]
    fn bad_values_name_the_parameter_and_column() {
        let (_, d) = read("np_grp[1].achse[0].versch 1.5\nnp_grp[1].achse[0].inaktiv 2\n");
        assert_eq!(d.len(), 2, "{d:?}");
        assert!(d[0].message.contains("whole number"), "{}", d[0].message);
        assert_eq!((d[0].line, d[0].col), (1, 27));
        assert!(d[1].message.contains("0 or 1"));
    }

    #[test]
    fn the_g53_group_unknown_and_unused_entries_warn() {
        let (t, d, s) = read_counted(
            "np_grp[0].achse[0].versch 70000\nnp_grp[7].achse[0].versch 1\nfoo 1\n\
             np_grp[1].achse[0].versch 5\n",
        );
        // Known but not used: inert; `foo`: unknown.
        assert_eq!((s.counts.used, s.counts.inert, s.counts.unknown), (1, 2, 1));
        assert_eq!(d.len(), 3);
        assert!(d[0].message.contains("G53"), "{}", d[0].message);
        assert!(d
            .iter()
            .all(|x| x.severity == crate::diag::Severity::Warning));
        // Only G54's X (5 × 0.1 µm) is set: group 0 did not become G54.
        assert_eq!(t[0][0], 0.0005);
        assert_eq!(t.iter().flatten().filter(|v| **v != 0.0).count(), 1);
    }
}
