//! Axis lists (`achsmds1.lis` …, named by the start-up list's `achs_mds[i]`, P-STUP-00015,
//! over the default list `default_achs_mds`, P-STUP-00035): each axis's logical number, name,
//! type, software limits and dynamics, converted from the kernel's units to the axis table's.
//!
//! As the kernel builds an axis's data (TF5200 Axis parameter, "list interpretation at
//! start-up"): its built-in defaults, overlaid by the default list, overlaid by the axis's own
//! list. Only gear 0 (`getriebe[0]`) is read: ncchannel has no gear change.
//!
//! | entry | P number | kernel unit | axis table |
//! |---|---|---|---|
//! | `kopf.achs_nr` | P-AXIS-00016 | logical axis number | joins the channel's `log_achs_nr` |
//! | `kopf.log_achs_name` | P-AXIS-00297 | name | the axis name when the channel names none |
//! | `kenngr.achs_typ` | P-AXIS-00018 | 1 linear, 2 rotary, 4 spindle | linear or rotary |
//! | `kenngr.swe_pos` / `swe_neg` | P-AXIS-00178 / -00177 | 0.1 µm, 10⁻⁴ ° | mm, ° (× 10⁻⁴) |
//! | `getriebe[0].dynamik.vb_max` | P-AXIS-00212 | µm/s, 10⁻³ °/s | mm/min, °/min (× 0.06) |
//! | `getriebe[0].vb_eilgang` | P-AXIS-00209 | µm/s, 10⁻³ °/s | G0 rate, mm/min (× 0.06) |
//! | `getriebe[0].dynamik.a_max` | P-AXIS-00008 | mm/s², °/s² | mm/s², °/s² |
//! | `getriebe[0].slope_profil.tr_*` | P-AXIS-00195 … -00198 | µs | jerk = a_max / tr |
//! | `getriebe[0].dynamik.tr_min` | P-AXIS-00201 | µs | the shortest ramp time |

use std::path::PathBuf;

use std::path::Path;

use super::catalog::{self, ListKind, ListSummary, Tally};
use super::channel::ChannelList;
use super::list::{Entry, ParamList, ValueKind};
use super::runtime::{axis_index, is_axis_name, AxisConfig, AxisKind, RuntimeConfig};
use super::value::{number_value, unresolved};
use crate::diag::{Diagnostic, Severity};
use crate::vocab::axis::MAX_AXES;

/// mm (or °) per kernel position unit: 0.1 µm (P-AXIS-00178: 0.1 µm, 0.0001 °).
pub(crate) const MM_PER_POSITION_UNIT: f64 = 1e-4;
/// mm/min per kernel velocity unit: 1 µm/s = 0.06 mm/min (P-AXIS-00212: µm/s, 0.001 °/s).
pub(crate) const MM_PER_MIN_PER_VELOCITY_UNIT: f64 = 60.0 / 1000.0;
/// s per kernel ramp-time unit, µs (P-AXIS-00196).
pub(crate) const S_PER_RAMP_UNIT: f64 = 1e-6;

/// The kernel's built-in values of the entries read, used where no list sets one.
/// P-AXIS-00212 vb_max, µm/s.
pub(crate) const DEFAULT_VB_MAX: f64 = 200_000.0;
/// P-AXIS-00209 vb_eilgang, µm/s (not above vb_max).
pub(crate) const DEFAULT_VB_EILGANG: f64 = 166_666.0;
/// P-AXIS-00008 a_max, mm/s².
pub(crate) const DEFAULT_A_MAX: f64 = 1000.0;
/// P-AXIS-00178 / -00177, 0.1 µm.
pub(crate) const DEFAULT_SWE_POS: f64 = 100_000_000.0;
pub(crate) const DEFAULT_SWE_NEG: f64 = -100_000_000.0;
/// P-AXIS-00195 … -00198 ramp times, µs.
pub(crate) const DEFAULT_TR: f64 = 50_000.0;
/// P-AXIS-00201 tr_min, µs.
pub(crate) const DEFAULT_TR_MIN: f64 = 10_000.0;

/// The ramp times whose shortest sets the jerk (non-linear slope, TF5200 Axis parameter).
const RAMP_TIMES: [&str; 4] = [
    "getriebe[0].slope_profil.tr_beschl_zu", // P-AXIS-00196
    "getriebe[0].slope_profil.tr_beschl_ab", // P-AXIS-00195
    "getriebe[0].slope_profil.tr_brems_zu",  // P-AXIS-00198
    "getriebe[0].slope_profil.tr_brems_ab",  // P-AXIS-00197
];
const ACHS_NR: &str = "kopf.achs_nr";
const LOG_ACHS_NAME: &str = "kopf.log_achs_name";
const ACHS_TYP: &str = "kenngr.achs_typ";
const SWE_POS: &str = "kenngr.swe_pos";
const SWE_NEG: &str = "kenngr.swe_neg";
const VB_MAX: &str = "getriebe[0].dynamik.vb_max";
const VB_EILGANG: &str = "getriebe[0].vb_eilgang";
const A_MAX: &str = "getriebe[0].dynamik.a_max";
const TR_MIN: &str = "getriebe[0].dynamik.tr_min";

/// Every entry an axis list is read for.
const USED: [&str; 13] = [
    ACHS_NR,
    LOG_ACHS_NAME,
    ACHS_TYP,
    SWE_POS,
    SWE_NEG,
    VB_MAX,
    VB_EILGANG,
    A_MAX,
    TR_MIN,
    RAMP_TIMES[0],
    RAMP_TIMES[1],
    RAMP_TIMES[2],
    RAMP_TIMES[3],
];

/// P-AXIS-00018: what kind of axis a list describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum AxisType {
    /// ACHSTYP_TRANSLATOR (0x0001): positions in mm.
    Linear,
    /// ACHSTYP_ROTATOR (0x0002): positions in degrees.
    Rotary,
    /// ACHSTYP_SPINDEL (0x0004): no path axis (P-CHAN-00035).
    Spindle,
}

/// One axis as its lists describe it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct AxisList {
    pub file: PathBuf,
    /// `kopf.achs_nr` (P-AXIS-00016), default 1.
    pub(crate) logical_number: u16,
    /// `kopf.log_achs_name` (P-AXIS-00297) with its line, if set.
    pub name: Option<(String, Entry)>,
    pub(crate) axis_type: AxisType,
    /// Limits in the axis table's units; `name` is left empty (the channel names the axis).
    pub limits: AxisConfig,
}

/// Does this list look like an axis list? (It names `kopf.*`, `kenngr.*` or `getriebe[…]`.)
pub(crate) fn is_axis_list(list: &ParamList) -> bool {
    list.entries.iter().any(|e| {
        e.name.segments.first().is_some_and(|s| {
            matches!(s.ident.as_str(), "kopf" | "kenngr") && s.index.is_none()
                || s.ident == "getriebe" && s.index.is_some()
        })
    })
}

/// Count and warn about the entries of one list (the default list or an axis's own list)
/// without reading values.
pub(crate) fn tally_axis_list(list: &ParamList, diags: &mut Vec<Diagnostic>) -> ListSummary {
    super::startup::warn_duplicates(list, diags);
    let mut tally = Tally::new(ListKind::Axis);
    for e in &list.entries {
        if !USED.contains(&e.name.text.as_str()) {
            tally.not_read(list, e, diags);
        }
    }
    tally.finish(list)
}

/// Read one axis from its list over the default list (`None`: the kernel's defaults only).
/// Problems go to `diags`; the values then fall back to the defaults.
pub(crate) fn interpret_axis(
    default: Option<&ParamList>,
    list: &ParamList,
    diags: &mut Vec<Diagnostic>,
) -> AxisList {
    let r = Reader {
        lists: match default {
            Some(d) => vec![d, list],
            None => vec![list],
        },
    };
    let logical_number = r
        .number(ACHS_NR, 1.0, f64::from(u16::MAX), diags)
        .map_or(1, |v| v as u16);
    let name = r
        .entry(LOG_ACHS_NAME)
        .map(|(_, e)| (e.value.text.clone(), e.clone()));
    let axis_type = r.axis_type(diags);

    let swe_pos = r.position(SWE_POS, DEFAULT_SWE_POS, diags);
    let swe_neg = r.position(SWE_NEG, DEFAULT_SWE_NEG, diags);
    if swe_neg >= swe_pos {
        r.error(
            SWE_POS,
            list,
            format!("kenngr.swe_pos {swe_pos} must be above kenngr.swe_neg {swe_neg} (0.1 µm)"),
            diags,
        );
    }
    let vb_max = r.number(VB_MAX, 1.0, 2e9, diags).unwrap_or(DEFAULT_VB_MAX);
    let vb_eilgang = match r.number(VB_EILGANG, 1.0, 2e9, diags) {
        Some(v) if v > vb_max => {
            r.error(
                VB_EILGANG,
                list,
                format!(
                    "getriebe[0].vb_eilgang {v} µm/s is above getriebe[0].dynamik.vb_max {vb_max} \
                     (P-AXIS-00209: at most P-AXIS-00212)"
                ),
                diags,
            );
            vb_max
        }
        Some(v) => v,
        None => DEFAULT_VB_EILGANG.min(vb_max),
    };
    let a_max = r.number(A_MAX, 1.0, 1e8, diags).unwrap_or(DEFAULT_A_MAX);
    let ramp = RAMP_TIMES
        .iter()
        .map(|n| {
            r.number(n, 0.0, f64::from(u32::MAX), diags)
                .unwrap_or(DEFAULT_TR)
        })
        .fold(f64::INFINITY, f64::min);
    let tr_min = r
        .number(TR_MIN, 0.0, f64::from(u32::MAX), diags)
        .unwrap_or(DEFAULT_TR_MIN);
    let tr_us = ramp.max(tr_min);

    let limits = AxisConfig {
        name: String::new(),
        kind: match axis_type {
            AxisType::Rotary => AxisKind::Rotary,
            _ => AxisKind::Linear,
        },
        max_velocity_mm_per_min: vb_max * MM_PER_MIN_PER_VELOCITY_UNIT,
        max_acceleration_mm_per_s2: a_max,
        max_jerk_mm_per_s3: jerk_of(a_max, tr_us),
        rapid_mm_per_min: vb_eilgang * MM_PER_MIN_PER_VELOCITY_UNIT,
        soft_limit_min_mm: swe_neg * MM_PER_POSITION_UNIT,
        soft_limit_max_mm: swe_pos * MM_PER_POSITION_UNIT,
    };
    AxisList {
        file: list.file.clone(),
        logical_number,
        name,
        axis_type,
        limits,
    }
}

/// Step: a channel's axis table. Without axis lists, runtime.toml's axes. With them, the
/// channel list's `gruppe[0].achse[j]` joined by logical number (P-CHAN-00035 = P-AXIS-00016)
/// to their axis lists, or — when the channel list names no axes — every axis list's axis
/// under its `kopf.log_achs_name`. `None` when an axis cannot be set up (reported).
pub(crate) fn channel_axes(
    chan: &ChannelList,
    axis_lists: &[AxisList],
    runtime: &RuntimeConfig,
    diags: &mut Vec<Diagnostic>,
) -> Option<Vec<AxisConfig>> {
    let list = &chan.list;
    if axis_lists.is_empty() {
        let first = chan.axes.values().next().and_then(|a| {
            a.name
                .as_ref()
                .map(|(_, e)| e)
                .or(a.logical_number.as_ref().map(|(_, e)| e))
        });
        if let Some(e) = first {
            diags.push(list.warning_at(
                e,
                e.name_pos,
                "the start-up list names no axis lists (achs_mds[i]): the axes come from \
                 runtime.toml",
            ));
        }
        return Some(runtime.axes.clone());
    }
    let before = diags.len();
    let mut axes: Vec<AxisConfig> = Vec::new();
    if chan.axes.is_empty() {
        every_listed_axis(&mut axes, list, axis_lists, diags);
    } else {
        named_axes(&mut axes, chan, axis_lists, diags);
    }
    if axes.is_empty() || axes.len() > MAX_AXES {
        diags.push(Diagnostic::error(
            &list.file,
            1,
            1,
            None,
            format!(
                "channel has {} path axes from its axis lists; 1 … {MAX_AXES} are needed",
                axes.len()
            ),
        ));
    }
    let failed = diags[before..]
        .iter()
        .any(|d| d.severity == Severity::Error);
    (!failed).then_some(axes)
}

/// Without `gruppe[0].achse[j]`: every axis list's axis (spindles aside), named by its
/// `kopf.log_achs_name`.
fn every_listed_axis(
    axes: &mut Vec<AxisConfig>,
    list: &ParamList,
    axis_lists: &[AxisList],
    diags: &mut Vec<Diagnostic>,
) {
    for a in axis_lists
        .iter()
        .filter(|a| a.axis_type != AxisType::Spindle)
    {
        let Some((name, e)) = &a.name else {
            diags.push(Diagnostic::error(
                &a.file,
                1,
                1,
                None,
                format!(
                    "axis {} has no kopf.log_achs_name, and {} names no \
                     gruppe[0].achse[j].bezeichnung",
                    a.logical_number,
                    list.file.display()
                ),
            ));
            continue;
        };
        push_axis(axes, name, a, &a.file, e, diags);
    }
}

/// `gruppe[0].achse[j]` joined by `log_achs_nr` to the axis list of that `kopf.achs_nr`.
fn named_axes(
    axes: &mut Vec<AxisConfig>,
    chan: &ChannelList,
    axis_lists: &[AxisList],
    diags: &mut Vec<Diagnostic>,
) {
    let list = &chan.list;
    for (j, r) in &chan.axes {
        let Some((nr, nr_entry)) = &r.logical_number else {
            if let Some((_, e)) = &r.name {
                diags.push(list.error_at(
                    e,
                    e.name_pos,
                    format!("gruppe[0].achse[{j}] has no log_achs_nr (P-CHAN-00035)"),
                ));
            }
            continue;
        };
        let Some(a) = axis_lists.iter().find(|a| a.logical_number == *nr) else {
            diags.push(list.error_at(
                nr_entry,
                nr_entry.value_pos,
                format!("{}: no axis list has kopf.achs_nr {nr}", nr_entry.name.text),
            ));
            continue;
        };
        if a.axis_type == AxisType::Spindle {
            diags.push(list.error_at(
                nr_entry,
                nr_entry.value_pos,
                format!(
                    "{}: axis {nr} ({}) is a spindle, which cannot be a path axis \
                     (P-CHAN-00035)",
                    nr_entry.name.text,
                    a.file.display()
                ),
            ));
            continue;
        }
        match (&r.name, &a.name) {
            (Some((name, e)), _) => push_axis(axes, name, a, &list.file, e, diags),
            (None, Some((name, e))) => push_axis(axes, name, a, &a.file, e, diags),
            (None, None) => diags.push(list.error_at(
                nr_entry,
                nr_entry.name_pos,
                format!(
                    "gruppe[0].achse[{j}] has no bezeichnung (P-CHAN-00006), and axis {nr} \
                     no kopf.log_achs_name"
                ),
            )),
        }
    }
}

/// Add one axis named `name` (written at `e` in `file`): a letter ncchannel drives, not yet
/// in the table.
fn push_axis(
    axes: &mut Vec<AxisConfig>,
    name: &str,
    a: &AxisList,
    file: &Path,
    e: &Entry,
    diags: &mut Vec<Diagnostic>,
) {
    let at = |message: String| {
        Diagnostic::error(file, e.value_pos.line, e.value_pos.col, None, message)
            .with_source(&e.line_text)
    };
    if !is_axis_name(name) {
        diags.push(at(format!(
            "{}: `{name}` is not an axis name ncchannel drives (X Y Z A B C U V W, or one of them followed by at most 15 letters, digits or `_`, as `X1`)",
            e.name.text
        )));
        return;
    }
    if axes.iter().any(|b| b.name.eq_ignore_ascii_case(name)) {
        diags.push(at(format!("{}: axis `{name}` is named twice", e.name.text)));
        return;
    }
    if let Some(b) = axes
        .iter()
        .find(|b| axis_index(&b.name).is_some() && axis_index(&b.name) == axis_index(name))
    {
        diags.push(at(format!(
            "{}: axis `{name}` takes the slot of axis `{}` (ncchannel drives one axis per letter X Y Z A B C; U V W take a slot left free)",
            e.name.text, b.name
        )));
        return;
    }
    axes.push(AxisConfig {
        name: name.to_ascii_uppercase(),
        ..a.limits.clone()
    });
}

/// The jerk limit of an acceleration `a` (mm/s²) built up in `tr_us` µs: a / tr, mm/s³;
/// no limit for a zero ramp time.
pub(crate) fn jerk_of(a_mm_per_s2: f64, tr_us: f64) -> Option<f64> {
    (tr_us > 0.0).then(|| a_mm_per_s2 / (tr_us * S_PER_RAMP_UNIT))
}

/// Reads entries by name from the default list and the axis list (the later wins).
struct Reader<'a> {
    lists: Vec<&'a ParamList>,
}

impl<'a> Reader<'a> {
    fn entry(&self, name: &str) -> Option<(&'a ParamList, &'a Entry)> {
        self.lists
            .iter()
            .rev()
            .find_map(|l| l.get(name).map(|e| (*l, e)))
    }

    /// A number in `min ..= max`, a reference resolved; `None` when not set or bad (reported).
    fn number(&self, name: &str, min: f64, max: f64, diags: &mut Vec<Diagnostic>) -> Option<f64> {
        let (list, e) = self.entry(name)?;
        let (tlist, target) = if matches!(e.value.kind, ValueKind::Ref(_)) {
            match catalog::resolve(ListKind::Axis, &self.lists, e) {
                Some(t) => t,
                None => {
                    diags.push(unresolved(list, e));
                    return None;
                }
            }
        } else {
            (list, e)
        };
        match number_value(tlist, target, min, max) {
            Ok(v) => Some(v),
            Err(d) => {
                diags.push(if std::ptr::eq(target, e) {
                    d
                } else {
                    list.error_at(
                        e,
                        e.value_pos,
                        format!("{} (via {})", d.message, e.value.text),
                    )
                });
                None
            }
        }
    }

    /// A software limit switch position, 0.1 µm (SGN32; REAL64 in later builds).
    fn position(&self, name: &str, default: f64, diags: &mut Vec<Diagnostic>) -> f64 {
        self.number(name, -1e15, 1e15, diags).unwrap_or(default)
    }

    fn axis_type(&self, diags: &mut Vec<Diagnostic>) -> AxisType {
        let Some((list, e)) = self.entry(ACHS_TYP) else {
            return AxisType::Linear;
        };
        let t = match (&e.value.kind, e.value.as_str()) {
            (ValueKind::Int(1) | ValueKind::Hex(1), _) | (_, "ACHSTYP_TRANSLATOR") => {
                Some(AxisType::Linear)
            }
            (ValueKind::Int(2) | ValueKind::Hex(2), _) | (_, "ACHSTYP_ROTATOR") => {
                Some(AxisType::Rotary)
            }
            (ValueKind::Int(4) | ValueKind::Hex(4), _) | (_, "ACHSTYP_SPINDEL") => {
                Some(AxisType::Spindle)
            }
            _ => None,
        };
        t.unwrap_or_else(|| {
            diags.push(list.error_at(
                e,
                e.value_pos,
                format!(
                    "kenngr.achs_typ: `{}` is not an axis type (ACHSTYP_TRANSLATOR or 1, \
                     ACHSTYP_ROTATOR or 2, ACHSTYP_SPINDEL or 4)",
                    e.value.text
                ),
            ));
            AxisType::Linear
        })
    }

    /// An error at the entry `name` where it is written, else at the axis list's first line.
    fn error(&self, name: &str, list: &ParamList, message: String, diags: &mut Vec<Diagnostic>) {
        diags.push(match self.entry(name) {
            Some((l, e)) => l.error_at(e, e.value_pos, message),
            None => Diagnostic::error(&list.file, 1, 1, None, message),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::list::parse_list;
    use std::path::Path;

    fn axis(default: &str, own: &str) -> (AxisList, Vec<Diagnostic>) {
        let (d, _) = parse_list(Path::new("default_mds.lis"), default);
        let (l, errs) = parse_list(Path::new("achsmds1.lis"), own);
        assert!(errs.is_empty(), "{errs:?}");
        let mut diags = Vec::new();
        let a = interpret_axis(Some(&d), &l, &mut diags);
        (a, diags)
    }

    #[test]
    fn units_convert_to_the_axis_table() {
        let (a, d) = axis(
            "getriebe[0].dynamik.a_max 2000\n",
            "kopf.achs_nr 3\nkopf.log_achs_name Z\nkenngr.swe_pos 15000000 ( P-AXIS-00178 : [0.1um]\n\
             kenngr.swe_neg -2500000\ngetriebe[0].dynamik.vb_max 500000\n\
             getriebe[0].vb_eilgang 250000\ngetriebe[0].slope_profil.tr_beschl_zu 40000\n\
             getriebe[0].dynamik.tr_min 0\n",
        );
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(a.logical_number, 3);
        assert_eq!(a.name.as_ref().map(|n| n.0.as_str()), Some("Z"));
        assert_eq!(a.axis_type, AxisType::Linear);
        let l = &a.limits;
        // 15000000 × 0.1 µm = 1500 mm; -2500000 × 0.1 µm = -250 mm.
        assert!((l.soft_limit_max_mm - 1500.0).abs() < 1e-9);
        assert!((l.soft_limit_min_mm + 250.0).abs() < 1e-9);
        // 500000 µm/s = 500 mm/s = 30000 mm/min; 250000 µm/s = 15000 mm/min.
        assert!((l.max_velocity_mm_per_min - 30000.0).abs() < 1e-9);
        assert!((l.rapid_mm_per_min - 15000.0).abs() < 1e-9);
        // a_max from the default list; jerk = 2000 mm/s² / 0.04 s = 50000 mm/s³.
        assert_eq!(l.max_acceleration_mm_per_s2, 2000.0);
        assert!((l.max_jerk_mm_per_s3.unwrap() - 50000.0).abs() < 1e-6);
    }

    #[test]
    fn rotary_axes_keep_degrees_and_tr_min_floors_the_ramp() {
        let (a, d) = axis(
            "",
            "kenngr.achs_typ ACHSTYP_ROTATOR\nkenngr.swe_pos 3600000\nkenngr.swe_neg -3600000\n\
             getriebe[0].dynamik.vb_max 60000\ngetriebe[0].slope_profil.tr_brems_ab 1000\n",
        );
        assert!(d.is_empty(), "{d:?}");
        assert_eq!(a.axis_type, AxisType::Rotary);
        assert_eq!(a.limits.kind, AxisKind::Rotary);
        // 3600000 × 10⁻⁴ ° = 360 °; 60000 × 10⁻³ °/s = 60 °/s = 3600 °/min.
        assert!((a.limits.soft_limit_max_mm - 360.0).abs() < 1e-9);
        assert!((a.limits.max_velocity_mm_per_min - 3600.0).abs() < 1e-9);
        // The rapid default (166666) is capped at vb_max.
        assert!((a.limits.rapid_mm_per_min - 3600.0).abs() < 1e-9);
        // tr 1000 µs is below tr_min 10000 µs: jerk = 1000 / 0.01 = 100000.
        assert!((a.limits.max_jerk_mm_per_s3.unwrap() - 100_000.0).abs() < 1e-6);
    }

    #[test]
    fn references_and_implausible_values() {
        let (a, d) = axis(
            "",
            "getriebe[0].dynamik.a_max 4000\ngetriebe[0].slope_profil.a_brems P-AXIS-00008.0\n\
             kenngr.swe_pos 10\nkenngr.swe_neg 20\ngetriebe[0].dynamik.vb_max 1000\n\
             getriebe[0].vb_eilgang 2000\nkenngr.achs_typ 7\n",
        );
        assert_eq!(a.limits.max_acceleration_mm_per_s2, 4000.0);
        let msgs: Vec<_> = d.iter().map(|d| (d.line, d.message.clone())).collect();
        assert_eq!(d.len(), 3, "{msgs:?}");
        assert!(msgs.iter().any(|(l, m)| *l == 3 && m.contains("swe_pos")));
        assert!(msgs
            .iter()
            .any(|(l, m)| *l == 6 && m.contains("vb_eilgang")));
        assert!(msgs.iter().any(|(l, m)| *l == 7 && m.contains("achs_typ")));
        let (_, d) = axis("", "getriebe[0].dynamik.a_max P-AXIS-00004.0\n");
        assert_eq!(d.len(), 1);
        assert!(d[0].message.contains("refers to P-AXIS-00004.0"), "{d:?}");
    }
}
