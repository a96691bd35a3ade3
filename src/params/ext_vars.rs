//! The list of external variables (V.E.), named per channel by the start-up list's
//! `ve_var[i]` (TF5200 Start-up list, P-STUP-00146), in the ISG list style (TF5200 External
//! variables, "Parameterising the memory layout of V.E. variables"):
//!
//! ```text
//! use_extended_string_var      1            # P-EXTV-00022: STRING holds 127 characters
//! var[0].name                  COUNT        # P-EXTV-00001
//! var[0].type                  SGN32        # P-EXTV-00003
//! var[1].name                  FARBE
//! var[1].type                  UNS16
//! var[1].array_elements        3            # P-EXTV-00007: FARBE[0] … FARBE[2]
//! var[2].name                  SCH
//! var[2].type                  SCHNITT      # a structure type, below
//! struct[0].name               SCHNITT      # P-EXTV-00015
//! struct[0].element[0].name    PREFLOW      # P-EXTV-00016
//! struct[0].element[0].type    REAL64       # P-EXTV-00017
//! ```
//!
//! Each variable is unfolded into its leaves: `V.E.SCH.PREFLOW` above is one leaf, a REAL64;
//! an array of structures gives its leaves the array's index (`V.E.INFO[1].X`). The memory
//! layout entries (byte offsets, alignment, synchronisation) describe the kernel's shared
//! memory with the PLC, which ncchannel does not have: they are inert. Bad entries are
//! errors with file, line and column.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use super::catalog::{ListKind, ListSummary, Tally};
use super::list::{read_list, Entry, ParamList, ValueKind};
use super::startup::{shape, warn_duplicates};
use super::value::uint_value;
use crate::diag::Diagnostic;
use crate::lang::block::VarType;
use crate::lang::codes::{MAX_ARRAY_DIMS, MAX_ARRAY_ELEMENTS};
use crate::vocab::vars::{CLASS_BYTES, ENTRY_BYTES};

/// Highest `var[i]` index + 1: P-EXTV-00010 `number_used_variables` is an UNS16.
pub(crate) const MAX_VARS: u32 = 65_535;
/// Structure types one list may define (`struct[i]`): ours, the TF5200 pages name no limit.
pub(crate) const MAX_STRUCTS: u32 = 1024;
/// Elements one structure type may have (`struct[i].element[j]`): ours.
pub(crate) const MAX_ELEMENTS: u32 = 1024;
/// Leaves all variables together unfold into: ours, so a list of structures of structures
/// cannot make the table grow without bound.
pub(crate) const MAX_LEAVES: usize = 65_536;
/// Bytes the leaves may cost in the variable store at most: its V.E. class budget, as the
/// store charges them (name, values, bookkeeping), so declaring them cannot fail.
pub(crate) const MAX_TABLE_BYTES: usize = CLASS_BYTES;
/// Structures nested in structures at most: ours (a structure containing itself stops here).
pub(crate) const MAX_NESTING: usize = 8;
/// Characters of a variable or element name at most: ours.
pub(crate) const MAX_NAME_CHARS: usize = 64;
/// Characters a STRING holds: 20, or 127 with `use_extended_string_var` (TF5200 External
/// variables, P-EXTV-00022 and "use_extended_string_var parameter").
pub(crate) const STRING_CHARS: u8 = 20;
pub(crate) const EXTENDED_STRING_CHARS: u8 = 127;
/// Bytes of a VSTRING (P-EXTV-00008 / P-EXTV-00021 `size`, with its NUL): the kernel takes
/// 1 … 800 and 128 by default; ncchannel's string variables hold at most 255 characters.
pub(crate) const DEFAULT_VSTRING_BYTES: u64 = 128;
pub(crate) const MAX_VSTRING_BYTES: u64 = 256;

/// The elementary type a V.E. list names (P-EXTV-00003: BOOLEAN, SGN08 … UNS32, REAL64,
/// STRING; VSTRING is read with its size), in the language's vocabulary of declared types;
/// STRING takes `string_chars`.
fn elementary(word: &str, string_chars: u8) -> Option<VarType> {
    match word {
        "STRING" => Some(VarType::String(string_chars)),
        "REAL" => None,
        w => VarType::numeric(w),
    }
}

/// P-EXTV-00006 / P-EXTV-00019: what an NC program may do with a leaf (the PLC and the HMI
/// may always read and write).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExtAccess {
    ReadWrite,
    ReadOnly,
    WriteOnly,
}

/// One leaf of a declared V.E. variable.
#[derive(Debug, Clone, PartialEq)]
pub struct ExtVar {
    /// Upper case, members joined by `.`: `SCH.PREFLOW`.
    pub name: String,
    /// The array sizes along the path, outermost first (empty: a scalar).
    pub sizes: Vec<u32>,
    pub ty: VarType,
    pub access: ExtAccess,
}

/// The leaves of a V.E. list, sorted by name.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ExtVarTable {
    pub file: PathBuf,
    pub vars: Vec<ExtVar>,
}

impl ExtVarTable {
    /// The leaf named `name` (upper case, members joined by `.`).
    pub fn get(&self, name: &str) -> Option<&ExtVar> {
        self.vars
            .binary_search_by(|v| v.name.as_str().cmp(name))
            .ok()
            .and_then(|i| self.vars.get(i))
    }
}

/// Does this list look like a V.E. list? (It names `var[…].name` or `struct[…]`.)
pub(crate) fn is_ext_var_list(list: &ParamList) -> bool {
    list.entries.iter().any(|e| {
        matches!(
            shape(e).as_slice(),
            [("var", Some(_)), ("name", None)] | [("struct", Some(_)), ..]
        )
    })
}

/// Read and check a V.E. list. `Err` when the file cannot be read; entry problems go to
/// `diags`.
pub(crate) fn read_ext_vars(
    path: &Path,
    diags: &mut Vec<Diagnostic>,
) -> Result<(ExtVarTable, ListSummary), Diagnostic> {
    let (list, errs) = read_list(path)?;
    diags.extend(errs);
    Ok(interpret_ext_vars(&list, diags))
}

/// The fields of one `var[i]` or `struct[i].element[j]`, each with its entry.
#[derive(Default)]
struct Fields<'l> {
    name: Option<&'l Entry>,
    ty: Option<&'l Entry>,
    access: Option<&'l Entry>,
    array: Option<&'l Entry>,
    size: Option<&'l Entry>,
}

impl<'l> Fields<'l> {
    /// Take `field` of `e`; `false` when the field is not one read.
    fn take(&mut self, field: &str, e: &'l Entry) -> bool {
        let slot = match field {
            "name" => &mut self.name,
            "type" => &mut self.ty,
            "access_rights" => &mut self.access,
            // TF5200 diagnosis 20100's example writes `array_size`.
            "array_elements" | "array_size" => &mut self.array,
            "size" => &mut self.size,
            _ => return false,
        };
        *slot = Some(e);
        true
    }
}

/// A structure type: its name's entry and its elements by index.
#[derive(Default)]
struct StructDef<'l> {
    name: Option<&'l Entry>,
    elements: BTreeMap<u32, Fields<'l>>,
}

/// The entries of a V.E. list, by variable and structure index.
struct Gathered<'l> {
    vars: BTreeMap<u32, Fields<'l>>,
    structs: BTreeMap<u32, StructDef<'l>>,
    string_chars: u8,
    /// `number_used_variables` (P-EXTV-00010), if given.
    used: Option<u32>,
}

/// Step 1: every entry to its variable, structure element or list setting.
fn gather<'l>(list: &'l ParamList, tally: &mut Tally, diags: &mut Vec<Diagnostic>) -> Gathered<'l> {
    let mut g = Gathered {
        vars: BTreeMap::new(),
        structs: BTreeMap::new(),
        string_chars: STRING_CHARS,
        used: None,
    };
    for e in &list.entries {
        match shape(e).as_slice() {
            [("var", Some(i)), (field, None)] => {
                if *i >= MAX_VARS {
                    diags.push(index_error(list, e, "variable", MAX_VARS));
                } else if !g.vars.entry(*i).or_default().take(field, e) {
                    tally.not_read(list, e, diags);
                }
            }
            [("struct", Some(i)), ("name", None)] if *i < MAX_STRUCTS => {
                g.structs.entry(*i).or_default().name = Some(e);
            }
            [("struct", Some(i)), ("element", Some(j)), (field, None)]
                if *i < MAX_STRUCTS && *j < MAX_ELEMENTS =>
            {
                let fields = g
                    .structs
                    .entry(*i)
                    .or_default()
                    .elements
                    .entry(*j)
                    .or_default();
                if !fields.take(field, e) {
                    tally.not_read(list, e, diags);
                }
            }
            [("struct", Some(_)), ..] => {
                diags.push(list.error_at(
                    e,
                    e.name_pos,
                    format!(
                        "{}: at most {MAX_STRUCTS} structure types of {MAX_ELEMENTS} elements",
                        e.name.text
                    ),
                ));
            }
            [("use_extended_string_var", None)] => match bool_value(list, e) {
                Ok(true) => g.string_chars = EXTENDED_STRING_CHARS,
                Ok(false) => g.string_chars = STRING_CHARS,
                Err(d) => diags.push(d),
            },
            [("number_used_variables" | "anzahl_belegt", None)] => {
                match uint_value(list, e, u64::from(MAX_VARS)) {
                    Ok(n) => g.used = Some(n as u32),
                    Err(d) => diags.push(d),
                }
            }
            _ => tally.not_read(list, e, diags),
        }
    }
    g
}

/// Check a parsed V.E. list.
pub(crate) fn interpret_ext_vars(
    list: &ParamList,
    diags: &mut Vec<Diagnostic>,
) -> (ExtVarTable, ListSummary) {
    warn_duplicates(list, diags);
    let mut tally = Tally::new(ListKind::ExtVars);
    let g = gather(list, &mut tally, diags);
    let mut cx = Unfold {
        list,
        structs: HashMap::new(),
        string_chars: g.string_chars,
        out: Vec::new(),
        bytes: 0,
        diags,
    };
    cx.register_structs(&g.structs);
    cx.unfold_vars(&g.vars, g.used);
    let Unfold { mut out, .. } = cx;
    out.sort_by(|a, b| a.name.cmp(&b.name));
    (
        ExtVarTable {
            file: list.file.clone(),
            vars: out,
        },
        tally.finish(list),
    )
}

/// Unfolds variables into leaves.
struct Unfold<'l, 'd> {
    list: &'l ParamList,
    structs: HashMap<String, &'l StructDef<'l>>,
    string_chars: u8,
    out: Vec<ExtVar>,
    /// Bytes the leaves so far cost in the variable store.
    bytes: usize,
    diags: &'d mut Vec<Diagnostic>,
}

impl<'l> Unfold<'l, '_> {
    /// Step 2: the structure types by name.
    fn register_structs(&mut self, structs: &'l BTreeMap<u32, StructDef<'l>>) {
        for (i, s) in structs {
            let Some(n) = s.name else {
                if let Some(e) = s.elements.values().find_map(|f| f.name.or(f.ty)) {
                    self.diags.push(self.list.error_at(
                        e,
                        e.name_pos,
                        format!("struct[{i}] has elements but no struct[{i}].name"),
                    ));
                }
                continue;
            };
            if let Some(name) = self.name(n) {
                if elementary(&name, self.string_chars).is_some() || name == "VSTRING" {
                    self.diags.push(self.list.error_at(
                        n,
                        n.value_pos,
                        format!("{}: {name} is an elementary type", n.name.text),
                    ));
                } else if self.structs.insert(name.clone(), s).is_some() {
                    self.diags.push(self.list.error_at(
                        n,
                        n.value_pos,
                        format!("{}: structure type {name} is defined twice", n.name.text),
                    ));
                }
            }
        }
    }

    /// Step 3: each variable below `used` unfolded into its leaves, names unique.
    fn unfold_vars(&mut self, vars: &BTreeMap<u32, Fields<'l>>, used: Option<u32>) {
        let mut seen: HashMap<String, usize> = HashMap::new();
        for (i, v) in vars {
            let Some(n) = v.name else {
                if let Some(e) = v.ty.or(v.access).or(v.array).or(v.size) {
                    self.diags.push(self.list.error_at(
                        e,
                        e.name_pos,
                        format!("var[{i}] has no var[{i}].name"),
                    ));
                }
                continue;
            };
            if used.is_some_and(|u| *i >= u) {
                self.diags.push(self.list.warning_at(
                    n,
                    n.name_pos,
                    format!(
                        "{}: not below number_used_variables {}: the kernel leaves it out, so does ncchannel",
                        n.name.text,
                        used.unwrap_or(0)
                    ),
                ));
                continue;
            }
            let Some(name) = self.name(n) else { continue };
            if let Some(first) = seen.insert(name.clone(), n.name_pos.line) {
                // TF5200 diagnosis 21485: the kernel makes the second one unreachable.
                self.diags.push(self.list.error_at(
                    n,
                    n.value_pos,
                    format!(
                        "{}: {name} is already declared on line {first}",
                        n.name.text
                    ),
                ));
                continue;
            }
            self.leaf_or_struct(&name, v, Vec::new(), ExtAccess::ReadWrite, 0);
        }
    }

    /// The upper-case name `e` gives, if it is a valid one (letters, digits, `_`, not
    /// starting with a digit; TF5200 diagnosis 20788 for a bad character).
    fn name(&mut self, e: &Entry) -> Option<String> {
        let text = e.value.text.trim();
        let ok = matches!(e.value.kind, ValueKind::Word)
            && (1..=MAX_NAME_CHARS).contains(&text.len())
            && text.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
            && !text.as_bytes()[0].is_ascii_digit();
        if ok {
            Some(text.to_ascii_uppercase())
        } else {
            self.diags.push(self.list.error_at(
                e,
                e.value_pos,
                format!(
                    "{}: `{}` is not a name (letters, digits and _, at most {MAX_NAME_CHARS}, not starting with a digit)",
                    e.name.text, e.value.text
                ),
            ));
            None
        }
    }

    /// The access right of `f` (P-EXTV-00006 / -00019), `inherited` when it names none;
    /// `None` after an error.
    fn access(&mut self, f: &Fields<'l>, inherited: ExtAccess) -> Option<ExtAccess> {
        let Some(e) = f.access else {
            return Some(inherited);
        };
        Some(match e.value.text.trim().to_ascii_uppercase().as_str() {
            "READ_WRITE" => ExtAccess::ReadWrite,
            "READ_ONLY" => ExtAccess::ReadOnly,
            "WRITE_ONLY" => ExtAccess::WriteOnly,
            "INHERIT_ACCESS" => inherited,
            _ => {
                self.diags.push(self.list.error_at(
                    e,
                    e.value_pos,
                    format!(
                        "{}: READ_WRITE, READ_ONLY, WRITE_ONLY or INHERIT_ACCESS expected, found `{}`",
                        e.name.text, e.value.text
                    ),
                ));
                return None;
            }
        })
    }

    /// `f`'s array size (P-EXTV-00007 / -00020; 0 is no array) added to `sizes`; `false`
    /// after an error.
    fn array(&mut self, f: &Fields<'l>, path: &str, sizes: &mut Vec<u32>) -> bool {
        let Some(e) = f.array else {
            return true;
        };
        match uint_value(self.list, e, MAX_ARRAY_ELEMENTS) {
            Ok(0) => true,
            Ok(n) if sizes.len() < MAX_ARRAY_DIMS => {
                sizes.push(n as u32);
                true
            }
            Ok(_) => {
                self.diags.push(self.list.error_at(
                    e,
                    e.name_pos,
                    format!(
                        "{}: {path} would have more than {MAX_ARRAY_DIMS} indices",
                        e.name.text
                    ),
                ));
                false
            }
            Err(d) => {
                self.diags.push(d);
                false
            }
        }
    }

    /// A VSTRING of `f.size` bytes with the NUL (P-EXTV-00008 / -00021; default 128);
    /// `None` after an error.
    fn vstring(&mut self, f: &Fields<'l>) -> Option<VarType> {
        let bytes = match f.size {
            None => DEFAULT_VSTRING_BYTES,
            Some(e) => match uint_value(self.list, e, MAX_VSTRING_BYTES) {
                Ok(0) => {
                    self.diags.push(self.list.error_at(
                        e,
                        e.value_pos,
                        format!("{}: at least 1 byte", e.name.text),
                    ));
                    return None;
                }
                Ok(n) => n,
                Err(d) => {
                    self.diags.push(d);
                    return None;
                }
            },
        };
        Some(VarType::String((bytes - 1) as u8))
    }

    /// One variable or element `f` named `path`, under arrays `sizes`, inheriting `access`.
    fn leaf_or_struct(
        &mut self,
        path: &str,
        f: &Fields<'l>,
        mut sizes: Vec<u32>,
        access: ExtAccess,
        depth: usize,
    ) {
        let list = self.list;
        let Some(access) = self.access(f, access) else {
            return;
        };
        if !self.array(f, path, &mut sizes) {
            return;
        }
        let elements: u64 = sizes.iter().map(|&s| u64::from(s)).product();
        if elements > MAX_ARRAY_ELEMENTS {
            let e = f.array.or(f.name);
            if let Some(e) = e {
                self.diags.push(list.error_at(
                    e,
                    e.value_pos,
                    format!("{path}: {elements} elements, at most {MAX_ARRAY_ELEMENTS}"),
                ));
            }
            return;
        }
        let word = f.ty.map_or("UNS32".to_string(), |e| {
            e.value.text.trim().to_ascii_uppercase()
        });
        let ty = match (elementary(&word, self.string_chars), word.as_str()) {
            (Some(t), _) => t,
            (None, "VSTRING") => match self.vstring(f) {
                Some(t) => t,
                None => return,
            },
            (None, _) => {
                let Some(s) = self.structs.get(&word).copied() else {
                    if let Some(e) = f.ty {
                        self.diags.push(list.error_at(
                            e,
                            e.value_pos,
                            format!(
                                "{}: unknown type {word} (BOOLEAN, SGN08, UNS08, SGN16, UNS16, SGN32, UNS32, REAL64, STRING, VSTRING or a struct[i].name)",
                                e.name.text
                            ),
                        ));
                    }
                    return;
                };
                if depth >= MAX_NESTING {
                    if let Some(e) = f.ty {
                        self.diags.push(list.error_at(
                            e,
                            e.value_pos,
                            format!(
                                "{}: structures nested more than {MAX_NESTING} deep (does {word} contain itself?)",
                                e.name.text
                            ),
                        ));
                    }
                    return;
                }
                for el in s.elements.values() {
                    let Some(n) = el.name else { continue };
                    let Some(member) = self.name(n) else { continue };
                    let child = format!("{path}.{member}");
                    self.leaf_or_struct(&child, el, sizes.clone(), access, depth + 1);
                }
                return;
            }
        };
        let elements = elements as usize;
        let bytes = path.len()
            + ENTRY_BYTES
            + elements
                * match ty {
                    VarType::String(max_chars) => {
                        std::mem::size_of::<Box<str>>() + usize::from(max_chars)
                    }
                    _ => std::mem::size_of::<f64>(),
                };
        if self.out.len() >= MAX_LEAVES || self.bytes + bytes > MAX_TABLE_BYTES {
            if let Some(e) = f.name {
                self.diags.push(list.error_at(
                    e,
                    e.value_pos,
                    format!(
                        "{path}: more than {MAX_LEAVES} V.E. variables or {MAX_TABLE_BYTES} bytes in all"
                    ),
                ));
            }
            return;
        }
        self.bytes += bytes;
        self.out.push(ExtVar {
            name: path.to_string(),
            sizes,
            ty,
            access,
        });
    }
}

/// A BOOLEAN list value: 0/1 or FALSE/TRUE.
fn bool_value(list: &ParamList, e: &Entry) -> Result<bool, Diagnostic> {
    match e.value.text.trim().to_ascii_uppercase().as_str() {
        "0" | "FALSE" => Ok(false),
        "1" | "TRUE" => Ok(true),
        _ => Err(list.error_at(
            e,
            e.value_pos,
            format!(
                "{}: 0, 1, FALSE or TRUE expected, found `{}`",
                e.name.text, e.value.text
            ),
        )),
    }
}

/// `var[i]` with i beyond the kernel's bound.
fn index_error(list: &ParamList, e: &Entry, what: &str, max: u32) -> Diagnostic {
    list.error_at(
        e,
        e.name_pos,
        format!("{}: {what} index must be below {max}", e.name.text),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::list::parse_list;

    fn read(text: &str) -> (ExtVarTable, Vec<Diagnostic>) {
        let (list, errs) = parse_list(Path::new("ve.lis"), text);
        assert!(errs.is_empty(), "{errs:?}");
        let mut d = Vec::new();
        let (t, _) = interpret_ext_vars(&list, &mut d);
        (t, d)
    }

    #[test]
    fn structures_unfold_into_leaves_with_the_arrays_on_their_path() {
        let (t, d) = read(
            "var[0].name Count\nvar[0].type SGN32\n\
             var[1].name info\nvar[1].type PT\nvar[1].array_elements 2\nvar[1].access_rights READ_ONLY\n\
             struct[0].name PT\nstruct[0].element[0].name X\nstruct[0].element[0].type UNS16\n\
             struct[0].element[1].name TAG\nstruct[0].element[1].type STRING\n\
             struct[0].element[1].access_rights READ_WRITE\n",
        );
        assert!(d.is_empty(), "{d:?}");
        let names: Vec<_> = t.vars.iter().map(|v| v.name.as_str()).collect();
        assert_eq!(names, ["COUNT", "INFO.TAG", "INFO.X"]);
        let x = t.get("INFO.X").expect("leaf");
        assert_eq!(
            (x.sizes.as_slice(), x.ty, x.access),
            (&[2][..], VarType::Uns16, ExtAccess::ReadOnly)
        );
        let tag = t.get("INFO.TAG").expect("leaf");
        assert_eq!(tag.ty, VarType::String(20));
        assert_eq!(tag.access, ExtAccess::ReadWrite);
    }

    #[test]
    fn a_structure_containing_itself_stops_at_the_nesting_bound() {
        let (t, d) = read(
            "var[0].name A\nvar[0].type LOOP\nstruct[0].name LOOP\n\
             struct[0].element[0].name IN\nstruct[0].element[0].type LOOP\n",
        );
        assert!(t.vars.is_empty());
        assert_eq!(d.len(), 1, "{d:?}");
        assert!(d[0].message.contains("nested"), "{}", d[0].message);
    }
}
