//! Machine data a program reads: `V.A.ABS.<axis>` / `V.A.ABS[<index>]`, the axis'
//! coordinate at the end of the previous block in the active coordinate system (TF5200
//! programming manual, "Axis-specific variables (V.A.)"), and `V.G.WZ_AKT.R` /
//! `V.G.WZ[j].R`, tool radii from the tool list ("Global variables (V.G.)"), and
//! `V.G.M_FCT[n].SYNCH` / `V.G.H_FCT[n].SYNCH`, a technology function's synchronisation
//! type (TF5200 "Parameterising the synchronisation methods"). The parser
//! refuses the manual's other V.A. and V.G. variables by name (docs/nc-language.md,
//! "Constructs of real programs").

use super::Interpreter;
use crate::decoder::modal;
use crate::vocab::axis::AXIS_LETTERS;

impl Interpreter {
    /// `V.A.ABS.<axis>`: the axis' end point of the previous block in program coordinates
    /// (zero offset and G92 taken off, in inch under G70); `None` for an axis the channel
    /// does not have.
    pub(super) fn axis_abs(&self, id: crate::lang::AxisId) -> Option<f64> {
        use crate::lang::AxisId;
        let i = match id {
            AxisId::Letter(l) => AXIS_LETTERS.iter().position(|&a| a == l)?,
            AxisId::Index(n) => usize::try_from(n).ok()?,
        };
        if !*self.settings.axes.get(i)? {
            return None;
        }
        let off = self.program_offset(modal::BlockGs::default());
        Some((self.modal.pos[i] - off[i]) / self.length_scale(i))
    }
}

impl Interpreter {
    /// Radius of tool data set `d` (`None`: the active D), mm; D0 is radius 0; `None` for a
    /// D the tool list does not have.
    pub(super) fn tool_radius(&self, d: Option<u32>) -> Option<f64> {
        let d = d.unwrap_or(self.modal.tool_offset);
        if d == 0 {
            return Some(0.0);
        }
        self.tool_radii
            .iter()
            .find(|(n, _)| *n == d)
            .map(|(_, r)| *r)
    }
}

impl Interpreter {
    /// `V.G.M_FCT[n].SYNCH` / `V.G.H_FCT[n].SYNCH` (`h`): the function's synchronisation
    /// value from the channel's table (decoder/interp/techno.rs).
    pub(super) fn function_sync(&self, h: bool, n: u32) -> Option<f64> {
        self.techno.sync_value(h, n)
    }
}
