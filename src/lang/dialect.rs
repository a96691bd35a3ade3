//! What ncchannel does with each G function and `#` command of the ISG dialect.
//!
//! The reference lists are the G-function and `#`-command overviews of the TF5200
//! programming manual as ISG's own editor support carries them
//! (`isg-stuttgart/vscode-isg-cnc`, `server/extension-resources-output/output_generated/
//! genericMerged.json`). Every entry there is one of three things here: implemented with its
//! documented effect, accepted as a documented no-op where ncchannel models nothing behind
//! it, or refused by name (error [`super::codes::UNSUPPORTED`]) — never given a silent wrong
//! meaning. A number or keyword outside the lists stays unknown (20131 / 20209).
//! docs/nc-language.md explains each choice.

/// How ncchannel treats one dialect entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Support {
    /// Executed with its documented effect.
    Implemented,
    /// Accepted and without effect: ncchannel models nothing behind it.
    Inert,
    /// Refused with [`super::codes::UNSUPPORTED`] naming it.
    Refused,
}

use Support::{Implemented as I, Inert as N, Refused as R};

/// The G functions of the reference list: number (ranges spelled out), what ISG says it
/// does, and ours.
const G_TABLE: &[(u32, u32, &str, Support)] = &[
    (0, 0, "linear interpolation in rapid traverse", I),
    (1, 1, "linear interpolation", I),
    (2, 3, "circular interpolation", I),
    (4, 4, "dwell time", I),
    (5, 5, "tangential selection/deselection of TRC", R),
    (8, 8, "acceleration at block start", N),
    (9, 9, "deceleration at block end", N),
    (10, 11, "feed rate of TRC", N),
    (12, 13, "corner deceleration", N),
    (17, 19, "plane selection", I),
    (20, 20, "deselecting the mirroring function", N),
    (21, 23, "mirroring programmed paths", R),
    (25, 26, "transitions with TRC", N),
    (33, 33, "thread cutting, uniform pitch", R),
    (40, 42, "tool radius compensation (modal state only)", I),
    (51, 51, "selecting diameter programming", R),
    (52, 52, "deselecting diameter programming", N),
    (53, 59, "zero offsets", I),
    (60, 60, "exact stop", N),
    (
        61,
        61,
        "polynomial contouring at block end (modal state only)",
        I,
    ),
    (63, 63, "thread tapping", R),
    (66, 66, "synchronising cycle at block end", R),
    (68, 68, "selecting contour rotation", R),
    (69, 69, "deselecting contour rotation", N),
    (70, 71, "inch / metric input", I),
    (74, 74, "homing", R),
    (
        80,
        80,
        "cycle cancellation (no implicit subroutine configured)",
        N,
    ),
    (81, 89, "implicit subroutine calls", R),
    (90, 91, "absolute / incremental dimensions", I),
    (92, 92, "reference point offset", I),
    (93, 93, "F word as machining time", R),
    (94, 95, "feed per minute / per revolution", I),
    (96, 96, "constant cutting velocity", R),
    (97, 97, "S word as spindle speed", I),
    (98, 99, "programmable software limit switches", R),
    (100, 102, "measuring functions", R),
    (106, 106, "measurement run", R),
    (107, 107, "deselecting cross-block edge banding", N),
    (108, 108, "edge banding", R),
    (112, 112, "gear changing", R),
    (115, 117, "look-ahead functions", N),
    (127, 128, "weighting of velocity and acceleration", R),
    (129, 129, "weighting of rapid traverse velocity", N),
    (
        130,
        131,
        "acceleration weighting (G130's axis words are weights, no move)",
        N,
    ),
    (132, 134, "weighting of ramp times", N),
    (135, 135, "selecting feedforward control", N),
    (136, 136, "weighting of feedforward control", R),
    (137, 137, "deselecting feedforward control", N),
    (138, 139, "direct / indirect TRC selection", R),
    (140, 140, "deselecting contour masking", N),
    (141, 141, "selecting contour masking", R),
    (
        150,
        151,
        "spline interpolation off / on (modal state only)",
        I,
    ),
    (159, 160, "extended / axis-specific zero offsets", R),
    // TF5200 programming manual, "Specifying centre point for circle definition
    // (G161/G162)": under G161 I J K are absolute in the programmer's coordinate system, under
    // G162 (the initial state) relative to the circle's start point.
    (161, 161, "circle centre absolute", I),
    (162, 162, "circle centre relative (initial state)", I),
    (163, 163, "radius programming (R is always accepted)", N),
    (164, 165, "circle centre point correction", N),
    (166, 167, "override 100 %", N),
    (
        193,
        193,
        "path-related feed interpolation (initial state)",
        N,
    ),
    (194, 194, "F word as weighting of maximum feed rate", R),
    (196, 196, "maximum spindle speed for G96", R),
    (200, 202, "manual mode", R),
    (230, 230, "axis-specific acceleration weighting for G00", R),
    (231, 231, "acceleration weighting for G00", N),
    (232, 232, "axis-specific weighting for G00", R),
    (233, 233, "weighting for G00", N),
    (236, 239, "TRC selection variants", R),
    (
        260,
        261,
        "polynomial contouring off / on (modal state only)",
        I,
    ),
    (293, 293, "time-related feed interpolation", R),
    (301, 302, "inserting chamfers / roundings", R),
    (303, 303, "arc in 3D space", R),
    (310, 310, "measuring with interruption", R),
    (331, 332, "tapping with pitch", R),
    (333, 339, "weighting with feedhold", R),
    (351, 351, "mirroring with axis specification", R),
    (359, 360, "exact stop off / on", N),
    (
        800,
        819,
        "implicit subroutine calls (g800_prog_file[i], P-CHAN-00187)",
        I,
    ),
    (900, 901, "deceleration at / after block end", N),
];

/// What ncchannel does with `G<g>`, and ISG's name for it; `None` for a number ISG's list
/// does not have (20131).
pub fn g_support(g: u32) -> Option<(Support, &'static str)> {
    G_TABLE
        .iter()
        .find(|&&(lo, hi, _, _)| (lo..=hi).contains(&g))
        .map(|&(_, _, name, s)| (s, name))
}

/// The `#` commands of the reference list by their first keyword, and ours. Commands
/// handled by the parser itself (`#FLUSH`, `#CACHE`, `#COMMENT`, `#SPLINE`, `#HSC`,
/// `#CONTOUR`, `#VAR`/`#ENDVAR`, `#MSG`, `#TIME`, `#EXPL SYN`) are listed as implemented.
const COMMAND_TABLE: &[(&str, Support)] = &[
    ("ACS", R),
    ("ADD", R),
    ("AKIMA", R),
    ("ANG", R),
    ("AX", R),
    ("BACKWARD", N),
    ("BCS", R),
    ("BLOCKSEARCH", N),
    ("CACHE", I),
    ("CALL", R),
    ("CAX", R),
    ("CAXTRACK", R),
    ("CHANNEL", R),
    ("CHF", R),
    ("CHR", R),
    ("CLEAR", N),
    ("COMMAND", N),
    ("COMMENT", I),
    ("CONTOUR", I),
    ("CONTROL", R),
    ("CORNER", N),
    ("CS", R),
    ("CYL", R),
    ("DEL", R),
    ("DELETE", R),
    ("DISABLE", R),
    ("DIST", R),
    ("DISTANCE", N),
    ("DRIVE", N),
    ("DYNAMIC", N),
    ("ECS", R),
    ("EDGE", R),
    ("EDM", R),
    ("ENABLE", R),
    ("ENDVAR", I),
    ("ERROR", R),
    ("EXPL", I),
    ("EXPORT", R),
    ("EXTCOMP", N),
    ("FACE", R),
    ("FF", N),
    ("FGROUP", R),
    ("FILE", R),
    ("FILTER", N),
    ("FLUSH", I),
    ("FRC", R),
    ("FREE", N),
    ("GANTRY", R),
    ("GEAR", R),
    ("GET", R),
    ("HANDWHEEL", N),
    ("HSC", I),
    ("IDENT", N),
    ("INIT", R),
    ("JOG", N),
    ("KIN", R),
    ("LAH", N),
    ("LIMIT", R),
    ("LOAD", N),
    ("LOCK", N),
    ("MACHINE", R),
    ("MAIN", R),
    ("MANUAL", N),
    ("MCS", R),
    ("MEAS", R),
    ("MSG", I),
    ("NIBBLE", R),
    ("OPTIONAL", R),
    ("ORI", R),
    ("OTC", R),
    ("OVERRIDE", R),
    ("PRESET", R),
    ("PSET", R),
    ("PTP", R),
    ("PUNCH", R),
    ("PUT", R),
    ("RETAIN", R),
    ("RND", R),
    ("ROTATION", R),
    ("RT", R),
    ("SAVE", N),
    ("SCALE", R),
    ("SEGMENTATION", N),
    ("SET", R),
    ("SIGNAL", R),
    ("SINGLE", N),
    ("SLOPE", N),
    ("SPLINE", I),
    ("STOP", N),
    ("STROKE", R),
    ("SUPPRESS", R),
    ("SYNC", R),
    ("TANGFEED", N),
    ("TIME", I),
    ("TIMER", R),
    ("TLAX", R),
    ("TLC", R),
    ("TOOL", R),
    ("TRACK", R),
    ("TRAFO", R),
    ("TRANSFORM", R),
    ("TRANSVELMIN", N),
    ("TRC", N),
    ("TURN", R),
    ("UNLOCK", N),
    ("VAR", I),
    ("VECTOR", N),
    ("VIB", N),
    ("VOLCOMP", N),
    ("WAIT", R),
    ("WCS", R),
];

/// `#` commands refused by their first keyword whose forms named here are accepted without
/// effect, because the kernel does something behind them that changes no path:
/// `#CHANNEL INIT [CMDPOS]` / `[ACTPOS]` (TF5200 programming manual, "Request current command
/// positions … (#CHANNEL INIT)": command and actual positions are one in ncchannel),
/// `#TOOL PREP`, `#TOOL DATA` (requests to the tool management, "Programming commands and
/// variables"), `#TOOL LIFE READ` ("Reading/removing tool life values": tool life data to the
/// tool management).
const INERT_FORMS: &[(&str, &[&str])] = &[
    ("CHANNEL", &["INIT"]),
    ("TOOL", &["DATA"]),
    ("TOOL", &["LIFE", "READ"]),
    ("TOOL", &["PREP"]),
];

/// `s` for the command `kw` (upper-case) whose text after the keyword is `rest`, made
/// [`Support::Inert`] when it is one of the [`INERT_FORMS`].
pub(crate) fn form_support(s: Support, kw: &[u8], rest: &str) -> Support {
    let inert = INERT_FORMS.iter().any(|(k, words)| {
        k.as_bytes() == kw
            && words
                .iter()
                .try_fold(rest, |r, w| super::expr::keyword(super::expr::ws(r), w))
                .is_some()
    });
    if s == Support::Refused && inert {
        Support::Inert
    } else {
        s
    }
}

/// What ncchannel does with the `#` command whose first keyword is `kw` (upper-case);
/// `None` for a keyword ISG's list does not have (20209).
pub fn command_support(kw: &[u8]) -> Option<Support> {
    COMMAND_TABLE
        .binary_search_by(|(k, _)| k.as_bytes().cmp(kw))
        .ok()
        .map(|i| COMMAND_TABLE[i].1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_table_is_sorted_for_the_binary_search() {
        assert!(COMMAND_TABLE.windows(2).all(|w| w[0].0 < w[1].0));
    }

    #[test]
    fn g_ranges_do_not_overlap() {
        assert!(G_TABLE
            .windows(2)
            .all(|w| w[0].1 < w[1].0 && w[0].0 <= w[0].1));
    }
}
