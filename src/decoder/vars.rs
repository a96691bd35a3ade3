//! Parameters and variables of a channel: P parameters, V.P. V.L. V.S. V.E. and cycle @P.
//!
//! Lifetimes follow ISG: V.P. and P are program-global and re-initialised at program start
//! (streaming: at stream start), V.L. belong to a program level and are seen by its callees,
//! V.S. survive reset, V.E. are written from outside (channel API, ADS).

use std::collections::HashMap;

use crate::lang::block::VScope;

/// Array indices of a variable, evaluated. At most three dimensions, as ISG arrays have.
pub type Indices = [i64; 3];

/// A variable with its indices evaluated: the key of the store.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum VarSlot {
    P {
        number: u32,
        indices: Indices,
        dims: u8,
    },
    V {
        scope: VScope,
        name: Box<str>,
        indices: Indices,
        dims: u8,
    },
    CycleParam(u32),
}

/// Most parameters in use are small plain numbers: keep those in a flat table.
const FLAT_P: usize = 1024;

/// Bound on variables of one kind, so a runaway program cannot eat the host's memory.
pub const MAX_VARIABLES: usize = 1 << 20;

#[derive(Debug, Clone, PartialEq)]
pub enum VarError {
    Undefined(String),
    TooMany,
}

#[derive(Debug, Default)]
pub struct VarStore {
    /// P1..P1023 without indices; NaN = never assigned.
    p_flat: Vec<f64>,
    p_other: HashMap<VarSlot, f64>,
    program: HashMap<VarSlot, f64>,
    /// One map per program level, innermost last.
    local: Vec<HashMap<VarSlot, f64>>,
    self_retaining: HashMap<VarSlot, f64>,
    external: HashMap<VarSlot, f64>,
    /// Cycle parameters per level (`@P`), innermost last.
    cycle: Vec<Vec<(u32, f64)>>,
}

impl VarStore {
    pub fn new() -> Self {
        VarStore {
            p_flat: vec![f64::NAN; FLAT_P],
            local: vec![HashMap::new()],
            cycle: vec![Vec::new()],
            ..Default::default()
        }
    }

    /// Program (or stream) start: P and V.P. start empty, one level of V.L.
    pub fn start_program(&mut self) {
        self.p_flat.iter_mut().for_each(|v| *v = f64::NAN);
        self.p_other.clear();
        self.program.clear();
        self.local.clear();
        self.local.push(HashMap::new());
        self.cycle.clear();
        self.cycle.push(Vec::new());
    }

    /// Channel reset: everything but V.S. and V.E. goes.
    pub fn reset(&mut self) {
        self.start_program();
    }

    /// A subroutine or cycle level begins.
    pub fn push_level(&mut self, cycle_params: Vec<(u32, f64)>) {
        self.local.push(HashMap::new());
        self.cycle.push(cycle_params);
    }

    pub fn pop_level(&mut self) {
        if self.local.len() > 1 {
            self.local.pop();
            self.cycle.pop();
        }
    }

    fn flat_index(k: &VarSlot) -> Option<usize> {
        match k {
            VarSlot::P {
                number, dims: 0, ..
            } if (*number as usize) < FLAT_P => Some(*number as usize),
            _ => None,
        }
    }

    pub fn get(&self, k: &VarSlot) -> Option<f64> {
        if let Some(i) = Self::flat_index(k) {
            let v = self.p_flat[i];
            return (!v.is_nan()).then_some(v);
        }
        match k {
            VarSlot::P { .. } => self.p_other.get(k).copied(),
            VarSlot::CycleParam(n) => {
                // @P of the innermost cycle level that has them.
                self.cycle
                    .iter()
                    .rev()
                    .find(|l| !l.is_empty())
                    .and_then(|l| l.iter().find(|(m, _)| m == n).map(|(_, v)| *v))
            }
            VarSlot::V { scope, .. } => match scope {
                VScope::Program => self.program.get(k).copied(),
                VScope::Local => self.local.iter().rev().find_map(|m| m.get(k).copied()),
                VScope::SelfRetaining => self.self_retaining.get(k).copied(),
                VScope::External => self.external.get(k).copied(),
            },
        }
    }

    pub fn set(&mut self, k: VarSlot, v: f64) -> Result<(), VarError> {
        if let Some(i) = Self::flat_index(&k) {
            self.p_flat[i] = v;
            return Ok(());
        }
        let map = match &k {
            VarSlot::P { .. } => &mut self.p_other,
            VarSlot::CycleParam(n) => {
                let n = *n;
                let level = self.cycle.last_mut().ok_or(VarError::TooMany)?;
                match level.iter_mut().find(|(m, _)| *m == n) {
                    Some(slot) => slot.1 = v,
                    None => level.push((n, v)),
                }
                return Ok(());
            }
            VarSlot::V { scope, .. } => match scope {
                VScope::Program => &mut self.program,
                VScope::Local => {
                    // An existing V.L. of a caller is updated where it lives.
                    let depth = self.local.iter().rposition(|m| m.contains_key(&k));
                    let idx = depth.unwrap_or(self.local.len() - 1);
                    &mut self.local[idx]
                }
                VScope::SelfRetaining => &mut self.self_retaining,
                VScope::External => &mut self.external,
            },
        };
        if map.len() >= MAX_VARIABLES && !map.contains_key(&k) {
            return Err(VarError::TooMany);
        }
        map.insert(k, v);
        Ok(())
    }

    /// V.E. written from outside the channel.
    pub fn set_external(&mut self, name: &str, v: f64) -> Result<(), VarError> {
        self.set(
            VarSlot::V {
                scope: VScope::External,
                name: name.to_ascii_uppercase().into(),
                indices: [0; 3],
                dims: 0,
            },
            v,
        )
    }

    pub fn get_external(&self, name: &str) -> Option<f64> {
        self.get(&VarSlot::V {
            scope: VScope::External,
            name: name.to_ascii_uppercase().into(),
            indices: [0; 3],
            dims: 0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(n: u32) -> VarSlot {
        VarSlot::P {
            number: n,
            indices: [0; 3],
            dims: 0,
        }
    }
    fn v(scope: VScope, name: &str) -> VarSlot {
        VarSlot::V {
            scope,
            name: name.into(),
            indices: [0; 3],
            dims: 0,
        }
    }

    #[test]
    fn lifetimes_follow_isg() {
        let mut s = VarStore::new();
        s.set(p(1), 10.0).unwrap();
        s.set(p(5000), 1.0).unwrap();
        s.set(v(VScope::SelfRetaining, "KEEP"), 7.0).unwrap();
        s.set(v(VScope::Program, "PG"), 3.0).unwrap();
        assert_eq!(s.get(&p(1)), Some(10.0));
        assert_eq!(s.get(&p(5000)), Some(1.0));
        s.reset();
        assert_eq!(s.get(&p(1)), None);
        assert_eq!(s.get(&p(5000)), None);
        assert_eq!(s.get(&v(VScope::Program, "PG")), None);
        assert_eq!(s.get(&v(VScope::SelfRetaining, "KEEP")), Some(7.0));
    }

    #[test]
    fn locals_are_seen_by_callees_and_die_with_their_level() {
        let mut s = VarStore::new();
        s.set(v(VScope::Local, "A"), 1.0).unwrap();
        s.push_level(vec![(1, 5.0)]);
        assert_eq!(s.get(&v(VScope::Local, "A")), Some(1.0));
        assert_eq!(s.get(&VarSlot::CycleParam(1)), Some(5.0));
        s.set(v(VScope::Local, "B"), 2.0).unwrap();
        s.set(v(VScope::Local, "A"), 3.0).unwrap();
        s.pop_level();
        assert_eq!(s.get(&v(VScope::Local, "B")), None);
        assert_eq!(s.get(&v(VScope::Local, "A")), Some(3.0));
        assert_eq!(s.get(&VarSlot::CycleParam(1)), None);
    }
}
