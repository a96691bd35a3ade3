//! What ncchannel knows of each list kind besides the entries it reads: the kernel's entries
//! it deliberately ignores (inert: they configure hardware or functions the emulator does not
//! model), and the P numbers a value may refer to (`P-AXIS-00008.0`). `check` counts per list
//! how many entries are used, inert and unknown, so a user sees what of a configuration is
//! modelled.

use std::fmt;

use super::list::{Entry, Name, ParamList, ParamRef};
use crate::diag::Diagnostic;

/// The kind of a parameter list, decided by what it names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ListKind {
    /// `hochlauf.lis`: channels, their lists, axis lists, paths (TF5200 "Start-up parameter").
    Startup,
    /// `sda_mds*.lis`: one channel (TF5200 "Channel parameter").
    Channel,
    /// `achsmds*.lis`, `default_mds.lis`: one axis (TF5200 "Axis parameter").
    Axis,
    /// The tool list (`wz[i].*`, TF5200 "Tool data"; start-up entry `werkz_data[i]`).
    Tools,
    /// The zero-offset list (`np_grp[i].achse[j].versch`, P-ZERO-00003; start-up entry
    /// `nullp_data[i]`).
    ZeroOffsets,
    /// The list of external variables (`var[i].*`, `struct[i].*`; TF5200 External variables).
    ExtVars,
}

impl fmt::Display for ListKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ListKind::Startup => "start-up list",
            ListKind::Channel => "channel list",
            ListKind::Axis => "axis list",
            ListKind::Tools => "tool list",
            ListKind::ZeroOffsets => "zero-offset list",
            ListKind::ExtVars => "external variable list",
        })
    }
}

/// How many entries of one list ncchannel uses, knows and ignores, or does not know.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EntryCounts {
    pub used: usize,
    pub inert: usize,
    pub unknown: usize,
}

/// One list read, with its counts, for `check`'s summary.
#[derive(Debug, Clone, PartialEq)]
pub struct ListSummary {
    pub file: std::path::PathBuf,
    pub kind: ListKind,
    pub counts: EntryCounts,
}

impl fmt::Display for ListSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = self.counts;
        write!(
            f,
            "{}: {}, {} entries: {} used, {} inert, {} unknown",
            self.file.display(),
            self.kind,
            c.used + c.inert + c.unknown,
            c.used,
            c.inert,
            c.unknown
        )
    }
}

/// Counts the entries a list interpreter does not read: inert ones silently, unknown ones
/// with a warning. What is left of the list was used.
#[derive(Debug)]
pub struct Tally {
    kind: ListKind,
    inert: usize,
    unknown: usize,
}

impl Tally {
    pub fn new(kind: ListKind) -> Self {
        Tally {
            kind,
            inert: 0,
            unknown: 0,
        }
    }

    /// An entry the interpreter does not read: inert when the catalog knows it, else a
    /// warning that it is unknown.
    pub(crate) fn not_read(&mut self, list: &ParamList, e: &Entry, diags: &mut Vec<Diagnostic>) {
        if is_inert(self.kind, &e.name) {
            self.inert += 1;
        } else {
            self.unknown += 1;
            diags.push(list.warning_at(
                e,
                e.name_pos,
                format!(
                    "unknown parameter {}: kept, but the emulator does not use it",
                    crate::diag::excerpt(&e.name.text)
                ),
            ));
        }
    }

    /// A kernel entry the interpreter knows but does not use, which it has warned about
    /// itself (a zero-offset group beyond G59, the G53 group, an axis beyond C): inert.
    pub(crate) fn kept_unused(&mut self) {
        self.inert += 1;
    }

    /// The summary of `list`, every entry not counted as inert or unknown being used.
    pub fn finish(&self, list: &ParamList) -> ListSummary {
        let total = list.entries.len();
        ListSummary {
            file: list.file.clone(),
            kind: self.kind,
            counts: EntryCounts {
                used: total.saturating_sub(self.inert + self.unknown),
                inert: self.inert,
                unknown: self.unknown,
            },
        }
    }
}

/// A name with its indices blanked: `getriebe[0].dynamik.a_max` → `getriebe[].dynamik.a_max`,
/// the form the tables below use.
fn pattern_of(name: &Name) -> String {
    let mut out = String::with_capacity(name.text.len());
    for (i, s) in name.segments.iter().enumerate() {
        if i > 0 {
            out.push('.');
        }
        out.push_str(&s.ident);
        if s.index.is_some() {
            out.push_str("[]");
        }
    }
    out
}

/// Is this a kernel entry ncchannel deliberately ignores? Exact patterns, or a prefix ending
/// in `.` that covers a whole structure (`spindel[].`: spindles are not modelled).
fn is_inert(kind: ListKind, name: &Name) -> bool {
    let p = pattern_of(name);
    let table = match kind {
        ListKind::Startup => INERT_STARTUP,
        ListKind::Channel => INERT_CHANNEL,
        ListKind::Axis => INERT_AXIS,
        ListKind::Tools => INERT_TOOLS,
        ListKind::ZeroOffsets => &[],
        ListKind::ExtVars => INERT_EXT_VARS,
    };
    table.iter().any(|(pat, _)| {
        if pat.ends_with('.') {
            p.starts_with(pat)
        } else {
            p == *pat
        }
    })
}

/// Start-up entries known and ignored, with their P numbers (TF5200 Start-up parameter).
pub(crate) const INERT_STARTUP: &[(&str, &str)] = &[
    (
        "listen",
        "P-STUP-00008 list type ASCII/BINAER: ncchannel reads ASCII lists",
    ),
    ("hand_mds", "P-STUP-00013 manual mode list: no manual mode"),
    (
        "zahl_mds",
        "P-STUP-00014 number of axis lists: the achs_mds[i] given are read",
    ),
    (
        "default_sda_mds",
        "P-STUP-00034 default channel list: not modelled",
    ),
    (
        "error_text_user_of_id",
        "P-STUP-00169 user error texts (#ERROR): no #ERROR",
    ),
    (
        "error_text_cycles_of_id",
        "P-STUP-00200 cycle error texts: no kernel cycles",
    ),
    ("sercos_hochlauf", "SERCOS start-up: no drives"),
    (
        "configuration.channel[].path_preparation.",
        "P-STUP-00060…64: path preparation functions",
    ),
    (
        "configuration.channel[].interpolator.",
        "P-STUP-00070…73: interpolator functions",
    ),
    (
        "configuration.channel[].tool_radius_comp.",
        "P-STUP-00080…82: TRC functions",
    ),
    (
        "configuration.channel[].decoder.log_entry_number",
        "P-STUP-00054 decoder log",
    ),
    (
        "configuration.channel[].decoder.log_level",
        "P-STUP-00055 decoder log",
    ),
    (
        "configuration.diagnosis_upload.",
        "P-STUP-00111…114 diagnosis upload",
    ),
];

/// Channel entries known and ignored (TF5200 Channel parameter).
pub(crate) const INERT_CHANNEL: &[(&str, &str)] = &[
    (
        "gruppe[].bezeichnung",
        "P-CHAN-00005 axis group name: display only",
    ),
    (
        "gruppe[].achs_anzahl",
        "P-CHAN-00003 axes of the group: the achse[j] given count",
    ),
    (
        "spindel[].",
        "P-CHAN-00007, P-CHAN-00036 …: spindles are not modelled",
    ),
    (
        "configuration.path_preparation.",
        "P-CHAN-00600…604 path preparation functions",
    ),
    (
        "configuration.interpolator.",
        "P-CHAN-00650…652 interpolator functions",
    ),
    (
        "configuration.tool_radius_comp.",
        "P-CHAN-00550…552 TRC functions",
    ),
    (
        "configuration.decoder.log_entry_number",
        "P-CHAN-00501 decoder log",
    ),
    (
        "configuration.decoder.log_level",
        "P-CHAN-00502 decoder log",
    ),
];

/// Axis entries known and ignored (TF5200 Axis parameter).
pub(crate) const INERT_AXIS: &[(&str, &str)] = &[
    (
        "getriebe[].slope_profil.a_beschl",
        "P-AXIS-00001: one acceleration, a_max, is modelled",
    ),
    (
        "getriebe[].slope_profil.a_brems",
        "P-AXIS-00002: one acceleration, a_max, is modelled",
    ),
    (
        "getriebe[].dynamik.a_emergency",
        "P-AXIS-00003 emergency stop deceleration",
    ),
    (
        "getriebe[].slope_profil.a_grenz",
        "P-AXIS-00004 rapid acceleration: a_max is used",
    ),
    (
        "getriebe[].slope_profil.tr_grenz",
        "P-AXIS-00200 rapid ramp time: the feed ramps are used",
    ),
    (
        "getriebe[].dynamik.tr_geom",
        "P-AXIS-00199 geometric ramp time",
    ),
    (
        "getriebe[].lslope_profil.",
        "P-AXIS-00005, -00006, -00011 …: the linear slope",
    ),
    ("getriebe[].vb_max_red", "reduced velocity: not modelled"),
    ("getriebe[].rapid_speed_red", "reduced rapid: not modelled"),
    ("getriebe[].vb_reflow", "homing velocity: no homing"),
    ("getriebe[].vb_refmax", "homing velocity: no homing"),
    ("getriebe[].a_ref", "homing acceleration: no homing"),
    (
        "kenngr.swe_toleranz",
        "P-AXIS-00179 actual-value tolerance: positions are exact",
    ),
    (
        "kenngr.antr_typ",
        "P-AXIS-00020 drive type: the emulated drive is ideal",
    ),
    (
        "kenngr.abs_pos_guelt",
        "P-AXIS-00014 absolute measuring system",
    ),
    (
        "lr_param.",
        "position controller parameters: no position controller",
    ),
    ("lr_hw.", "position controller hardware: no hardware"),
    ("antr.", "drive parameters: no drive"),
    ("handbetrieb.", "P-AXIS-00009, -00213 …: no manual mode"),
    ("vorsteuer.", "feed forward: no control loop"),
    ("twincat.", "TwinCAT system manager data"),
];

/// Tool entries known and ignored (TF5200 Tool data).
pub(crate) const INERT_TOOLS: &[(&str, &str)] = &[
    ("wz[].typ", "P-TOOL-00001 tool type: milling tools only"),
    ("wz[].srk_lage", "P-TOOL-00002 cutter position: no turning"),
    ("wz[].param[]", "P-TOOL-00007 free tool parameters"),
    (
        "wz[].kinematic.",
        "P-TOOL-00009 kinematic offsets: no transformations",
    ),
    (
        "wz[].tool_fixed",
        "tool fixed / alignable: no transformations",
    ),
    ("wz[].kin_id", "kinematic ID: no transformations"),
    (
        "wz[].log_ax_nr_spdl",
        "spindle of the tool: no spindle model",
    ),
    ("wz[].vb_min", "tool speed limits: no spindle model"),
    ("wz[].vb_max", "tool speed limits: no spindle model"),
    ("wz[].a_max", "tool acceleration limit: no spindle model"),
];

/// V.E. list entries known and ignored (TF5200 External variables): they lay out the
/// kernel's memory shared with the PLC, which ncchannel does not have.
pub(crate) const INERT_EXT_VARS: &[(&str, &str)] = &[
    ("var[].byte_offset", "P-EXTV-00002 position in memory"),
    ("var[].index", "position in 24-byte blocks (older lists)"),
    (
        "var[].scope",
        "P-EXTV-00004 CHANNEL/GLOBAL: each channel keeps its own",
    ),
    (
        "var[].synchronisation",
        "P-EXTV-00005 synchronisation with the PLC",
    ),
    (
        "var[].create_hmi_interface",
        "HMI interface: the ADS side serves every leaf",
    ),
    (
        "struct[].element[].synchronisation",
        "P-EXTV-00018 synchronisation",
    ),
    (
        "check_overlapping_variables",
        "P-EXTV-00011 memory layout check",
    ),
    ("auto_memory_mode", "P-EXTV-00012 automatic memory layout"),
];

/// The entries a value may refer to by P number, by list kind: (P number, pattern). The
/// `.n` of a reference fills the pattern's first `[]`.
const REFERABLE: &[(ListKind, &str, u32, &str)] = &[
    (
        ListKind::Axis,
        "AXIS",
        1,
        "getriebe[].slope_profil.a_beschl",
    ),
    (ListKind::Axis, "AXIS", 2, "getriebe[].slope_profil.a_brems"),
    (ListKind::Axis, "AXIS", 4, "getriebe[].slope_profil.a_grenz"),
    (ListKind::Axis, "AXIS", 8, "getriebe[].dynamik.a_max"),
    (ListKind::Axis, "AXIS", 177, "kenngr.swe_neg"),
    (ListKind::Axis, "AXIS", 178, "kenngr.swe_pos"),
    (
        ListKind::Axis,
        "AXIS",
        195,
        "getriebe[].slope_profil.tr_beschl_ab",
    ),
    (
        ListKind::Axis,
        "AXIS",
        196,
        "getriebe[].slope_profil.tr_beschl_zu",
    ),
    (
        ListKind::Axis,
        "AXIS",
        197,
        "getriebe[].slope_profil.tr_brems_ab",
    ),
    (
        ListKind::Axis,
        "AXIS",
        198,
        "getriebe[].slope_profil.tr_brems_zu",
    ),
    (
        ListKind::Axis,
        "AXIS",
        200,
        "getriebe[].slope_profil.tr_grenz",
    ),
    (ListKind::Axis, "AXIS", 201, "getriebe[].dynamik.tr_min"),
    (ListKind::Axis, "AXIS", 209, "getriebe[].vb_eilgang"),
    (ListKind::Axis, "AXIS", 212, "getriebe[].dynamik.vb_max"),
];

/// The parameter name a reference names, e.g. `P-AXIS-00008.0` → `getriebe[0].dynamik.a_max`.
pub(crate) fn referenced_name(kind: ListKind, r: &ParamRef) -> Option<String> {
    let (_, _, _, pat) = REFERABLE
        .iter()
        .find(|(k, g, n, _)| *k == kind && *g == r.group && *n == r.number)?;
    let index = r.index.unwrap_or(0).to_string();
    Some(pat.replacen("[]", &format!("[{index}]"), 1))
}

/// The entry a reference resolves to in `lists` (searched last list first, as later lists
/// override earlier ones), following references up to a few steps.
pub fn resolve<'a>(
    kind: ListKind,
    lists: &[&'a ParamList],
    e: &'a Entry,
) -> Option<(&'a ParamList, &'a Entry)> {
    let mut cur = e;
    for _ in 0..4 {
        let super::list::ValueKind::Ref(r) = &cur.value.kind else {
            return None;
        };
        let name = referenced_name(kind, r)?;
        let (list, target) = lists
            .iter()
            .rev()
            .find_map(|l| l.get(&name).map(|t| (*l, t)))?;
        if !matches!(target.value.kind, super::list::ValueKind::Ref(_)) {
            return Some((list, target));
        }
        cur = target;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::list::parse_list;
    use std::path::Path;

    #[test]
    fn references_resolve_by_p_number_and_gear_index() {
        let (list, _) = parse_list(
            Path::new("a.lis"),
            "getriebe[0].dynamik.a_max 3000\ngetriebe[0].slope_profil.a_brems P-AXIS-00008.0\n\
             x P-AXIS-00002.0\ny P-AXIS-09999\n",
        );
        let (_, t) = resolve(ListKind::Axis, &[&list], &list.entries[1]).unwrap();
        assert_eq!(t.value.as_int(), Some(3000));
        // A reference to a reference follows on.
        let (_, t) = resolve(ListKind::Axis, &[&list], &list.entries[2]).unwrap();
        assert_eq!(t.value.as_int(), Some(3000));
        assert!(resolve(ListKind::Axis, &[&list], &list.entries[3]).is_none());
    }

    #[test]
    fn inert_patterns_blank_indices_and_cover_structures() {
        let (list, _) = parse_list(
            Path::new("a.lis"),
            "spindel[0].range_way 0\nkenngr.swe_toleranz 1000\nfoo 1\n",
        );
        let mut diags = Vec::new();
        let mut t = Tally::new(ListKind::Axis);
        for e in &list.entries {
            t.not_read(&list, e, &mut diags);
        }
        assert_eq!(diags.len(), 2, "{diags:?}");
        assert_eq!(
            t.finish(&list).counts,
            EntryCounts {
                used: 0,
                inert: 1,
                unknown: 2
            }
        );
        let mut t = Tally::new(ListKind::Channel);
        t.not_read(&list, &list.entries[0], &mut diags);
        assert_eq!(t.inert, 1);
    }
}
