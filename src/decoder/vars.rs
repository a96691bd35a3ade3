//! Parameters and variables of a channel: P parameters, V.P. V.L. V.S. V.E. and cycle @P.
//!
//! Lifetimes follow ISG: V.P. and P are program-global and re-initialised at program start
//! (streaming: at stream start), V.L. belong to a program level and are seen by its callees,
//! V.S. survive reset, V.E. are written from outside (channel API, ADS).
//!
//! Memory is bounded per variable class in bytes, as ISG bounds it per class (TF5200
//! diagnosis 20967 "Memory for variables limited", counted per class V.P., V.S., V.E., V.L.):
//! a variable costs its name, 8 bytes a value and [`ENTRY_BYTES`] of bookkeeping. An array
//! is one entry — its name once, its values in one block — so declaring 100,000 elements
//! under a 3,900-character name costs 0.8 MB, not a copy of the name per element (which
//! cost 395 MB and a 524 ms tick). V.S. survive resets, so their bound is what keeps a
//! long-running channel from filling up over many programs.

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::lang::block::MAX_STRING;
use crate::lang::block::{VScope, VarType};
use crate::lang::codes::{
    ARRAY_INDEX_RANGE, EVAL_NUMBER_AS_STRING, EVAL_STRING_AS_NUMBER, EVAL_UNDEFINED,
    MAX_ARRAY_DIMS, MAX_ARRAY_ELEMENTS, STRING_TOO_LONG_FOR_VARIABLE, TOO_MANY_INDICES,
    VARIABLE_MEMORY_FULL, VARIABLE_OUT_OF_FORMAT, VARIABLE_READ_DENIED, VARIABLE_UNKNOWN,
    VARIABLE_WRITE_DENIED,
};
use crate::params::ext_vars::{ExtAccess, ExtVar, ExtVarTable};
use crate::source::loader::Loader;

/// Array indices of a variable, evaluated. At most three dimensions, as ISG arrays have.
pub(crate) type Indices = [i64; 3];

/// A variable with its indices evaluated: the key of the store.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
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

pub use crate::vocab::vars::{CLASS_BYTES, ENTRY_BYTES};

/// A variable class: each has its own [`CLASS_BYTES`] budget. ISG counts V.P., V.S., V.E.
/// and V.L. (diagnosis 20967's class parameter); P parameters outside the flat table are a
/// class of ours.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VarClass {
    P,
    Program,
    Local,
    SelfRetaining,
    External,
}

impl VarClass {
    fn of(scope: VScope) -> Self {
        match scope {
            VScope::Program => VarClass::Program,
            VScope::Local => VarClass::Local,
            VScope::SelfRetaining => VarClass::SelfRetaining,
            VScope::External => VarClass::External,
        }
    }

    /// The class as a program writes it.
    pub fn prefix(self) -> &'static str {
        match self {
            VarClass::P => "P",
            VarClass::Program => "V.P.",
            VarClass::Local => "V.L.",
            VarClass::SelfRetaining => "V.S.",
            VarClass::External => "V.E.",
        }
    }
}

/// Why the store refused a write.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VarError {
    #[error("memory for {} variables used up: {used} of {limit} bytes in use, {need} more needed", class.prefix())]
    Full {
        class: VarClass,
        used: usize,
        need: usize,
        limit: usize,
    },
    #[error("{0}: index outside the declared array")]
    OutOfRange(String),
    #[error("{0} is not a declared array")]
    NotDeclared(String),
    #[error("{0}: an array has at most {MAX_ARRAY_DIMS} indices")]
    TooManyIndices(String),
    #[error("{name} : STRING[{max}] cannot hold a string of {len} characters")]
    StringTooLong { name: String, len: usize, max: u8 },
    #[error("{0} is a STRING variable: a number cannot be assigned to it")]
    NumberToString(String),
    #[error("{0} holds numbers: a string cannot be assigned to it")]
    StringToNumber(String),
    #[error("{0} is not declared in the list of external variables")]
    UnknownExternal(String),
    #[error("{0} is READ_ONLY for NC programs (list of external variables)")]
    WriteDenied(String),
    #[error("{0} is WRITE_ONLY for NC programs (list of external variables)")]
    ReadDenied(String),
    #[error("{name}: {value} is outside {min} … {max}, the range of its type")]
    OutOfFormat {
        name: String,
        value: f64,
        min: f64,
        max: f64,
    },
}

impl VarError {
    /// 20967 memory used up, 21928 index outside the array, 20974 too many indices (TF5200
    /// diagnosis list); an element of an undeclared array is undefined (`codes::EVAL_UNDEFINED`).
    pub fn code(&self) -> u32 {
        match self {
            VarError::Full { .. } => VARIABLE_MEMORY_FULL,
            VarError::OutOfRange(_) => ARRAY_INDEX_RANGE,
            VarError::NotDeclared(_) => EVAL_UNDEFINED,
            VarError::TooManyIndices(_) => TOO_MANY_INDICES,
            VarError::StringTooLong { .. } => STRING_TOO_LONG_FOR_VARIABLE,
            VarError::NumberToString(_) => EVAL_NUMBER_AS_STRING,
            VarError::StringToNumber(_) => EVAL_STRING_AS_NUMBER,
            VarError::UnknownExternal(_) => VARIABLE_UNKNOWN,
            VarError::WriteDenied(_) => VARIABLE_WRITE_DENIED,
            VarError::ReadDenied(_) => VARIABLE_READ_DENIED,
            VarError::OutOfFormat { .. } => VARIABLE_OUT_OF_FORMAT,
        }
    }
}

/// One V. variable: a scalar (no sizes, one value) or an array, its values row-major. A
/// `STRING[n]` variable keeps its strings in `texts` and no numbers.
#[derive(Debug, Clone)]
struct Variable {
    sizes: [u32; 3],
    dims: u8,
    values: Box<[f64]>,
    texts: Option<Box<Texts>>,
}

/// The strings of a `STRING[max]` variable, row-major; each at most `max` characters.
#[derive(Debug, Clone)]
struct Texts {
    max: u8,
    values: Box<[Box<str>]>,
}

impl Variable {
    fn scalar(v: f64) -> Self {
        Variable {
            sizes: [0; 3],
            dims: 0,
            values: Box::new([v]),
            texts: None,
        }
    }

    /// Bytes this variable is charged under `name`.
    fn bytes(&self, name: &str) -> usize {
        match &self.texts {
            Some(t) => text_cost(name, t.values.len(), t.max),
            None => cost(name, self.values.len()),
        }
    }

    /// The position of an element, if `indices` (of which `dims` count) lie in the array.
    fn offset(&self, indices: &Indices, dims: u8) -> Option<usize> {
        if dims != self.dims {
            return None;
        }
        let mut at = 0usize;
        for (&i, &n) in indices.iter().zip(&self.sizes).take(usize::from(dims)) {
            let i = usize::try_from(i).ok().filter(|&i| i < n as usize)?;
            at = at * n as usize + i;
        }
        Some(at)
    }
}

/// Bytes a variable of `values` values under `name` is charged.
fn cost(name: &str, values: usize) -> usize {
    name.len() + values * std::mem::size_of::<f64>() + ENTRY_BYTES
}

/// Bytes a `STRING[max]` variable of `values` strings under `name` is charged: each string
/// as if full, with its pointer and length.
fn text_cost(name: &str, values: usize, max: u8) -> usize {
    name.len() + values * (std::mem::size_of::<Box<str>>() + usize::from(max)) + ENTRY_BYTES
}

/// The variables of one scope (or one V.L. level), with the bytes they are charged.
///
/// A B-tree, not a hash map, for the reason label tables are one (`decoder::labels`): a scope
/// may hold some 100,000 variables, and no insert may rehash them all in one tick. A large
/// scope that ends is freed by the loader thread.
#[derive(Debug, Default)]
struct Scope {
    vars: BTreeMap<Box<str>, Variable>,
    bytes: usize,
}

/// Let go of a table: a large one is freed by the loader thread (freeing 100,000 entries
/// costs a tick milliseconds).
fn free_large<K: Send + 'static, V: Send + 'static>(loader: &Loader, table: BTreeMap<K, V>) {
    let items = table.len();
    loader.release_table(table, items);
}

impl Scope {
    fn get(&self, name: &str, indices: &Indices, dims: u8) -> Option<f64> {
        let var = self.vars.get(name)?;
        var.offset(indices, dims)
            .and_then(|at| var.values.get(at).copied())
    }

    fn get_str(&self, name: &str, indices: &Indices, dims: u8) -> Option<&str> {
        let var = self.vars.get(name)?;
        let t = var.texts.as_ref()?;
        var.offset(indices, dims)
            .and_then(|at| t.values.get(at))
            .map(|s| &**s)
    }

    fn insert(&mut self, name: &str, var: Variable) {
        self.bytes += var.bytes(name);
        if let Some(old) = self.vars.insert(name.into(), var) {
            self.bytes -= old.bytes(name);
        }
    }

    fn clear(&mut self, loader: &Loader) {
        free_large(loader, std::mem::take(&mut self.vars));
        self.bytes = 0;
    }
}

#[derive(Debug)]
pub struct VarStore {
    /// Frees the scopes and tables that end when that could cost a tick.
    loader: Loader,
    /// P1..P1023 without indices; NaN = never assigned.
    p_flat: Vec<f64>,
    p_other: BTreeMap<VarSlot, f64>,
    program: Scope,
    /// One scope per program level, innermost last.
    local: Vec<Scope>,
    self_retaining: Scope,
    external: Scope,
    /// Cycle parameters per level (`@P`), innermost last.
    cycle: Vec<Vec<(u32, f64)>>,
    /// String cycle parameters (`@P1="text"`) per level, beside `cycle`: one entry per level.
    cycle_text: Vec<Vec<(u32, Box<str>)>>,
    /// The V.E. list's leaves, when the start-up list names one (`ve_var[i]`): then only
    /// they exist, typed; without a list V.E. variables are made by whoever writes first.
    ext: Option<Arc<ExtVarTable>>,
}

/// The scopes still held when the decoder goes are freed as a scope that ends is.
impl Drop for VarStore {
    fn drop(&mut self) {
        let loader = &self.loader;
        for s in self.local.drain(..) {
            free_large(loader, s.vars);
        }
        for s in [
            std::mem::take(&mut self.program),
            std::mem::take(&mut self.self_retaining),
            std::mem::take(&mut self.external),
        ] {
            free_large(loader, s.vars);
        }
        free_large(loader, std::mem::take(&mut self.p_other));
    }
}

impl VarStore {
    pub fn new(loader: Loader) -> Self {
        VarStore {
            loader,
            p_flat: vec![f64::NAN; FLAT_P],
            p_other: BTreeMap::new(),
            program: Scope::default(),
            local: vec![Scope::default()],
            self_retaining: Scope::default(),
            external: Scope::default(),
            cycle: vec![Vec::new()],
            cycle_text: vec![Vec::new()],
            ext: None,
        }
    }

    /// Declare the leaves of a V.E. list, every number 0 and every string empty (TF5200
    /// External variables: the kernel clears the shared memory at start-up). From then on
    /// only they exist.
    pub(crate) fn declare_externals(&mut self, table: Arc<ExtVarTable>) -> Result<(), VarError> {
        for v in &table.vars {
            match v.ty {
                VarType::String(max_chars) => {
                    self.declare_str(VScope::External, &v.name, &v.sizes, max_chars, "")?
                }
                _ => self.declare(VScope::External, &v.name, &v.sizes, 0.0)?,
            };
        }
        self.ext = Some(table);
        Ok(())
    }

    /// With a V.E. list: the leaf a V.E. slot names, or 20196. `Ok(None)`: no list, or not a
    /// V.E. slot.
    fn ext_leaf(&self, k: &VarSlot) -> Result<Option<&ExtVar>, VarError> {
        let (
            Some(t),
            VarSlot::V {
                scope: VScope::External,
                name,
                indices,
                dims,
            },
        ) = (&self.ext, k)
        else {
            return Ok(None);
        };
        t.get(name).map(Some).ok_or_else(|| {
            VarError::UnknownExternal(element(VScope::External, name, indices, *dims))
        })
    }

    /// The value an NC program writing `v` to `k` stores: a declared V.E. leaf takes what
    /// its type holds (an integer type rounds to the nearest whole number, BOOLEAN holds 0
    /// or 1; outside: 20847), and refuses a program's write when READ_ONLY (20100; the PLC
    /// and the HMI may always write, P-EXTV-00006).
    fn typed(&self, k: &VarSlot, v: f64, from_nc: bool) -> Result<f64, VarError> {
        let Some(leaf) = self.ext_leaf(k)? else {
            return Ok(v);
        };
        let name = || match k {
            VarSlot::V {
                scope,
                name,
                indices,
                dims,
            } => element(*scope, name, indices, *dims),
            _ => String::new(),
        };
        if from_nc && leaf.access == ExtAccess::ReadOnly {
            return Err(VarError::WriteDenied(name()));
        }
        let Some((min, max)) = leaf.ty.range() else {
            return Ok(v);
        };
        let r = v.round();
        if !(min..=max).contains(&r) {
            return Err(VarError::OutOfFormat {
                name: name(),
                value: v,
                min,
                max,
            });
        }
        Ok(r)
    }

    /// Why an NC program reading `k` gets nothing: an undeclared V.E. (20196), a WRITE_ONLY
    /// one (20097), an index outside a declared V.E. array (21928). `None`: no list, or
    /// nothing to add to "undefined".
    pub(crate) fn why_missing(&self, k: &VarSlot) -> Option<VarError> {
        let leaf = match self.ext_leaf(k) {
            Err(e) => return Some(e),
            Ok(leaf) => leaf?,
        };
        let VarSlot::V {
            scope,
            name,
            indices,
            dims,
        } = k
        else {
            return None;
        };
        if leaf.access == ExtAccess::WriteOnly {
            return Some(VarError::ReadDenied(element(*scope, name, indices, *dims)));
        }
        let var = self.external.vars.get(&**name)?;
        var.offset(indices, *dims)
            .is_none()
            .then(|| VarError::OutOfRange(element(*scope, name, indices, *dims)))
    }

    /// Whether an NC program may read `k`: not a WRITE_ONLY V.E. leaf.
    fn readable(&self, k: &VarSlot) -> bool {
        !matches!(self.ext_leaf(k), Ok(Some(leaf)) if leaf.access == ExtAccess::WriteOnly)
    }

    /// [`VarStore::get`] as an NC program reads.
    pub(crate) fn nc_get(&self, k: &VarSlot) -> Option<f64> {
        self.readable(k).then(|| self.get(k)).flatten()
    }

    /// [`VarStore::get_str`] as an NC program reads.
    pub(crate) fn nc_get_str(&self, k: &VarSlot) -> Option<&str> {
        self.readable(k).then(|| self.get_str(k)).flatten()
    }

    /// Program (or stream) start: P and V.P. start empty, one level of V.L.
    pub fn start_program(&mut self) {
        self.p_flat.iter_mut().for_each(|v| *v = f64::NAN);
        free_large(&self.loader, std::mem::take(&mut self.p_other));
        self.program.clear(&self.loader);
        for s in self.local.drain(..) {
            free_large(&self.loader, s.vars);
        }
        self.local.push(Scope::default());
        self.cycle.clear();
        self.cycle.push(Vec::new());
        self.cycle_text.clear();
        self.cycle_text.push(Vec::new());
    }

    /// Channel reset: everything but V.S. and V.E. goes.
    pub fn reset(&mut self) {
        self.start_program();
    }

    /// A subroutine or cycle level begins.
    pub(crate) fn push_level(&mut self, cycle_params: Vec<(u32, f64)>) {
        self.push_cycle_level(cycle_params, Vec::new());
    }

    /// A cycle level begins with numeric and string parameters (`@P1=5 @P2="text"`).
    pub(crate) fn push_cycle_level(
        &mut self,
        numbers: Vec<(u32, f64)>,
        texts: Vec<(u32, Box<str>)>,
    ) {
        self.local.push(Scope::default());
        self.cycle.push(numbers);
        self.cycle_text.push(texts);
    }

    pub(crate) fn pop_level(&mut self) {
        if self.local.len() > 1 {
            if let Some(s) = self.local.pop() {
                free_large(&self.loader, s.vars);
            }
            self.cycle.pop();
            self.cycle_text.pop();
        }
    }

    /// The innermost level that has cycle parameters, numbers or strings.
    fn cycle_level(&self) -> Option<usize> {
        (0..self.cycle.len()).rev().find(|&k| {
            !self.cycle[k].is_empty() || self.cycle_text.get(k).is_some_and(|t| !t.is_empty())
        })
    }

    /// The string `k` holds, if it holds one.
    pub fn get_str(&self, k: &VarSlot) -> Option<&str> {
        match k {
            VarSlot::CycleParam(n) => self
                .cycle_level()
                .and_then(|l| self.cycle_text.get(l))
                .and_then(|t| t.iter().find(|(m, _)| m == n))
                .map(|(_, s)| &**s),
            VarSlot::V {
                scope,
                name,
                indices,
                dims,
            } => self.scope_of(*scope, name)?.get_str(name, indices, *dims),
            VarSlot::P { .. } => None,
        }
    }

    /// The declared length of the `STRING[n]` variable `k` names, if it names one.
    #[cfg(test)]
    pub fn string_max(&self, k: &VarSlot) -> Option<u8> {
        let VarSlot::V { scope, name, .. } = k else {
            return None;
        };
        let var = self.scope_of(*scope, name)?.vars.get(&**name)?;
        var.texts.as_ref().map(|t| t.max)
    }

    /// Bytes the variables of `class` are charged now.
    pub fn bytes(&self, class: VarClass) -> usize {
        match class {
            VarClass::P => self.p_other.len() * ENTRY_BYTES,
            VarClass::Program => self.program.bytes,
            VarClass::Local => self.local.iter().map(|s| s.bytes).sum(),
            VarClass::SelfRetaining => self.self_retaining.bytes,
            VarClass::External => self.external.bytes,
        }
    }

    /// May `class` take `need` more bytes once `freed` bytes have gone?
    fn charge(&self, class: VarClass, need: usize, freed: usize) -> Result<(), VarError> {
        let used = self.bytes(class) - freed;
        if used + need > CLASS_BYTES {
            return Err(VarError::Full {
                class,
                used,
                need,
                limit: CLASS_BYTES,
            });
        }
        Ok(())
    }

    fn flat_index(k: &VarSlot) -> Option<usize> {
        match k {
            VarSlot::P {
                number, dims: 0, ..
            } if (*number as usize) < FLAT_P => Some(*number as usize),
            _ => None,
        }
    }

    /// The scope a V. variable of `scope` named `name` lives in: for V.L. the innermost
    /// level that has it.
    fn scope_of(&self, scope: VScope, name: &str) -> Option<&Scope> {
        match scope {
            VScope::Program => Some(&self.program),
            VScope::Local => self.local.iter().rev().find(|s| s.vars.contains_key(name)),
            VScope::SelfRetaining => Some(&self.self_retaining),
            VScope::External => Some(&self.external),
        }
    }

    /// The scope a new V. variable of `scope` goes into (V.L.: the current level).
    fn scope_mut(&mut self, scope: VScope) -> &mut Scope {
        match scope {
            VScope::Program => &mut self.program,
            VScope::Local => {
                if self.local.is_empty() {
                    self.local.push(Scope::default());
                }
                let last = self.local.len() - 1;
                &mut self.local[last]
            }
            VScope::SelfRetaining => &mut self.self_retaining,
            VScope::External => &mut self.external,
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
                self.cycle_level()
                    .and_then(|l| self.cycle[l].iter().find(|(m, _)| m == n).map(|(_, v)| *v))
            }
            VarSlot::V {
                scope,
                name,
                indices,
                dims,
            } => self.scope_of(*scope, name)?.get(name, indices, *dims),
        }
    }

    /// `P<number>` without indices set to `v`: [`Self::set`] of that slot, the commonest
    /// assignment of a stream, without building the slot when it lies in the flat table (a
    /// P parameter has no V.E. type to check).
    pub fn set_p(&mut self, number: u32, v: f64) -> Result<(), VarError> {
        match self.p_flat.get_mut(number as usize) {
            Some(slot) => {
                *slot = v;
                Ok(())
            }
            None => self.set(
                VarSlot::P {
                    number,
                    indices: Indices::default(),
                    dims: 0,
                },
                v,
            ),
        }
    }

    /// Assign a value. A V. scalar not yet there is created (in its scope; V.L. in the
    /// current level); an element needs its array declared, and its indices inside it.
    pub fn set(&mut self, k: VarSlot, v: f64) -> Result<(), VarError> {
        let v = self.typed(&k, v, true)?;
        self.set_typed(k, v)
    }

    fn set_typed(&mut self, k: VarSlot, v: f64) -> Result<(), VarError> {
        if let Some(i) = Self::flat_index(&k) {
            self.p_flat[i] = v;
            return Ok(());
        }
        match k {
            VarSlot::P { .. } => {
                if !self.p_other.contains_key(&k) {
                    self.charge(VarClass::P, ENTRY_BYTES, 0)?;
                }
                self.p_other.insert(k, v);
                Ok(())
            }
            VarSlot::CycleParam(n) => {
                if self.cycle.is_empty() {
                    self.cycle.push(Vec::new());
                }
                let last = self.cycle.len() - 1;
                if let Some(t) = self.cycle_text.get_mut(last) {
                    t.retain(|(m, _)| *m != n);
                }
                let level = &mut self.cycle[last];
                match level.iter_mut().find(|(m, _)| *m == n) {
                    Some(slot) => slot.1 = v,
                    None => level.push((n, v)),
                }
                Ok(())
            }
            VarSlot::V {
                scope,
                name,
                indices,
                dims,
            } => self.set_v(scope, &name, &indices, dims, v),
        }
    }

    fn set_v(
        &mut self,
        scope: VScope,
        name: &str,
        indices: &Indices,
        dims: u8,
        v: f64,
    ) -> Result<(), VarError> {
        let existing = match scope {
            VScope::Local => self.local.iter().rposition(|s| s.vars.contains_key(name)),
            _ => self.scope_mut(scope).vars.contains_key(name).then_some(0),
        };
        if let Some(level) = existing {
            let target = match scope {
                VScope::Local => &mut self.local[level],
                _ => self.scope_mut(scope),
            };
            let Some(var) = target.vars.get_mut(name) else {
                return Err(VarError::NotDeclared(v_name(scope, name)));
            };
            if var.texts.is_some() {
                return Err(VarError::NumberToString(element(
                    scope, name, indices, dims,
                )));
            }
            let Some(at) = var.offset(indices, dims) else {
                return Err(VarError::OutOfRange(element(scope, name, indices, dims)));
            };
            var.values[at] = v;
            return Ok(());
        }
        if dims > 0 {
            return Err(VarError::NotDeclared(v_name(scope, name)));
        }
        self.charge(VarClass::of(scope), cost(name, 1), 0)?;
        self.scope_mut(scope).insert(name, Variable::scalar(v));
        Ok(())
    }

    /// Assign a string. A `STRING[n]` variable takes at most n characters (21462); a V.
    /// scalar not yet there is created as a `STRING[126]`; a variable holding numbers, or a P
    /// parameter, takes none (900008). A cycle parameter becomes a string one.
    pub(crate) fn set_str(&mut self, k: VarSlot, text: &str) -> Result<(), VarError> {
        self.set_str_from(k, text, true)
    }

    fn set_str_from(&mut self, k: VarSlot, text: &str, from_nc: bool) -> Result<(), VarError> {
        if let Some(leaf) = self.ext_leaf(&k)? {
            if from_nc && leaf.access == ExtAccess::ReadOnly {
                return Err(VarError::WriteDenied(leaf.name.clone()));
            }
        }
        let len = text.chars().count();
        match k {
            VarSlot::P { number, .. } => Err(VarError::StringToNumber(format!("P{number}"))),
            VarSlot::CycleParam(n) => {
                if self.cycle.is_empty() {
                    self.cycle.push(Vec::new());
                }
                let last = self.cycle.len() - 1;
                self.cycle[last].retain(|(m, _)| *m != n);
                while self.cycle_text.len() <= last {
                    self.cycle_text.push(Vec::new());
                }
                let level = &mut self.cycle_text[last];
                match level.iter_mut().find(|(m, _)| *m == n) {
                    Some(slot) => slot.1 = text.into(),
                    None => level.push((n, text.into())),
                }
                Ok(())
            }
            VarSlot::V {
                scope,
                name,
                indices,
                dims,
            } => {
                let existing = match scope {
                    VScope::Local => self.local.iter().rposition(|s| s.vars.contains_key(&*name)),
                    _ => self.scope_mut(scope).vars.contains_key(&*name).then_some(0),
                };
                if let Some(level) = existing {
                    let target = match scope {
                        VScope::Local => &mut self.local[level],
                        _ => self.scope_mut(scope),
                    };
                    let Some(var) = target.vars.get_mut(&*name) else {
                        return Err(VarError::NotDeclared(v_name(scope, &name)));
                    };
                    let at = var.offset(&indices, dims);
                    let Some(t) = var.texts.as_mut() else {
                        return Err(VarError::StringToNumber(element(
                            scope, &name, &indices, dims,
                        )));
                    };
                    let Some(at) = at else {
                        return Err(VarError::OutOfRange(element(scope, &name, &indices, dims)));
                    };
                    if len > usize::from(t.max) {
                        return Err(VarError::StringTooLong {
                            name: element(scope, &name, &indices, dims),
                            len,
                            max: t.max,
                        });
                    }
                    t.values[at] = text.into();
                    return Ok(());
                }
                if dims > 0 {
                    return Err(VarError::NotDeclared(v_name(scope, &name)));
                }
                let max = MAX_STRING as u8;
                if len > MAX_STRING {
                    return Err(VarError::StringTooLong {
                        name: v_name(scope, &name),
                        len,
                        max,
                    });
                }
                self.charge(VarClass::of(scope), text_cost(&name, 1, max), 0)?;
                let var = Variable {
                    sizes: [0; 3],
                    dims: 0,
                    values: Box::new([]),
                    texts: Some(Box::new(Texts {
                        max,
                        values: Box::new([text.into()]),
                    })),
                };
                self.scope_mut(scope).insert(&name, var);
                Ok(())
            }
        }
    }

    /// `#VAR` declaration of a `STRING[max]` variable: `name` in `scope` with the array
    /// `sizes` (empty: a scalar), every element `init` (the parser checked its length).
    /// Replaces a variable of that name as [`VarStore::declare`] does; returns the number of
    /// values made.
    pub(crate) fn declare_str(
        &mut self,
        scope: VScope,
        name: &str,
        sizes: &[u32],
        max: u8,
        init: &str,
    ) -> Result<usize, VarError> {
        let elements = self.declared_elements(scope, name, sizes)?;
        let freed = self
            .scope_mut(scope)
            .vars
            .get(name)
            .map_or(0, |old| old.bytes(name));
        self.charge(VarClass::of(scope), text_cost(name, elements, max), freed)?;
        let init: Box<str> = init.into();
        let mut var = Variable {
            sizes: [0; 3],
            dims: sizes.len() as u8,
            values: Box::new([]),
            texts: Some(Box::new(Texts {
                max,
                values: vec![init; elements].into_boxed_slice(),
            })),
        };
        var.sizes[..sizes.len()].copy_from_slice(sizes);
        self.scope_mut(scope).insert(name, var);
        Ok(elements)
    }

    /// The number of elements `sizes` declare, within the limits (20974, 20967).
    fn declared_elements(
        &self,
        scope: VScope,
        name: &str,
        sizes: &[u32],
    ) -> Result<usize, VarError> {
        if sizes.len() > MAX_ARRAY_DIMS {
            return Err(VarError::TooManyIndices(v_name(scope, name)));
        }
        let class = VarClass::of(scope);
        let elements = sizes
            .iter()
            .fold(1u64, |n, &s| n.saturating_mul(u64::from(s)));
        if elements > MAX_ARRAY_ELEMENTS {
            // The parser refuses such a declaration already; the store does not rely on it.
            return Err(VarError::Full {
                class,
                used: self.bytes(class),
                need: usize::try_from(elements)
                    .unwrap_or(usize::MAX)
                    .saturating_mul(std::mem::size_of::<f64>()),
                limit: CLASS_BYTES,
            });
        }
        Ok(elements as usize)
    }

    /// `#VAR` declaration: `name` in `scope` with the array `sizes` (empty: a scalar), every
    /// value `init`. A variable of that name in the same scope (V.L.: the same level) is
    /// replaced. Returns the number of values made, so the decoder can spread the work of
    /// large declarations over ticks.
    pub(crate) fn declare(
        &mut self,
        scope: VScope,
        name: &str,
        sizes: &[u32],
        init: f64,
    ) -> Result<usize, VarError> {
        let class = VarClass::of(scope);
        let elements = self.declared_elements(scope, name, sizes)?;
        let freed = self
            .scope_mut(scope)
            .vars
            .get(name)
            .map_or(0, |old| old.bytes(name));
        self.charge(class, cost(name, elements), freed)?;
        let mut var = Variable {
            sizes: [0; 3],
            dims: sizes.len() as u8,
            values: vec![init; elements].into_boxed_slice(),
            texts: None,
        };
        var.sizes[..sizes.len()].copy_from_slice(sizes);
        self.scope_mut(scope).insert(name, var);
        Ok(elements)
    }

    /// Write `values` into the first elements of `name`, just declared (an array
    /// initialiser, row-major); the parser refuses more values than elements.
    pub fn fill(&mut self, scope: VScope, name: &str, values: &[f64]) {
        if let Some(var) = self.scope_mut(scope).vars.get_mut(name) {
            for (d, v) in var.values.iter_mut().zip(values) {
                *d = *v;
            }
        }
    }

    /// V.E. written from outside the channel (PLC, HMI, ADS): `name` as a program writes it
    /// after `V.E.`, with members and indices (`SCH.PREFLOW`, `FARBE[2]`). Typed as a
    /// program's write is, but access rights do not apply (P-EXTV-00006: they bind the CNC).
    pub(crate) fn set_external(&mut self, name: &str, v: f64) -> Result<(), VarError> {
        let k = external_slot(name)?;
        let v = self.typed(&k, v, false)?;
        self.set_typed(k, v)
    }

    /// A string V.E. written from outside the channel, as [`VarStore::set_external`].
    pub(crate) fn set_external_str(&mut self, name: &str, text: &str) -> Result<(), VarError> {
        self.set_str_from(external_slot(name)?, text, false)
    }

    pub(crate) fn get_external(&self, name: &str) -> Option<f64> {
        self.get(&external_slot(name).ok()?)
    }

    /// A V.E. read from outside with what the PLC side needs to encode it: a number with its
    /// declared type (`None` without a list), or a string with the characters it may hold.
    pub(crate) fn external_value(&self, name: &str) -> Option<ExternalValue> {
        let k = external_slot(name).ok()?;
        let ty = self.ext_leaf(&k).ok().flatten().map(|l| l.ty);
        if let Some(v) = self.get(&k) {
            return Some(ExternalValue::Num(v, ty));
        }
        let text = self.get_str(&k)?;
        let max = match ty {
            Some(VarType::String(max_chars)) => max_chars,
            _ => MAX_STRING as u8,
        };
        Some(ExternalValue::Str(text.to_string(), max))
    }
}

/// A V.E. value as the PLC side reads it ([`VarStore::external_value`]).
#[derive(Debug, Clone, PartialEq)]
pub enum ExternalValue {
    /// The value and the declared type (`None`: no list, an LREAL).
    Num(f64, Option<VarType>),
    /// The text and the characters the variable may hold.
    Str(String, u8),
}

/// Characters of a V.E. name written from outside at most.
const MAX_EXTERNAL_NAME: usize = 255;

/// `SCH.PREFLOW`, `FARBE[2]`, `INFO[1].X` (any case, blanks around ignored) as the store's
/// key: the members joined by `.`, the indices in order. A name that is not one is unknown.
pub(crate) fn external_slot(text: &str) -> Result<VarSlot, VarError> {
    let unknown = || VarError::UnknownExternal(format!("V.E.{}", text.trim()));
    let text = text.trim();
    if text.is_empty() || text.len() > MAX_EXTERNAL_NAME {
        return Err(unknown());
    }
    let mut name = String::with_capacity(text.len());
    let mut indices = [0i64; 3];
    let mut dims = 0usize;
    let mut rest = text;
    loop {
        let end = rest
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        if end == 0 {
            return Err(unknown());
        }
        name.push_str(&rest[..end].to_ascii_uppercase());
        rest = &rest[end..];
        while let Some(r) = rest.strip_prefix('[') {
            let close = r.find(']').ok_or_else(unknown)?;
            let i: i64 = r[..close].trim().parse().map_err(|_| unknown())?;
            *indices.get_mut(dims).ok_or_else(unknown)? = i;
            dims += 1;
            rest = &r[close + 1..];
        }
        match rest.strip_prefix('.') {
            Some(r) => {
                name.push('.');
                rest = r;
            }
            None if rest.is_empty() => break,
            None => return Err(unknown()),
        }
    }
    Ok(VarSlot::V {
        scope: VScope::External,
        name: name.into(),
        indices,
        dims: dims as u8,
    })
}

fn v_name(scope: VScope, name: &str) -> String {
    format!("V.{}.{name}", scope.letter())
}

fn element(scope: VScope, name: &str, indices: &Indices, dims: u8) -> String {
    let mut s = v_name(scope, name);
    for i in &indices[..usize::from(dims).min(3)] {
        s.push_str(&format!("[{i}]"));
    }
    s
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
    fn el(scope: VScope, name: &str, indices: &[i64]) -> VarSlot {
        let mut i = [0; 3];
        i[..indices.len()].copy_from_slice(indices);
        VarSlot::V {
            scope,
            name: name.into(),
            indices: i,
            dims: indices.len() as u8,
        }
    }

    #[test]
    fn lifetimes_follow_isg() {
        let mut s = VarStore::new(Loader::inline());
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
        let mut s = VarStore::new(Loader::inline());
        s.set(v(VScope::Local, "A"), 1.0).unwrap();
        s.push_level(vec![(1, 5.0)]);
        assert_eq!(s.get(&v(VScope::Local, "A")), Some(1.0));
        assert_eq!(s.get(&VarSlot::CycleParam(1)), Some(5.0));
        s.set(v(VScope::Local, "B"), 2.0).unwrap();
        s.set(v(VScope::Local, "A"), 3.0).unwrap();
        let inner = s.bytes(VarClass::Local);
        s.pop_level();
        assert!(
            s.bytes(VarClass::Local) < inner,
            "B's bytes go with its level"
        );
        assert_eq!(s.get(&v(VScope::Local, "B")), None);
        assert_eq!(s.get(&v(VScope::Local, "A")), Some(3.0));
        assert_eq!(s.get(&VarSlot::CycleParam(1)), None);
    }

    #[test]
    fn an_array_is_one_entry_with_its_name_once() {
        let mut s = VarStore::new(Loader::inline());
        let name = "N".repeat(3900);
        assert_eq!(
            s.declare(VScope::Local, &name, &[100_000], 0.5),
            Ok(100_000)
        );
        assert_eq!(
            s.bytes(VarClass::Local),
            3900 + 800_000 + ENTRY_BYTES,
            "charged once for the name, 8 bytes a value"
        );
        assert_eq!(s.get(&el(VScope::Local, &name, &[99_999])), Some(0.5));
        assert_eq!(s.get(&el(VScope::Local, &name, &[100_000])), None);
        s.set(el(VScope::Local, &name, &[7]), 2.0).unwrap();
        assert_eq!(s.get(&el(VScope::Local, &name, &[7])), Some(2.0));
        let e = s
            .set(el(VScope::Local, &name, &[100_000]), 1.0)
            .unwrap_err();
        assert_eq!(e.code(), ARRAY_INDEX_RANGE);
        // Indexed as a matrix, or not at all: outside the declared shape.
        assert_eq!(s.get(&el(VScope::Local, &name, &[0, 0])), None);
        assert_eq!(s.get(&v(VScope::Local, &name)), None);
    }

    #[test]
    fn row_major_elements_of_a_matrix() {
        let mut s = VarStore::new(Loader::inline());
        s.declare(VScope::Program, "GRID", &[3, 4], 0.0).unwrap();
        for i in 0..3 {
            for j in 0..4 {
                s.set(el(VScope::Program, "GRID", &[i, j]), (i * 10 + j) as f64)
                    .unwrap();
            }
        }
        assert_eq!(s.get(&el(VScope::Program, "GRID", &[2, 3])), Some(23.0));
        assert_eq!(s.get(&el(VScope::Program, "GRID", &[1, 0])), Some(10.0));
        assert_eq!(s.get(&el(VScope::Program, "GRID", &[3, 0])), None);
    }

    #[test]
    fn string_variables_hold_bounded_strings() {
        let mut s = VarStore::new(Loader::inline());
        assert_eq!(s.declare_str(VScope::Local, "ROW", &[3], 4, "ab"), Ok(3));
        assert_eq!(s.bytes(VarClass::Local), text_cost("ROW", 3, 4));
        assert_eq!(s.get_str(&el(VScope::Local, "ROW", &[2])), Some("ab"));
        assert_eq!(s.get(&el(VScope::Local, "ROW", &[2])), None, "no number");
        assert_eq!(s.string_max(&el(VScope::Local, "ROW", &[0])), Some(4));
        s.set_str(el(VScope::Local, "ROW", &[1]), "wxyz").unwrap();
        assert_eq!(s.get_str(&el(VScope::Local, "ROW", &[1])), Some("wxyz"));
        let e = |r: Result<(), VarError>| r.unwrap_err().code();
        assert_eq!(
            e(s.set_str(el(VScope::Local, "ROW", &[1]), "vwxyz")),
            STRING_TOO_LONG_FOR_VARIABLE
        );
        assert_eq!(
            e(s.set_str(el(VScope::Local, "ROW", &[3]), "a")),
            ARRAY_INDEX_RANGE
        );
        assert_eq!(
            e(s.set(el(VScope::Local, "ROW", &[0]), 1.0)),
            EVAL_NUMBER_AS_STRING
        );
        s.set(v(VScope::Local, "N"), 1.0).unwrap();
        assert_eq!(
            e(s.set_str(v(VScope::Local, "N"), "a")),
            EVAL_STRING_AS_NUMBER
        );
        assert_eq!(e(s.set_str(p(1), "a")), EVAL_STRING_AS_NUMBER);
        // An undeclared scalar becomes a STRING[126]; a string too long for that is refused.
        s.set_str(v(VScope::Program, "NEW"), "abc").unwrap();
        assert_eq!(s.string_max(&v(VScope::Program, "NEW")), Some(126));
        assert_eq!(
            e(s.set_str(v(VScope::Program, "NEW2"), &"x".repeat(127))),
            STRING_TOO_LONG_FOR_VARIABLE
        );
        // A cycle parameter becomes a string one.
        s.push_level(vec![(1, 5.0)]);
        s.set_str(VarSlot::CycleParam(1), "t").unwrap();
        assert_eq!(s.get(&VarSlot::CycleParam(1)), None);
        assert_eq!(s.get_str(&VarSlot::CycleParam(1)), Some("t"));
    }

    #[test]
    fn declared_externals_are_typed_and_bind_programs_not_the_plc() {
        use crate::params::ext_vars::{ExtAccess, ExtVar, ExtVarTable};
        let leaf = |name: &str, sizes: Vec<u32>, ty, access| ExtVar {
            name: name.into(),
            sizes,
            ty,
            access,
        };
        let mut s = VarStore::new(Loader::inline());
        let table = ExtVarTable {
            file: "ve.lis".into(),
            vars: vec![
                leaf("INFO.X", vec![2], VarType::Uns08, ExtAccess::ReadOnly),
                leaf("MSG", vec![], VarType::String(4), ExtAccess::ReadWrite),
            ],
        };
        s.declare_externals(Arc::new(table)).unwrap();
        // Members and indices as a program writes them, any case.
        assert_eq!(
            external_slot(" info[1].x "),
            Ok(el(VScope::External, "INFO.X", &[1]))
        );
        assert!(external_slot("INFO[1]..X").is_err());
        assert!(external_slot("A[1][2][3][4]").is_err());
        // The PLC writes a READ_ONLY leaf, rounded into UNS08; a program may not.
        s.set_external("Info[1].X", 6.5).unwrap();
        assert_eq!(s.get_external("INFO[1].X"), Some(7.0));
        let e = |r: Result<(), VarError>| r.unwrap_err().code();
        assert_eq!(
            e(s.set(el(VScope::External, "INFO.X", &[0]), 1.0)),
            VARIABLE_WRITE_DENIED
        );
        assert_eq!(
            e(s.set_external("INFO[0].X", 256.0)),
            VARIABLE_OUT_OF_FORMAT
        );
        assert_eq!(e(s.set_external("INFO[2].X", 1.0)), ARRAY_INDEX_RANGE);
        assert_eq!(e(s.set_external("NOPE", 1.0)), VARIABLE_UNKNOWN);
        s.set_external_str("msg", "abcd").unwrap();
        assert_eq!(
            s.external_value("MSG"),
            Some(ExternalValue::Str("abcd".into(), 4))
        );
        assert_eq!(
            e(s.set_external_str("MSG", "abcde")),
            STRING_TOO_LONG_FOR_VARIABLE
        );
        // A reset keeps them.
        s.reset();
        assert_eq!(
            s.external_value("INFO[1].X"),
            Some(ExternalValue::Num(7.0, Some(VarType::Uns08)))
        );
    }

    #[test]
    fn an_element_of_an_undeclared_array_is_refused() {
        let mut s = VarStore::new(Loader::inline());
        let e = s.set(el(VScope::Local, "NOPE", &[2]), 1.0).unwrap_err();
        assert_eq!(e.code(), EVAL_UNDEFINED);
    }

    #[test]
    fn each_class_is_bounded_in_bytes_and_redeclaring_does_not_grow() {
        let mut s = VarStore::new(Loader::inline());
        // Redeclaring one name a thousand times replaces it: the bytes stay.
        for _ in 0..1000 {
            s.declare(VScope::SelfRetaining, "A", &[100_000], 0.0)
                .unwrap();
        }
        assert_eq!(s.bytes(VarClass::SelfRetaining), cost("A", 100_000));
        // Ten distinct arrays fit, the eleventh does not: 20967 with the figures.
        let mut full = None;
        for k in 0..20 {
            if let Err(e) = s.declare(VScope::SelfRetaining, &format!("B{k}"), &[100_000], 0.0) {
                full = Some((k, e));
                break;
            }
        }
        let (k, e) = full.expect("the V.S. budget refused a declaration");
        assert!(k >= 9, "only {k} arrays fitted");
        assert_eq!(e.code(), VARIABLE_MEMORY_FULL);
        assert!(s.bytes(VarClass::SelfRetaining) <= CLASS_BYTES);
        // V.S. survive a reset, so the budget is what bounds them across programs.
        s.reset();
        assert!(s.bytes(VarClass::SelfRetaining) > CLASS_BYTES / 2);
        // Other classes have their own budget.
        assert!(s.declare(VScope::Program, "C", &[100_000], 0.0).is_ok());
    }

    #[test]
    fn scalars_and_p_parameters_are_bounded_too() {
        let mut s = VarStore::new(Loader::inline());
        let long = "L".repeat(3900);
        let mut refused = None;
        for k in 0..10_000 {
            if let Err(e) = s.set(v(VScope::External, &format!("{long}{k}")), 1.0) {
                refused = Some(e);
                break;
            }
        }
        assert_eq!(refused.map(|e| e.code()), Some(VARIABLE_MEMORY_FULL));
        let mut refused = None;
        for n in 0..1_000_000 {
            let k = VarSlot::P {
                number: 5000 + n,
                indices: [0; 3],
                dims: 0,
            };
            if let Err(e) = s.set(k, 1.0) {
                refused = Some(e);
                break;
            }
        }
        assert_eq!(refused.map(|e| e.code()), Some(VARIABLE_MEMORY_FULL));
        assert!(s.bytes(VarClass::P) <= CLASS_BYTES);
    }
}
