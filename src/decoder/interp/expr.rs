//! The bridge between the language's expression evaluator and the channel's variable store.

use crate::lang::block::{Expr, VarRef};
use crate::lang::eval::{self, VarKey, Vars};

use crate::decoder::error::DecodeError;
use crate::decoder::vars::{VarSlot, VarStore};
use crate::lang::codes;

/// Index bound of the store's keys: ISG arrays have at most three dimensions.
pub(super) fn slot(k: &VarKey<'_>) -> Option<VarSlot> {
    pub(super) fn idx(v: &[u32]) -> Option<([i64; 3], u8)> {
        if v.len() > 3 {
            return None;
        }
        let mut out = [0i64; 3];
        for (o, &i) in out.iter_mut().zip(v) {
            *o = i as i64;
        }
        Some((out, v.len() as u8))
    }
    Some(match k {
        VarKey::P { number, indices } => {
            let (indices, dims) = idx(indices)?;
            VarSlot::P {
                number: *number,
                indices,
                dims,
            }
        }
        VarKey::V {
            scope,
            name,
            indices,
        } => {
            let (indices, dims) = idx(indices)?;
            VarSlot::V {
                scope: *scope,
                name: (*name).into(),
                indices,
                dims,
            }
        }
        VarKey::CycleParam(n) => VarSlot::CycleParam(*n),
        // Read from the decoder's position, never stored (`Env`).
        VarKey::AxisAbs(_)
        | VarKey::ToolRadius(_)
        | VarKey::ToolData { .. }
        | VarKey::ZeroOffset { .. }
        | VarKey::FunctionSync { .. } => return None,
    })
}

/// What an expression in a running program sees: the variable store and, for `V.A.ABS`,
/// the decoder's position.
pub(super) struct Env<'d>(pub &'d super::Interpreter);

impl Vars for Env<'_> {
    fn get(&self, key: &VarKey<'_>) -> Option<f64> {
        match key {
            VarKey::AxisAbs(id) => self.0.axis_abs(*id),
            VarKey::ToolRadius(d) => self.0.tool_radius(*d),
            VarKey::ToolData { tool, field } => self.0.tool_field(*tool, *field),
            VarKey::ZeroOffset { group, axis } => self.0.zero_offset_of(*group, *axis),
            VarKey::FunctionSync { h, number } => self.0.function_sync(*h, *number),
            _ => self.0.vars.nc_get(&slot(key)?),
        }
    }

    fn get_str(&self, key: &VarKey<'_>) -> Option<&str> {
        Vars::get_str(&self.0.vars, key)
    }

    fn why_missing(&self, key: &VarKey<'_>) -> Option<eval::EvalError> {
        Vars::why_missing(&self.0.vars, key)
    }
}

/// What a program sees of the store: V.E. variables as their list declares them.
impl Vars for VarStore {
    fn get(&self, key: &VarKey<'_>) -> Option<f64> {
        self.nc_get(&slot(key)?)
    }

    fn get_str(&self, key: &VarKey<'_>) -> Option<&str> {
        self.nc_get_str(&slot(key)?)
    }

    fn why_missing(&self, key: &VarKey<'_>) -> Option<eval::EvalError> {
        let e = VarStore::why_missing(self, &slot(key)?)?;
        Some(eval::EvalError::Refused(e.code(), e.to_string()))
    }
}

pub(super) fn err(e: eval::EvalError) -> DecodeError {
    e.into()
}

pub(crate) fn eval(e: &Expr, vars: &dyn Vars) -> Result<f64, DecodeError> {
    eval::eval(e, vars).map_err(err)
}

/// [`eval::eval_value`]: a value that may be a string.
pub(crate) fn eval_value(e: &Expr, vars: &dyn Vars) -> Result<eval::Val, DecodeError> {
    eval::eval_value(e, vars).map_err(err)
}

pub(crate) fn resolve(v: &VarRef, vars: &dyn Vars) -> Result<VarSlot, DecodeError> {
    let k = eval::resolve(v, vars).map_err(err)?;
    slot(&k)
        .ok_or_else(|| DecodeError::new(codes::BAD_VALUE, format!("{k}: more than three indices")))
}
