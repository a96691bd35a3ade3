//! What the decoder needs from the configuration (runtime.toml, channel parameters), and its
//! per-tick budgets.

use std::sync::Arc;

use super::modal::ZeroOffsets;
use crate::geometry::SoftLimits;
use crate::lang::block::AxisName;
use crate::vocab::axis::{AXIS_LETTERS, MAX_AXES};
use crate::vocab::techno::TechnoTable;

/// What the decoder needs from the configuration.
#[derive(Debug, Clone)]
pub struct DecoderSettings {
    /// Lines decoded per tick at most (runtime.toml `decoder.blocks_per_tick`).
    pub blocks_per_tick: usize,
    /// Subroutine nesting depth at most (main program = level 0).
    pub(crate) max_depth: usize,
    /// Axes the channel has, by letter index of `AXIS_LETTERS`.
    pub axes: [bool; MAX_AXES],
    /// The name of the axis in each slot (`X`, or `X1` for an axis list's `X1`): a program
    /// writes `X10` for a one-letter name, `X1=10` for a longer one. Resolved once at set-up.
    pub(crate) axis_names: [AxisName; MAX_AXES],
    pub(crate) zero_offsets: ZeroOffsets,
    /// How far the end point may lie off the circle, mm.
    pub(crate) arc_tolerance_mm: f64,
    /// Software limits per axis (runtime.toml `soft_limit_min_mm` / `soft_limit_max_mm`),
    /// mm in machine coordinates, by `AXIS_LETTERS` index: a block whose end point or arc
    /// lies outside is refused before it moves (21897).
    pub(crate) soft_limits_mm: [SoftLimits; MAX_AXES],
    /// Global subroutines the channel calls by itself: at program start (P-CHAN-00119), before
    /// the main program's M02/M30 (P-CHAN-00252) and for M6 (P-CHAN-00118).
    pub implicit: crate::params::channel::ImplicitSubroutines,
    /// The kernel's error texts by id (start-up list P-STUP-00168): an error with a text there
    /// is reported with it, ncchannel's detail after it in parentheses.
    pub(crate) error_texts: Option<Arc<crate::params::error_texts::ErrorTexts>>,
    /// M/H/S/T functions: synchronisation types, process times (the channel list's
    /// `m_synch[i]`, `h_synch[i]`, `spindel[0].*`, `tool.*`).
    pub techno: TechnoTable,
    /// The channel's list of external variables (start-up list `ve_var[i]`, P-STUP-00146):
    /// `None` leaves V.E. variables free.
    pub ext_vars: Option<Arc<crate::params::ext_vars::ExtVarTable>>,
}

/// Each slot named by its letter, `X` to `C`.
pub(crate) fn letter_names() -> [AxisName; MAX_AXES] {
    AXIS_LETTERS.map(|l| AxisName::new(std::str::from_utf8(&[l]).unwrap_or("X")).expect("a letter"))
}

/// Values `#VAR` declarations may make in one tick before decoding waits for the next: a
/// 100,000-element declaration costs ~0.1 ms to fill, so a tick does at most about two
/// such, whatever the NC text (a line of ten took 15 s in one tick before).
pub const DECLARED_VALUES_PER_TICK: usize = 100_000;

/// Bytes of NC text the decoder reads per tick at most (files and stream alike; one line may
/// end beyond it). Real blocks are tens of bytes, so `blocks_per_tick` lines stay far inside
/// it; lines thousands of bytes long (comments in a `#COMMENT` block) no longer make a tick's
/// work grow with them (64 lines of 60 KB took 30 ms a tick before).
pub const LINE_BYTES_PER_TICK: usize = 64 * 1024;

impl Default for DecoderSettings {
    fn default() -> Self {
        DecoderSettings {
            blocks_per_tick: 64,
            max_depth: 20,
            axes: [true, true, true, false, false, false],
            axis_names: letter_names(),
            zero_offsets: [[0.0; MAX_AXES]; 6],
            arc_tolerance_mm: 0.01,
            soft_limits_mm: [SoftLimits::default(); MAX_AXES],
            implicit: Default::default(),
            error_texts: None,
            techno: TechnoTable::kernel_defaults(),
            ext_vars: None,
        }
    }
}
