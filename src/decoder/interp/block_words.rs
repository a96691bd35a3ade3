//! Step 1's result for an ordinary block (module `words`): its words by meaning, values
//! evaluated, not yet applied. One is reused from block to block.

use crate::decoder::error::{DecodeError, Res};
use crate::lang::codes;
use crate::vocab::axis::MAX_AXES;

/// M or H functions one block may hold.
pub(super) const MAX_FUNCTIONS: usize = 8;
/// G functions one block may hold (a CAM header writes six or seven).
const MAX_GS: usize = 16;

/// Step 1's result: the block's words by meaning, values evaluated, not yet applied.
#[derive(Debug, Default)]
pub(super) struct Words {
    /// G numbers in written order, with their columns.
    pub(super) gs: [(u32, u32); MAX_GS],
    pub(super) n_gs: usize,
    /// Axis values as programmed (program units), by `AXIS_LETTERS` index.
    /// Plain values and a bit mask rather than `Option`s: this struct is built for every
    /// block, and reading `Option<f64>`s back showed as store-forwarding stalls in a profile.
    pub(super) axes: [f64; MAX_AXES],
    /// Bit i: axis i is programmed.
    pub(super) axes_set: u8,
    /// Column of an X word on a channel without X: an error unless X is a dwell time.
    pub(super) unconfigured_x_col: Option<u32>,
    /// I, J, K as programmed (program units).
    pub(super) ijk: [Option<f64>; 3],
    /// R as programmed (program units).
    pub(super) radius: Option<f64>,
    /// F as programmed, with its column.
    pub(super) feed: Option<(f64, u32)>,
    /// S, rpm.
    pub(super) spindle_rpm: Option<f64>,
    pub(super) tool: Option<u32>,
    /// The T word's column (valid with `tool`).
    pub(super) tool_col: u32,
    /// D, with its column.
    pub(super) tool_offset: Option<(u32, u32)>,
    /// `G04 <t>` / `G04 P1` / `G04 X<t>` / `G04 S<n>`: the dwell time in seconds.
    pub(super) dwell_s: Option<f64>,
    pub(super) ms: [u32; MAX_FUNCTIONS],
    /// The value of each M programmed with one (`M200=1200`), by its place in `ms`.
    pub(super) m_values: [Option<f64>; MAX_FUNCTIONS],
    pub(super) n_ms: usize,
    pub(super) hs: [u32; MAX_FUNCTIONS],
    pub(super) h_values: [Option<f64>; MAX_FUNCTIONS],
    pub(super) n_hs: usize,
    /// G800–G819 (number, column): an implicit subroutine call at the end of the block.
    pub(super) call: Option<(u32, u32)>,
    /// Its transfer parameters as `@P` number and value (gaps left out).
    pub(super) call_params: Vec<(u32, f64)>,
}

impl Words {
    /// Empty again for the next block. The fixed arrays keep their stale entries: only the
    /// first `n_*` count, so clearing them would be a memset per block for nothing.
    pub(super) fn clear(&mut self) {
        self.n_gs = 0;
        self.axes_set = 0;
        self.unconfigured_x_col = None;
        self.ijk = [None; 3];
        self.radius = None;
        self.feed = None;
        self.spindle_rpm = None;
        self.tool = None;
        self.tool_offset = None;
        self.dwell_s = None;
        self.n_ms = 0;
        self.n_hs = 0;
        // `call_params` count only with `call`, and are cleared when it is set.
        self.call = None;
    }

    pub(super) fn gs(&self) -> &[(u32, u32)] {
        &self.gs[..self.n_gs]
    }

    pub(super) fn push_g(&mut self, g: u32, col: u32) -> Res {
        if self.n_gs == MAX_GS {
            return Err(DecodeError::new(
                codes::SYNTAX,
                "too many G functions in one block",
            ));
        }
        self.gs[self.n_gs] = (g, col);
        self.n_gs += 1;
        Ok(())
    }
    pub(super) fn ms(&self) -> &[u32] {
        &self.ms[..self.n_ms]
    }
    pub(super) fn has_m(&self, m: u32) -> bool {
        self.ms().contains(&m)
    }
    pub(super) fn hs(&self) -> &[u32] {
        &self.hs[..self.n_hs]
    }
}
