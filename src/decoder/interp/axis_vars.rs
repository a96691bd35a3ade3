//! Machine data a program reads: `V.A.ABS.<axis>` / `V.A.ABS[<index>]`, the axis'
//! coordinate at the end of the previous block in the active coordinate system (TF5200
//! programming manual, "Axis-specific variables (V.A.)"), `V.G.WZ_AKT.*` / `V.G.WZ[j].*`,
//! tool data from the tool list (TF5200 "Access to tool data in the NC program (V.G.WZ..)"),
//! `V.G.NP[i].V.<axis>`, the zero-offset groups, also written (programming manual, "Zero
//! offsets"), and
//! `V.G.M_FCT[n].SYNCH` / `V.G.H_FCT[n].SYNCH`, a technology function's synchronisation
//! type (TF5200 "Parameterising the synchronisation methods"). The parser
//! refuses the manual's other V.A. and V.G. variables by name (docs/nc-language.md,
//! "Constructs of real programs").

use super::Interpreter;
use crate::decoder::error::{DecodeError, Res};
use crate::decoder::modal;
use crate::lang::codes;
use crate::lang::ToolFieldId;
use crate::lang::VarKey;
use crate::params::tools::ToolData;
use crate::vocab::axis::{AXIS_LETTERS, MAX_AXES};

impl Interpreter {
    /// `V.A.ABS.<axis>`: the axis' end point of the previous block in program coordinates
    /// (zero offset and G92 taken off, in inch under G70); `None` for an axis the channel
    /// does not have.
    pub(super) fn axis_abs(&self, id: crate::lang::AxisId) -> Option<f64> {
        let i = self.axis_slot(id)?;
        let off = self.program_offset(modal::BlockGs::default());
        Some((self.modal.pos[i] - off[i]) / self.length_scale(i))
    }
}

impl Interpreter {
    /// Tool data set `d` (`None`: the active D); D0 is all zeros; `None` for a D the tool
    /// list does not have.
    pub(super) fn tool(&self, d: Option<u32>) -> Option<ToolData> {
        let d = d.unwrap_or(self.modal.tool_offset);
        if d == 0 {
            return Some(ToolData {
                d: 0,
                radius_mm: 0.0,
                length_mm: 0.0,
                valid: true,
                axis_offsets_mm: [0.0; MAX_AXES],
            });
        }
        // Sorted by D (params/tools.rs): a start-up list of 10,000 tools costs 14 steps.
        self.tools
            .binary_search_by_key(&d, |t| t.d)
            .ok()
            .map(|i| self.tools[i])
    }

    /// The active D and its radius, mm (0 for a D the tool list lacks).
    pub(in crate::decoder) fn active_tool(&self) -> (u32, f64) {
        (
            self.modal.tool_offset,
            self.tool_radius(None).unwrap_or(0.0),
        )
    }

    /// Radius of tool data set `d` (`None`: the active D), mm.
    pub(super) fn tool_radius(&self, d: Option<u32>) -> Option<f64> {
        self.tool(d).map(|t| t.radius_mm)
    }

    /// `V.G.WZ_AKT.<field>` / `V.G.WZ[j].<field>`: length and axis offsets in mm, the
    /// validity flag 1 or 0.
    pub(super) fn tool_field(&self, d: Option<u32>, field: ToolFieldId) -> Option<f64> {
        let t = self.tool(d)?;
        Some(match field {
            ToolFieldId::Length => t.length_mm,
            ToolFieldId::Valid => f64::from(u8::from(t.valid)),
            ToolFieldId::AxisOffset(a) => t.axis_offsets_mm[self.axis_slot(a)?],
        })
    }

    /// `V.G.NP[group].V.<axis>`: the offset group `group` holds on a configured axis, mm;
    /// group 0 is G53 (no offset), 1 … 6 are G54 … G59; `None` beyond.
    pub(super) fn zero_offset_of(&self, group: u32, axis: crate::lang::AxisId) -> Option<f64> {
        let i = self.axis_slot(axis)?;
        match group {
            0 => Some(0.0),
            g => Some(self.zero_offsets.get(g as usize - 1)?[i]),
        }
    }

    /// `V.G.NP[group].V.<axis> = value`: a program sets group `group`'s offset on an axis, mm
    /// (TF5200 programming manual, "Zero offsets (G53/G54/...G59)": `V.G.NP[1].V.X=10`
    /// then `G54`). The value stays in the table until the next write: it is the channel's
    /// zero-offset data, not a program's modal state, so neither a reset nor a new program
    /// takes it back. Group 0 (G53, no offset) and groups past G59 cannot be written.
    pub(super) fn set_zero_offset(&mut self, key: &VarKey<'_>, value_mm: f64) -> Res {
        let VarKey::ZeroOffset { group, axis } = *key else {
            // Only a `V.G.NP` target resolves here; anything else is refused, never dropped.
            return Err(DecodeError::new(
                codes::UNSUPPORTED,
                format!("{key}: not a zero offset"),
            ));
        };
        let Some(i) = self.axis_slot(axis) else {
            return Err(DecodeError::new(
                codes::UNSUPPORTED,
                format!("{key}: no such axis in this channel"),
            ));
        };
        match usize::try_from(group).ok().and_then(|g| g.checked_sub(1)) {
            Some(g) if g < self.zero_offsets.len() => {
                self.zero_offsets[g][i] = value_mm;
                Ok(())
            }
            _ => Err(DecodeError::new(
                codes::UNSUPPORTED,
                format!(
                    "{key}: only groups 1 … 6 (G54 … G59) can be written; group 0 is G53, \
                     no offset"
                ),
            )),
        }
    }

    /// The slot of a configured axis named by letter or by channel axis index.
    fn axis_slot(&self, id: crate::lang::AxisId) -> Option<usize> {
        use crate::lang::AxisId;
        let i = match id {
            AxisId::Letter(l) => AXIS_LETTERS.iter().position(|&a| a == l)?,
            AxisId::Index(n) => usize::try_from(n).ok()?,
        };
        self.settings.axes.get(i).copied()?.then_some(i)
    }
}

impl Interpreter {
    /// `V.G.M_FCT[n].SYNCH` / `V.G.H_FCT[n].SYNCH` (`h`): the function's synchronisation
    /// value from the channel's table (decoder/interp/techno.rs).
    pub(super) fn function_sync(&self, h: bool, n: u32) -> Option<f64> {
        self.techno.sync_value(h, n)
    }
}
