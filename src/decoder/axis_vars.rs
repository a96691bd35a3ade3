//! Axis variables a program reads (TF5200 programming manual, "Axis-specific variables
//! (V.A.)"): `V.A.ABS.<axis>` / `V.A.ABS[<index>]`, the axis' coordinate at the end of the
//! previous block in the active coordinate system. The parser refuses the manual's other
//! V.A. fields by name (docs/nc-language.md, "Constructs of real programs").

use super::*;

impl Decoder {
    /// `V.A.ABS.<axis>`: the axis' end point of the previous block in program coordinates
    /// (zero offset and G92 taken off, in inch under G70); `None` for an axis the channel
    /// does not have.
    pub(super) fn axis_abs(&self, id: crate::lang::AxisId) -> Option<f64> {
        use crate::lang::AxisId;
        let i = match id {
            AxisId::Letter(l) => crate::queue::AXIS_LETTERS.iter().position(|&a| a == l)?,
            AxisId::Index(n) => usize::try_from(n).ok()?,
        };
        if !*self.settings.axes.get(i)? {
            return None;
        }
        let off = self.program_offset(modal::BlockGs::default());
        Some((self.modal.pos[i] - off[i]) / self.length_scale(i))
    }
}
