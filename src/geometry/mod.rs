//! Geometry shared by the decoder and motion: circles of G2/G3 blocks (centre, sweep, extent)
//! and the software limits a move is checked against. Below both, so that neither depends on
//! the other; it knows moves (`queue`) and error numbers (`lang::codes`), nothing of either.

pub mod arc;

/// One axis's software limits, mm (machine coordinates); unbounded by default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SoftLimits {
    pub min_mm: f64,
    pub max_mm: f64,
}

impl Default for SoftLimits {
    fn default() -> Self {
        SoftLimits {
            min_mm: f64::NEG_INFINITY,
            max_mm: f64::INFINITY,
        }
    }
}
