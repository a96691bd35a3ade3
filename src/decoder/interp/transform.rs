//! The neutral transformation commands (`lang::transform`): accepted with a warning that
//! they change nothing, as long as the path stays as it is. A coordinate system with a shift
//! or a rotation, or the selection of one never defined, is refused by name (900133): ncchannel
//! models no transformation.

use super::Interpreter;
use crate::decoder::error::{DecodeError, Res};
use crate::decoder::note::Note;
use crate::lang::block::{Expr, Transform};
use crate::lang::codes;

/// Most CS ids kept: 1 to 63 (bits of a `u64`); the TF5200 programming manual gives no
/// largest id, and a program that numbers more CSs than this is refused rather than
/// followed into an unbounded table.
const MAX_CS_ID: u32 = 63;

impl Interpreter {
    /// `#TRAFO OFF`, `#CS OFF`, `#CS DEF/ON` of an identity CS: the warning, or the refusal.
    pub(super) fn transform(&mut self, t: &Transform, notes: &mut Vec<Note>) -> Res {
        match t {
            Transform::Off { .. } => {}
            Transform::CsDefine {
                text, id, values, ..
            } => {
                for v in values {
                    if self.eval(v)? != 0.0 {
                        return Err(not_modelled(crate::lang::transform::not_identity(text)));
                    }
                }
                let id = self.cs_id(id.as_ref(), text)?;
                self.modal.cs_defined |= id.map_or(0, |id| 1 << id);
                self.modal.cs_last_defined = true;
            }
            Transform::CsSelect { text, id } => {
                let defined = match self.cs_id(id.as_ref(), text)? {
                    Some(id) => self.modal.cs_defined & (1 << id) != 0,
                    None => self.modal.cs_last_defined,
                };
                if !defined {
                    return Err(not_modelled(format!(
                        "#{text}: no coordinate system defined (ncchannel models only the \
                         identity CS, defined by #CS DEF with all values 0)"
                    )));
                }
            }
        }
        notes.push(Note::Warning {
            code: codes::NEUTRAL_TRANSFORMATION,
            msg: format!(
                "#{}: no transformation is active in ncchannel; the command changes nothing",
                t.text()
            ),
        });
        Ok(())
    }

    /// A CS id: a whole number 1 to [`MAX_CS_ID`], or `None` when not programmed.
    fn cs_id(&self, id: Option<&Expr>, text: &str) -> Res<Option<u32>> {
        let Some(id) = id else {
            return Ok(None);
        };
        let v = self.eval(id)?;
        match crate::lang::range::whole_u32(v) {
            Some(n) if (1..=MAX_CS_ID).contains(&n) => Ok(Some(n)),
            _ => Err(DecodeError::new(
                codes::BAD_VALUE,
                format!("#{text}: CS id {v} outside 1 to {MAX_CS_ID}"),
            )),
        }
    }
}

fn not_modelled(msg: String) -> DecodeError {
    DecodeError::new(codes::UNSUPPORTED, msg)
}
