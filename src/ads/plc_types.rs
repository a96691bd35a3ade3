//! The HLI's PLC data types as a TwinCAT 3 PLC runtime describes them: base types, `STRING(n)`,
//! `ARRAY [a..b] OF T` and the HLI structs with their byte layouts, encoded as
//! `AdsDatatypeEntry` records for the data-type services (upload 0xF00E, by name 0xF011).
//!
//! Struct layouts: `kimblad/TwinSharp` `TwinSharp/CNC/Structs.cs` (all `Pack = 1`, the HLI's
//! packing). Member names are the HLI's where the HLI documentation or the symbol table names
//! them (`mode_and_state.state_r.mode`, `mc_error.satz_r.kopf.error_id`, infosys
//! `tf5200_hli_interface/174914699.html`), else TwinSharp's field names in snake case.
//! `HLI_ERROR_SATZ_RUMPF` (the 838-byte error body) is served as bytes: its inner constants
//! (`HLI_ERR_MASK_MAXIDX`, …) are not public in those sources, and ncchannel leaves it empty.
//!
//! Entry layout (Beckhoff AdsLib `AdsDef.h` `AdsDatatypeEntry`; `jisotalo/ads-client`
//! `parseAdsResponseDataType`): entry length, version 1, hash, base-type hash, size, offset,
//! ADS data type, flags (u32 each), name/type/comment lengths, array dimensions and sub-item
//! count (u16 each), the three NUL-terminated texts, one (lower bound, elements) pair per
//! dimension, then each sub-item as a whole entry of its own.

/// ADS data type ids (`ADST_*`, AdsLib `AdsDef.h`).
pub(crate) mod adst {
    pub const INT16: u32 = 2;
    pub const INT32: u32 = 3;
    pub const UINT8: u32 = 17;
    pub const UINT16: u32 = 18;
    pub const UINT32: u32 = 19;
    pub const STRING: u32 = 30;
    pub const BIT: u32 = 33;
    pub const BIGTYPE: u32 = 65;
}

/// `ADSDATATYPEFLAG_DATATYPE`: the entry describes a type.
const FLAG_DATATYPE: u32 = 0x1;
/// `ADSDATATYPEFLAG_DATAITEM`: the entry describes a member of a struct.
const FLAG_DATAITEM: u32 = 0x2;
/// Longest type name parsed (`ARRAY [..] OF …` included).
const MAX_TYPE_NAME_BYTES: usize = 255;
/// Nesting bound when resolving member types (the HLI nests three deep).
const MAX_DEPTH: usize = 8;

/// One member of an HLI struct: name, type name, byte offset in the struct.
pub(crate) struct Member {
    pub name: &'static str,
    pub ty: &'static str,
    pub offset_bytes: u32,
}

/// An HLI struct: name, size in bytes, members in layout order.
pub(crate) struct Struct {
    pub name: &'static str,
    pub size_bytes: u32,
    pub members: &'static [Member],
}

const fn m(name: &'static str, ty: &'static str, offset_bytes: u32) -> Member {
    Member {
        name,
        ty,
        offset_bytes,
    }
}

/// Every HLI struct the symbol table uses (TwinSharp `Structs.cs`).
pub(crate) static STRUCTS: &[Struct] = &[
    Struct {
        name: "HLI_IMCM_MODE_STATE",
        size_bytes: 8,
        members: &[m("mode", "UDINT", 0), m("state", "UDINT", 4)],
    },
    Struct {
        name: "HLI_PROC_TRANS_TO_MODE_STATE",
        size_bytes: 327,
        members: &[
            m("from_mode", "UDINT", 0),
            m("from_state", "UDINT", 4),
            m("to_mode", "UDINT", 8),
            m("to_state", "UDINT", 12),
            m("channel_number", "UDINT", 16),
            m("fill_up_1", "DINT", 20),
            m("parameter", "STRING(298)", 24),
            m("fill_up_2", "DINT", 323),
        ],
    },
    Struct {
        name: "HLI_ERROR_SATZ",
        size_bytes: 942,
        members: &[
            m("kopf", "HLI_ERROR_SATZ_KOPF", 0),
            m("rumpf", "ARRAY [0..837] OF BYTE", 104),
        ],
    },
    Struct {
        name: "HLI_ERROR_SATZ_KOPF",
        size_bytes: 104,
        members: &[
            m("error_id", "UDINT", 0),
            m("fill_up_1", "DINT", 4),
            m("modul_name", "STRING(15)", 8),
            m("line", "DINT", 24),
            m("util_error_id", "UDINT", 28),
            m("util_modul_name", "STRING(15)", 32),
            m("util_line", "DINT", 48),
            m("multiple_id", "UINT", 52),
            m("bf_type", "UINT", 54),
            m("cnc_channel", "UINT", 56),
            m("kommu_id", "UINT", 58),
            m("suppress_tc2_event_log_output", "BOOL", 60),
            m("fill_up_2", "BOOL", 61),
            m("fill_up_3", "INT", 62),
            m("time_stamp", "HLI_FB_ZEITANGABE", 64),
            m("version_name", "STRING(15)", 72),
            m("fill_up_4", "DINT", 88),
            m("fill_up_5", "DINT", 92),
            m("rectification_type", "UINT", 96),
            m("reaction_type", "UINT", 98),
            m("body_type", "UDINT", 100),
        ],
    },
    Struct {
        name: "HLI_FB_ZEITANGABE",
        size_bytes: 8,
        members: &[
            m("date_counter", "UDINT", 0),
            m("cycle_counter", "UDINT", 4),
        ],
    },
    // TwinSharp `Structs.cs` `TECHNO_UNIT_CH` (please_rw, done_w, TechnologyType, fill_up_1,
    // MSTH_PROCESS_CH byte[39]); the data's HLI path is `attribut_r.data` (TF5200 HLI "Data
    // of the M/H function": `techno_unit_std_sync[k].attribut_r.data[0]`). The name of
    // attribut_r's type is not public: ncchannel calls it TECHNO_UNIT_CH_ATTRIBUT.
    Struct {
        name: "TECHNO_UNIT_CH",
        size_bytes: 47,
        members: &[
            m("please_rw", "BOOL", 0),
            m("done_w", "BOOL", 1),
            m("type", "UINT", 2),
            m("fill_up_1", "DINT", 4),
            m("attribut_r", "TECHNO_UNIT_CH_ATTRIBUT", 8),
        ],
    },
    Struct {
        name: "TECHNO_UNIT_CH_ATTRIBUT",
        size_bytes: 39,
        members: &[m("data", "ARRAY [0..38] OF BYTE", 0)],
    },
    // TF5200 HLI "Data of the M/H function" (the first 32 bytes of `attribut_r.data` for M
    // and H); TwinSharp `Structs.cs` `HLI_M_H_PROZESS`. Served by name (0xF011).
    Struct {
        name: "HLI_M_H_PROZESS",
        size_bytes: 32,
        members: &[
            m("nr", "UDINT", 0),
            m("time", "DINT", 4),
            m("block_nr", "UDINT", 8),
            m("prg_line", "UDINT", 12),
            m("add_value", "DINT", 16),
            m("nr_late_sync", "UINT", 20),
            m("fill_up_1", "UINT", 22),
            m("synch_mode", "UDINT", 24),
            m("fill_up_2", "DINT", 28),
        ],
    },
    Struct {
        name: "HLI_ADD_CMD_VALUE",
        size_bytes: 32,
        members: &[
            m("m_add_pos_value", "DINT", 0),
            m("m_add_speed_value", "DINT", 4),
            m("sgn32_free_1", "DINT", 8),
            m("sgn32_free_2", "DINT", 12),
            m("sgn32_free_3", "DINT", 16),
            m("sgn32_free_4", "DINT", 20),
            m("sgn32_free_5", "DINT", 24),
            m("sgn32_free_6", "DINT", 28),
        ],
    },
    Struct {
        name: "HLI_HB_DISPLAY",
        size_bytes: 10,
        members: &[
            m("state", "UINT", 0),
            m("operation_mode", "UINT", 2),
            m("control_element", "UINT", 4),
            m("tipp_geschw", "DINT", 6),
        ],
    },
    Struct {
        name: "HLI_HB_ACTIVATION",
        size_bytes: 12,
        members: &[
            m("logical_axis_number", "UINT", 0),
            m("control_element", "UINT", 2),
            m("operation_mode", "UINT", 4),
            m("parameter_index", "UINT", 6),
            m("fill_up_1", "UINT", 8),
            m("fill_up_2", "UINT", 10),
        ],
    },
    Struct {
        name: "HLI_HB_TIP_PARAMETER",
        size_bytes: 8,
        members: &[
            m("logical_axis_number", "UINT", 0),
            m("fill_up_1", "UINT", 2),
            m("speed", "UDINT", 4),
        ],
    },
    Struct {
        name: "HLI_HB_JOG_PARAMETER",
        size_bytes: 16,
        members: &[
            m("logical_axis_number", "UINT", 0),
            m("fill_up_1", "UINT", 2),
            m("distance", "UDINT", 4),
            m("speed", "UDINT", 8),
            m("fill_up_2", "DINT", 12),
        ],
    },
    Struct {
        name: "HLI_HB_HR_PARAMETER",
        size_bytes: 8,
        members: &[
            m("logical_axis_number", "UINT", 0),
            m("fill_up_1", "UINT", 2),
            m("resolution", "DINT", 4),
        ],
    },
    Struct {
        name: "HLI_HB_RAPID_KEY",
        size_bytes: 8,
        members: &[
            m("logical_key_number", "UINT", 0),
            m("key_pressed", "UINT", 2),
            m("fill_up_1", "UDINT", 4),
        ],
    },
    Struct {
        name: "HLI_HB_KEY",
        size_bytes: 16,
        members: &[
            m("logical_key_number", "UINT", 0),
            m("direction", "INT", 2),
            m("life_time", "UDINT", 4),
            m("f_refresh", "BOOL", 8),
            m("fill_up_1", "BOOL", 9),
            m("fill_up_2", "BOOL", 10),
            m("fill_up_3", "BOOL", 11),
            m("fill_up_4", "DINT", 12),
        ],
    },
];

/// IEC base types: name, size in bytes, ADS data type.
const BASE: [(&str, u32, u32); 6] = [
    ("BOOL", 1, adst::BIT),
    ("BYTE", 1, adst::UINT8),
    ("INT", 2, adst::INT16),
    ("UINT", 2, adst::UINT16),
    ("DINT", 4, adst::INT32),
    ("UDINT", 4, adst::UINT32),
];

/// A type name resolved.
#[derive(Clone, Copy)]
pub(crate) enum DataType<'a> {
    Base {
        name: &'static str,
        size_bytes: u32,
        adst: u32,
    },
    /// `STRING(n)`: n characters and the NUL, `n + 1` bytes.
    String {
        name: &'a str,
        chars: u32,
    },
    /// `ARRAY [lower..upper] OF element` (one dimension).
    Array {
        name: &'a str,
        lower: i32,
        elements: u32,
        element: &'a str,
    },
    Struct(&'static Struct),
}

impl<'a> DataType<'a> {
    /// The type called `name` (case-insensitive as IEC names are), if the HLI has it.
    pub(crate) fn lookup(name: &'a str) -> Option<DataType<'a>> {
        let name = name.trim();
        if name.len() > MAX_TYPE_NAME_BYTES {
            return None;
        }
        if let Some(&(n, size_bytes, adst)) =
            BASE.iter().find(|(n, ..)| n.eq_ignore_ascii_case(name))
        {
            return Some(DataType::Base {
                name: n,
                size_bytes,
                adst,
            });
        }
        if let Some(s) = STRUCTS.iter().find(|s| s.name.eq_ignore_ascii_case(name)) {
            return Some(DataType::Struct(s));
        }
        parse_string(name).or_else(|| parse_array(name))
    }

    pub(crate) fn name(&self) -> &str {
        match self {
            DataType::Base { name, .. } => name,
            DataType::String { name, .. } | DataType::Array { name, .. } => name,
            DataType::Struct(s) => s.name,
        }
    }

    pub(crate) fn adst(&self) -> u32 {
        match self {
            DataType::Base { adst, .. } => *adst,
            DataType::String { .. } => adst::STRING,
            DataType::Array { .. } | DataType::Struct(_) => adst::BIGTYPE,
        }
    }

    /// Size in bytes; `None` for an array of an unknown type or one nested too deep.
    pub(crate) fn size_bytes(&self) -> Option<u32> {
        self.size_at(0)
    }

    fn size_at(&self, depth: usize) -> Option<u32> {
        if depth > MAX_DEPTH {
            return None;
        }
        match self {
            DataType::Base { size_bytes, .. } => Some(*size_bytes),
            DataType::String { chars, .. } => chars.checked_add(1),
            DataType::Array {
                elements, element, ..
            } => DataType::lookup(element)?
                .size_at(depth + 1)?
                .checked_mul(*elements),
            DataType::Struct(s) => Some(s.size_bytes),
        }
    }

    /// The `AdsDatatypeEntry` of this type (`None` when its size is unknown).
    pub(crate) fn entry(&self) -> Option<Vec<u8>> {
        let size = self.size_bytes()?;
        let mut dims = Vec::new();
        let mut items = Vec::new();
        let base = match self {
            DataType::Array {
                lower,
                elements,
                element,
                ..
            } => {
                dims.push((*lower, *elements));
                *element
            }
            DataType::Struct(s) => {
                for mem in s.members {
                    items.push(member_entry(mem)?);
                }
                ""
            }
            _ => "",
        };
        Some(encode(&EntryHead {
            name: self.name(),
            base,
            size,
            offset: 0,
            adst: self.adst(),
            flags: FLAG_DATATYPE,
            dims: &dims,
            items: &items,
        }))
    }

    /// Every type this one refers to, itself first (for the upload's list of types).
    pub(crate) fn closure(&self, out: &mut Vec<String>) {
        self.closure_at(out, 0);
    }

    fn closure_at(&self, out: &mut Vec<String>, depth: usize) {
        if depth > MAX_DEPTH || out.iter().any(|n| n == self.name()) {
            return;
        }
        out.push(self.name().to_string());
        let refs: Vec<&str> = match self {
            DataType::Array { element, .. } => vec![element],
            DataType::Struct(s) => s.members.iter().map(|m| m.ty).collect(),
            _ => Vec::new(),
        };
        for r in refs {
            if let Some(t) = DataType::lookup(r) {
                t.closure_at(out, depth + 1);
            }
        }
    }

    /// Every member and array element below this type, depth first, as symbol names
    /// continue a root's name (`.kopf`, `.kopf.error_id`, `[3]`, `[3].done_w`): the path,
    /// its byte offset in this type and its type. At most `limit` entries and
    /// [`MAX_DEPTH`] levels (the HLI's types are finite; the bounds keep a wrong table from
    /// growing without end).
    pub(crate) fn sub_paths(&self, limit: usize) -> Vec<(String, u32, DataType<'a>)> {
        let mut out = Vec::new();
        self.sub_paths_at(&mut String::new(), 0, 0, limit, &mut out);
        out
    }

    fn sub_paths_at(
        &self,
        path: &mut String,
        at: u32,
        depth: usize,
        limit: usize,
        out: &mut Vec<(String, u32, DataType<'a>)>,
    ) {
        if depth >= MAX_DEPTH {
            return;
        }
        let visit = |out: &mut Vec<_>, path: &mut String, part: String, at, ty: DataType<'a>| {
            if out.len() >= limit {
                return;
            }
            let len = path.len();
            path.push_str(&part);
            out.push((path.clone(), at, ty));
            ty.sub_paths_at(path, at, depth + 1, limit, out);
            path.truncate(len);
        };
        match self {
            DataType::Struct(st) => {
                for mem in st.members {
                    let Some(ty) = DataType::lookup(mem.ty) else {
                        continue;
                    };
                    let Some(off) = at.checked_add(mem.offset_bytes) else {
                        continue;
                    };
                    visit(out, path, format!(".{}", mem.name), off, ty);
                }
            }
            DataType::Array {
                lower,
                elements,
                element,
                ..
            } => {
                let Some(el) = DataType::lookup(element) else {
                    return;
                };
                let Some(size) = el.size_bytes() else { return };
                for k in 0..*elements {
                    let Some(off) = k.checked_mul(size).and_then(|o| at.checked_add(o)) else {
                        return;
                    };
                    let index = i64::from(*lower) + i64::from(k);
                    visit(out, path, format!("[{index}]"), off, el);
                }
            }
            DataType::Base { .. } | DataType::String { .. } => {}
        }
    }

    #[cfg(test)]
    /// The member at `path` (`.a.b[3].c`, as symbol names continue a root's name): byte
    /// offset, size and type name. `None` when the path names nothing in this type.
    pub(crate) fn member_at(&self, path: &'a str) -> Option<(u32, u32, &'a str)> {
        let mut ty = *self;
        let mut at = 0u32;
        let mut rest = path;
        while !rest.is_empty() {
            if let Some(r) = rest.strip_prefix('.') {
                let DataType::Struct(s) = ty else { return None };
                let end = r.find(['.', '[']).unwrap_or(r.len());
                let mem = s.members.iter().find(|m| m.name == &r[..end])?;
                at = at.checked_add(mem.offset_bytes)?;
                ty = DataType::lookup(mem.ty)?;
                rest = &r[end..];
            } else if let Some(r) = rest.strip_prefix('[') {
                let DataType::Array {
                    lower,
                    elements,
                    element,
                    ..
                } = ty
                else {
                    return None;
                };
                let end = r.find(']')?;
                let i: i64 = r[..end].trim().parse().ok()?;
                let k = u32::try_from(i - i64::from(lower))
                    .ok()
                    .filter(|&k| k < elements)?;
                let el = DataType::lookup(element)?;
                at = at.checked_add(k.checked_mul(el.size_bytes()?)?)?;
                ty = el;
                rest = &r[end + 1..];
            } else {
                return None;
            }
        }
        Some((at, ty.size_bytes()?, ty.name_a()))
    }

    /// The name with the lifetime of the text it was parsed from.
    pub(crate) fn name_a(self) -> &'a str {
        match self {
            DataType::Base { name, .. } => name,
            DataType::String { name, .. } | DataType::Array { name, .. } => name,
            DataType::Struct(s) => s.name,
        }
    }
}

/// `STRING(n)`.
fn parse_string(name: &str) -> Option<DataType<'_>> {
    let inner = strip_prefix_ci(name, "STRING(")?.strip_suffix(')')?;
    let chars: u32 = inner
        .trim()
        .parse()
        .ok()
        .filter(|&n| n > 0 && n <= 65_535)?;
    Some(DataType::String { name, chars })
}

/// `ARRAY [a..b] OF T` (one dimension, `b >= a`).
fn parse_array(name: &str) -> Option<DataType<'_>> {
    let rest = strip_prefix_ci(name, "ARRAY")?.trim_start();
    let rest = rest.strip_prefix('[')?;
    let close = rest.find(']')?;
    let (lo, hi) = rest[..close].split_once("..")?;
    let lower: i32 = lo.trim().parse().ok()?;
    let upper: i32 = hi.trim().parse().ok()?;
    let elements = u32::try_from(i64::from(upper) - i64::from(lower) + 1)
        .ok()
        .filter(|&n| n > 0)?;
    let element = strip_prefix_ci(rest[close + 1..].trim_start(), "OF")?.trim();
    if element.is_empty() {
        return None;
    }
    Some(DataType::Array {
        name,
        lower,
        elements,
        element,
    })
}

fn strip_prefix_ci<'s>(s: &'s str, prefix: &str) -> Option<&'s str> {
    let head = s.get(..prefix.len())?;
    head.eq_ignore_ascii_case(prefix)
        .then(|| &s[prefix.len()..])
}

/// A struct member as a sub-item entry: its name, its type's name, size, offset, ADS type.
fn member_entry(mem: &Member) -> Option<Vec<u8>> {
    let ty = DataType::lookup(mem.ty)?;
    Some(encode(&EntryHead {
        name: mem.name,
        base: ty.name(),
        size: ty.size_bytes()?,
        offset: mem.offset_bytes,
        adst: ty.adst(),
        flags: FLAG_DATAITEM,
        dims: &[],
        items: &[],
    }))
}

struct EntryHead<'e> {
    name: &'e str,
    base: &'e str,
    size: u32,
    offset: u32,
    adst: u32,
    flags: u32,
    dims: &'e [(i32, u32)],
    items: &'e [Vec<u8>],
}

fn encode(h: &EntryHead<'_>) -> Vec<u8> {
    let mut out = Vec::with_capacity(64 + h.name.len() + h.base.len());
    out.extend_from_slice(&[0; 4]);
    for w in [1, 0, 0, h.size, h.offset, h.adst, h.flags] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    for n in [h.name.len(), h.base.len(), 0, h.dims.len(), h.items.len()] {
        out.extend_from_slice(&(n as u16).to_le_bytes());
    }
    for text in [h.name, h.base, ""] {
        out.extend_from_slice(text.as_bytes());
        out.push(0);
    }
    for (lower, elements) in h.dims {
        out.extend_from_slice(&lower.to_le_bytes());
        out.extend_from_slice(&elements.to_le_bytes());
    }
    for item in h.items {
        out.extend_from_slice(item);
    }
    let n = out.len() as u32;
    out[0..4].copy_from_slice(&n.to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_struct_member_fits_and_resolves() {
        for s in STRUCTS {
            let mut end = 0;
            for mem in s.members {
                let ty = DataType::lookup(mem.ty).unwrap_or_else(|| panic!("{}", mem.ty));
                let size = ty.size_bytes().unwrap();
                assert!(mem.offset_bytes >= end, "{}.{} overlaps", s.name, mem.name);
                end = mem.offset_bytes + size;
            }
            assert_eq!(end, s.size_bytes, "{} members fill it", s.name);
        }
    }

    #[test]
    fn paths_walk_members_and_array_elements() {
        let t = DataType::lookup("ARRAY [0..19] OF TECHNO_UNIT_CH").unwrap();
        assert_eq!(t.size_bytes(), Some(940));
        assert_eq!(t.member_at("[2].done_w"), Some((95, 1, "BOOL")));
        assert_eq!(t.member_at("[20]"), None);
        assert_eq!(t.member_at("[1].type"), Some((49, 2, "UINT")));
        assert_eq!(
            t.member_at("[1].attribut_r.data"),
            Some((55, 39, "ARRAY [0..38] OF BYTE"))
        );
        let mh = DataType::lookup("HLI_M_H_PROZESS").unwrap();
        assert_eq!(mh.member_at(".synch_mode"), Some((24, 4, "UDINT")));
        let e = DataType::lookup("hli_error_satz").unwrap();
        assert_eq!(e.member_at(".kopf.error_id"), Some((0, 4, "UDINT")));
        assert_eq!(
            e.member_at(".kopf.time_stamp.cycle_counter"),
            Some((68, 4, "UDINT"))
        );
        assert_eq!(e.member_at(".nope"), None);
    }

    #[test]
    fn sub_paths_name_every_level_where_member_at_finds_it() {
        let e = DataType::lookup("HLI_ERROR_SATZ").unwrap();
        let paths = e.sub_paths(10_000);
        assert_eq!(paths[0].0, ".kopf");
        let names: Vec<&str> = paths.iter().map(|p| p.0.as_str()).collect();
        assert!(names.contains(&".kopf.time_stamp.cycle_counter"));
        assert!(names.contains(&".rumpf[837]"));
        for (path, at, ty) in &paths {
            assert_eq!(
                e.member_at(path),
                Some((*at, ty.size_bytes().unwrap(), ty.name_a())),
                "{path}"
            );
        }
        assert_eq!(e.sub_paths(3).len(), 3, "bounded");
    }

    #[test]
    fn struct_entry_carries_its_members() {
        let e = DataType::lookup("HLI_IMCM_MODE_STATE")
            .unwrap()
            .entry()
            .unwrap();
        assert_eq!(
            u32::from_le_bytes([e[0], e[1], e[2], e[3]]) as usize,
            e.len()
        );
        assert_eq!(&e[16..20], &8u32.to_le_bytes(), "size");
        assert_eq!(&e[40..42], &2u16.to_le_bytes(), "two sub-items");
        assert!(DataType::lookup("ARRAY [3..1] OF BYTE").is_none());
        assert!(DataType::lookup("ARRAY [0..1] OF NOPE")
            .unwrap()
            .entry()
            .is_none());
    }
}
