//! Modal state of a channel: what a block leaves behind for the next (G groups, feed, spindle,
//! coolant, tool, position), re-initialised at program start and collected by block search.

use crate::lang::block::SplineCommand;
use crate::lang::dialect::{g_support, Support};
use crate::queue::Plane;
use crate::vocab::axis::{Position, MAX_AXES};

/// Deviation for G261/G61 before any `#CONTOUR MODE` sets one, mm.
pub const DEFAULT_PATH_DEV_MM: f64 = 0.05;

/// `PATH_DEV=<mm>` from the bracket text of `#CONTOUR MODE [...]`, if it has a valid one.
pub(crate) fn path_dev_mm(options: &str) -> Option<f64> {
    options
        .split(|c: char| c.is_whitespace() || c == '[' || c == ']' || c == ',')
        .filter_map(|w| {
            let (k, v) = w.split_once('=')?;
            k.trim()
                .eq_ignore_ascii_case("PATH_DEV")
                .then(|| v.trim().parse::<f64>().ok())
                .flatten()
        })
        .find(|v| v.is_finite() && *v >= 0.0)
}

/// Motion G group.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionMode {
    Rapid,
    Linear,
    ArcCw,
    ArcCcw,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spindle {
    Off,
    /// M3.
    Cw,
    /// M4.
    Ccw,
}

impl Spindle {
    /// The direction's name as the live view's snapshot gives it: `cw`, `ccw` or `off`.
    pub fn name(self) -> &'static str {
        match self {
            Spindle::Cw => "cw",
            Spindle::Ccw => "ccw",
            Spindle::Off => "off",
        }
    }
}

/// Tool radius compensation (G40 / G41 / G42).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RadiusComp {
    Off,
    Left,
    Right,
}

/// Units of programmed lengths and feeds (G70 / G71).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Units {
    /// G71: mm (the channel default).
    Metric,
    /// G70: inch; lengths and feeds are scaled by 25.4 at decode time.
    Inch,
}

impl Units {
    /// mm per programmed length unit.
    pub(crate) fn mm_per_unit(self) -> f64 {
        match self {
            Units::Metric => 1.0,
            Units::Inch => 25.4,
        }
    }
}

/// Meaning of the F word (G94 / G95).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FeedMode {
    /// G94: length per minute (the default).
    PerMinute,
    /// G95: length per spindle revolution; the path feed is F × S, computed at decode time.
    PerRevolution,
}

/// Exact-stop / velocity mode at block ends (G60, G08, G09, G359/G360, G900/G901). Kept as
/// state only: the planner does not read it yet (docs/nc-language.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum BlockEnd {
    /// Default: continuous path.
    Continuous,
    /// G360: exact stop at every block end (G359 deselects).
    ExactStop,
}

/// Everything modal the emulator tracks. Block search compares these between a full run and a
/// search run, so every field is plain data.
#[derive(Debug, Clone, PartialEq)]
pub struct Modal {
    pub motion: MotionMode,
    pub plane: Plane,
    /// G90 (true) / G91 (false).
    pub absolute: bool,
    /// Modal path feed under G94, mm/min; 0 = none programmed yet.
    pub feed_mm_per_min: f64,
    /// Modal feed under G95, mm per spindle revolution; 0 = none programmed yet.
    pub(crate) feed_mm_per_rev: f64,
    pub(crate) feed_mode: FeedMode,
    pub units: Units,
    /// G92 reference point offset per axis, mm / degrees, added to programmed absolute
    /// positions after the zero offset.
    pub(crate) g92_offset: [f64; MAX_AXES],
    pub(crate) block_end: BlockEnd,
    pub spindle: Spindle,
    /// Programmed spindle speed, rpm.
    pub spindle_rpm: f64,
    /// M7.
    pub(crate) coolant_mist: bool,
    /// M8.
    pub coolant_flood: bool,
    pub tool: u32,
    /// D word: tool data set for radius compensation.
    pub tool_offset: u32,
    /// Active zero offset: 0 = none (G53 state), 1..=6 = G54..G59.
    pub(crate) zero_offset: usize,
    pub(crate) radius_comp: RadiusComp,
    /// G261 contouring on (G260 off).
    pub contouring: bool,
    /// `#CONTOUR MODE [DEV PATH_DEV=…]`: corner deviation for G261/G61, mm.
    pub contour_dev_mm: f64,
    /// G161: I J K give the circle centre in absolute program coordinates; G162 (false,
    /// the initial state): offsets from the start point (TF5200 programming manual,
    /// "Specifying centre point for circle definition (G161/G162)").
    pub(crate) centre_absolute: bool,
    /// Bit n: `#CS DEF [n]` defined CS n (always the identity: `decoder::interp::transform`).
    pub(crate) cs_defined: u64,
    /// A CS was defined: `#CS ON` without an id selects the last one.
    pub(crate) cs_last_defined: bool,
    /// G151 / `#SPLINE ON`.
    pub spline: bool,
    pub(crate) spline_type: SplineCommand,
    /// `#HSC ON`.
    pub(crate) hsc: bool,
    /// Programmed end position of the last block in machine coordinates (mm / degrees).
    pub pos: Position,
}

impl Modal {
    /// The modal G codes in effect, in the order an HMI lists them: motion, plane,
    /// absolute/incremental, units, feed mode, radius compensation, zero offset.
    pub fn g_codes(&self) -> [&'static str; 7] {
        use crate::queue::Plane;
        const ZERO_OFFSETS: [&str; 7] = ["G53", "G54", "G55", "G56", "G57", "G58", "G59"];
        [
            match self.motion {
                MotionMode::Rapid => "G00",
                MotionMode::Linear => "G01",
                MotionMode::ArcCw => "G02",
                MotionMode::ArcCcw => "G03",
            },
            match self.plane {
                Plane::Xy => "G17",
                Plane::Zx => "G18",
                Plane::Yz => "G19",
            },
            if self.absolute { "G90" } else { "G91" },
            match self.units {
                Units::Metric => "G71",
                Units::Inch => "G70",
            },
            match self.feed_mode {
                FeedMode::PerMinute => "G94",
                FeedMode::PerRevolution => "G95",
            },
            match self.radius_comp {
                RadiusComp::Off => "G40",
                RadiusComp::Left => "G41",
                RadiusComp::Right => "G42",
            },
            ZERO_OFFSETS.get(self.zero_offset).copied().unwrap_or("G54"),
        ]
    }

    /// The channel defaults a program start restores; the position is the machine's.
    pub fn defaults(pos: Position) -> Self {
        Modal {
            motion: MotionMode::Linear,
            plane: Plane::Xy,
            absolute: true,
            feed_mm_per_min: 0.0,
            feed_mm_per_rev: 0.0,
            feed_mode: FeedMode::PerMinute,
            units: Units::Metric,
            g92_offset: [0.0; MAX_AXES],
            block_end: BlockEnd::Continuous,
            spindle: Spindle::Off,
            spindle_rpm: 0.0,
            coolant_mist: false,
            coolant_flood: false,
            tool: 0,
            tool_offset: 0,
            zero_offset: 0,
            radius_comp: RadiusComp::Off,
            contouring: false,
            contour_dev_mm: DEFAULT_PATH_DEV_MM,
            centre_absolute: false,
            cs_defined: 0,
            cs_last_defined: false,
            spline: false,
            spline_type: SplineCommand::TypeAkima,
            hsc: false,
            pos,
        }
    }

    /// The cross-block state a motion block carries to motion (`contour_here`: G61 in the
    /// block).
    pub(crate) fn path_mode(&self, contour_here: bool) -> crate::queue::PathMode {
        use crate::queue::{CompSide, PathMode, SplineKind};
        PathMode {
            contour_dev_mm: (self.contouring || contour_here).then_some(self.contour_dev_mm),
            comp: match self.radius_comp {
                RadiusComp::Off => CompSide::Off,
                RadiusComp::Left => CompSide::Left,
                RadiusComp::Right => CompSide::Right,
            },
            tool_offset: self.tool_offset,
            spline: self.spline.then_some(match self.spline_type {
                SplineCommand::TypeBspline => SplineKind::BSpline,
                _ => SplineKind::Akima,
            }),
        }
    }

    /// The cross-block function that forbids `#FLUSH`, if one is active: its error id and
    /// name. TRC, spline and HSC do (TF5200 diagnosis IDs 20651, 120102, 120434); polynomial
    /// contouring does not (kernels since V2.10.1503.08, TF5200 "Flushing NC channel"): the
    /// motion suppresses the blend at the motion blocks around the flush.
    pub(crate) fn flush_refusal(&self) -> Option<(u32, &'static str)> {
        use crate::lang::codes;
        if self.radius_comp != RadiusComp::Off {
            Some((codes::FLUSH_UNDER_TRC, "tool radius compensation"))
        } else if self.spline {
            Some((codes::FLUSH_UNDER_SPLINE, "spline interpolation"))
        } else if self.hsc {
            Some((codes::FLUSH_UNDER_HSC, "#HSC"))
        } else {
            None
        }
    }
}

/// The outcome of a block's G words beyond the modal groups.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct BlockGs {
    /// G4 in this block: the X word is the dwell time in seconds.
    pub dwell: bool,
    /// G53 in this block: coordinates are machine coordinates for this block only.
    pub(crate) machine_coords: bool,
    /// G61: contouring at this block's end only.
    pub(crate) contour_this_block: bool,
    /// G92: the block's axis words set the reference point offset; no motion.
    pub(crate) set_reference: bool,
    /// G60 / G09 / G900 / G901: stop at this block's end (state only, as `BlockEnd`).
    pub(crate) stop_this_block: bool,
    /// G130: the block's axis words are acceleration weightings in percent, not positions
    /// (TF5200 programming manual, "Acceleration weighting"); no motion.
    pub(crate) axis_weights: bool,
}

/// Apply one G code. `false` for a G code the channel does not know or refuses (the parser
/// has already said which).
#[must_use]
pub(crate) fn apply_g(m: &mut Modal, g: u32, b: &mut BlockGs) -> bool {
    match g {
        0 => m.motion = MotionMode::Rapid,
        1 => m.motion = MotionMode::Linear,
        2 => m.motion = MotionMode::ArcCw,
        3 => m.motion = MotionMode::ArcCcw,
        4 => b.dwell = true,
        17 => m.plane = Plane::Xy,
        18 => m.plane = Plane::Zx,
        19 => m.plane = Plane::Yz,
        40 => m.radius_comp = RadiusComp::Off,
        41 => m.radius_comp = RadiusComp::Left,
        42 => m.radius_comp = RadiusComp::Right,
        53 => {
            b.machine_coords = true;
            m.zero_offset = 0;
        }
        54..=59 => m.zero_offset = (g - 53) as usize,
        61 => b.contour_this_block = true,
        60 | 9 | 900 | 901 => b.stop_this_block = true,
        130 => b.axis_weights = true,
        70 => m.units = Units::Inch,
        71 => m.units = Units::Metric,
        90 => m.absolute = true,
        91 => m.absolute = false,
        92 => b.set_reference = true,
        94 => m.feed_mode = FeedMode::PerMinute,
        95 => m.feed_mode = FeedMode::PerRevolution,
        // S is a spindle speed: the only meaning ncchannel has for it (G96 is refused).
        97 => {}
        359 => m.block_end = BlockEnd::Continuous,
        360 => m.block_end = BlockEnd::ExactStop,
        150 => m.spline = false,
        151 => m.spline = true,
        161 => m.centre_absolute = true,
        162 => m.centre_absolute = false,
        260 => m.contouring = false,
        261 => m.contouring = true,
        // The rest of ISG's list that ncchannel accepts without effect (lang::dialect).
        _ => return matches!(g_support(g), Some((Support::Inert, _))),
    }
    true
}

/// Apply an M function's modal effect (spindle, coolant). Program ends are handled by the
/// decoder; other M functions are PLC outputs with no modal state.
pub(crate) fn apply_m(m: &mut Modal, code: u32) {
    match code {
        3 => m.spindle = Spindle::Cw,
        4 => m.spindle = Spindle::Ccw,
        5 => m.spindle = Spindle::Off,
        7 => m.coolant_mist = true,
        8 => m.coolant_flood = true,
        9 => {
            m.coolant_mist = false;
            m.coolant_flood = false;
        }
        _ => {}
    }
}

/// Zero-offset table: G54..G59 → offset per axis (mm / degrees).
pub type ZeroOffsets = [[f64; MAX_AXES]; 6];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_dev_comes_from_the_bracket() {
        assert_eq!(path_dev_mm("[DEV PATH_DEV=0.02 CONST_VEL=1]"), Some(0.02));
        assert_eq!(path_dev_mm("[DIST RELEASE_DIST=1]"), None);
        assert_eq!(path_dev_mm("[DEV PATH_DEV=x]"), None);
    }
}
