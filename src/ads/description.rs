//! What a served object is: its type, size, access, unit and source, and the 84-byte object
//! description record the COM task lists at `0x130100 + ch`.
//!
//! Record layout (little-endian) from Beckhoff infosys "Requesting object description"
//! (`tf5200_ads_access_to_cnc/855973643.html`), as TwinSharp `CNC.cs` (`ObjectDescription`)
//! parses it: id u32, size u32, write access u16, padding u16, index group u32, index offset
//! u32, name STRING(32), type STRING(32).

use super::result::AdsResult;

/// Bytes of one object description record.
pub(crate) const RECORD_BYTES: usize = 84;
/// Bytes of the name and type fields of a record (NUL-padded).
const TEXT_FIELD_BYTES: usize = 32;

/// What a served object holds. The description record carries the kernel's type text
/// ([`AdsType::record_name`]); the object map in docs/ads.md the layout ([`AdsType::name`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AdsType {
    Bool,
    Byte,
    Word,
    Int,
    Dword,
    Dint,
    Lword,
    Lreal,
    String,
    /// Two DWORDs (e.g. `ncc_stream_fill_r`).
    Dword2,
    /// One LREAL per axis.
    LrealArray,
    /// `{DINT mode; DINT state}` (`mcm_active_r`).
    ModeState,
    /// The kernel's tool ID, 16 bytes: basic, sister, variant (DINT), sister_valid,
    /// variant_valid (BOOL), 2 bytes padding (`mc_active_tool_id_r`; TF5200 HLI "Data of the
    /// T function", HLI_TOOL_ID).
    ToolId,
    /// A zero-length write that triggers an action.
    Trigger,
    /// A PLC type by name (HLI symbols).
    Named(&'static str),
}

impl AdsType {
    /// The type text of the description record, as the kernel writes it: one of the IEC names
    /// infosys 855973643 lists (BOOL, BYTE, WORD, INT, DWORD, DINT, LWORD, LREAL, STRING) for a
    /// scalar or string, "NONE" for anything else — the ISG object dump types every structure,
    /// array and trigger "NONE" (`mcm_active_r`, `mc_active_g_functions_r`, `cnc_time_reset`).
    pub fn record_name(self) -> &'static str {
        match self {
            AdsType::Dword2
            | AdsType::LrealArray
            | AdsType::ModeState
            | AdsType::ToolId
            | AdsType::Trigger
            | AdsType::Named(_) => "NONE",
            scalar => scalar.name(),
        }
    }

    /// The type as IEC 61131-3 declares it (structures by their members), for the object map.
    pub fn name(self) -> &'static str {
        match self {
            AdsType::Bool => "BOOL",
            AdsType::Byte => "BYTE",
            AdsType::Word => "WORD",
            AdsType::Int => "INT",
            AdsType::Dword => "DWORD",
            AdsType::Dint => "DINT",
            AdsType::Lword => "LWORD",
            AdsType::Lreal => "LREAL",
            AdsType::String => "STRING",
            AdsType::Dword2 => "ARRAY [0..1] OF DWORD",
            AdsType::LrealArray => "ARRAY [1..axes] OF LREAL",
            AdsType::ModeState => "STRUCT mode : DINT; state : DINT; END_STRUCT",
            AdsType::ToolId => {
                "STRUCT basic : DINT; sister : DINT; variant : DINT; sister_valid : BOOL; \
                 variant_valid : BOOL; END_STRUCT"
            }
            AdsType::Trigger => "NONE",
            AdsType::Named(n) => n,
        }
    }
}

/// Who may do what with an object.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Access {
    Read,
    Write,
    ReadWrite,
}

impl Access {
    pub fn readable(self) -> bool {
        matches!(self, Access::Read | Access::ReadWrite)
    }
    pub fn writable(self) -> bool {
        matches!(self, Access::Write | Access::ReadWrite)
    }
    pub fn letters(self) -> &'static str {
        match self {
            Access::Read => "R",
            Access::Write => "W",
            Access::ReadWrite => "RW",
        }
    }
}

/// One served object at its address, as the description table and the object map list it.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectInfo {
    pub port: u16,
    pub group: u32,
    pub offset: u32,
    pub name: String,
    pub ty: AdsType,
    /// Bytes a read answers (strings: their whole buffer).
    pub size: u32,
    pub(crate) access: Access,
    pub unit: &'static str,
    /// Where the address, type and unit come from.
    pub source: &'static str,
}

/// The 84-byte description record of `o` with id `id`. Names and types longer than 31 bytes
/// are cut (a record has 32 bytes for each, NUL-terminated).
pub fn record(id: u32, o: &ObjectInfo) -> [u8; RECORD_BYTES] {
    let mut r = [0u8; RECORD_BYTES];
    r[0..4].copy_from_slice(&id.to_le_bytes());
    r[4..8].copy_from_slice(&o.size.to_le_bytes());
    r[8..10].copy_from_slice(&u16::from(o.access.writable()).to_le_bytes());
    r[12..16].copy_from_slice(&o.group.to_le_bytes());
    r[16..20].copy_from_slice(&o.offset.to_le_bytes());
    put_text(&mut r[20..20 + TEXT_FIELD_BYTES], &o.name);
    put_text(&mut r[52..52 + TEXT_FIELD_BYTES], o.ty.record_name());
    r
}

fn put_text(field: &mut [u8], text: &str) {
    let n = text.len().min(field.len() - 1);
    field[..n].copy_from_slice(&text.as_bytes()[..n]);
}

/// Reads of a description table (offset 0 = count, offset k = record k, a multiple of 84
/// bytes = records k, k+1, … in sequence; infosys 855973643).
pub(crate) fn read_table(
    objects: &[ObjectInfo],
    offset: u32,
    length: u32,
) -> Result<Vec<u8>, AdsResult> {
    if offset == 0 {
        if length < 4 {
            return Err(AdsResult::INVALID_SIZE);
        }
        return Ok((objects.len() as u32).to_le_bytes().to_vec());
    }
    let first = offset as usize - 1;
    if first >= objects.len() {
        return Err(AdsResult::INVALID_OFFSET);
    }
    let length = length as usize;
    if length < RECORD_BYTES {
        return Err(AdsResult::INVALID_SIZE);
    }
    // A multiple of 84 bytes asks for records in sequence; anything else for one record.
    let wanted = if length.is_multiple_of(RECORD_BYTES) {
        length / RECORD_BYTES
    } else {
        1
    };
    let end = first.saturating_add(wanted).min(objects.len());
    let mut out = Vec::with_capacity((end - first) * RECORD_BYTES);
    for (i, o) in objects[first..end].iter().enumerate() {
        out.extend_from_slice(&record((first + i + 1) as u32, o));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(name: &str) -> ObjectInfo {
        ObjectInfo {
            port: 553,
            group: 0x120101,
            offset: 0x0D,
            name: name.into(),
            ty: AdsType::Dword,
            size: 4,
            access: Access::Read,
            unit: "",
            source: "",
        }
    }

    #[test]
    fn record_layout_is_byte_exact() {
        let r = record(7, &info("mc_block_count_r"));
        assert_eq!(&r[0..4], &7u32.to_le_bytes());
        assert_eq!(&r[4..8], &4u32.to_le_bytes());
        assert_eq!(&r[8..12], &[0, 0, 0, 0]);
        assert_eq!(&r[12..16], &0x120101u32.to_le_bytes());
        assert_eq!(&r[16..20], &0x0Du32.to_le_bytes());
        assert_eq!(&r[20..36], b"mc_block_count_r");
        assert!(r[36..52].iter().all(|&b| b == 0));
        assert_eq!(&r[52..57], b"DWORD");
        assert_eq!(r[57], 0);
    }

    #[test]
    fn structures_and_triggers_are_typed_none_as_the_kernel_types_them() {
        for ty in [
            AdsType::ModeState,
            AdsType::Dword2,
            AdsType::LrealArray,
            AdsType::Trigger,
        ] {
            let r = record(1, &ObjectInfo { ty, ..info("x") });
            assert_eq!(&r[52..57], b"NONE\0", "{ty:?}");
        }
        let r = record(
            1,
            &ObjectInfo {
                ty: AdsType::Lreal,
                ..info("x")
            },
        );
        assert_eq!(&r[52..58], b"LREAL\0");
    }

    #[test]
    fn table_reads_count_one_record_or_a_run() {
        let objs: Vec<_> = ["a", "b", "c"].iter().map(|n| info(n)).collect();
        assert_eq!(read_table(&objs, 0, 4).unwrap(), 3u32.to_le_bytes());
        assert_eq!(read_table(&objs, 2, 84).unwrap()[20], b'b');
        let all = read_table(&objs, 1, 3 * 84).unwrap();
        assert_eq!(all.len(), 3 * 84);
        assert_eq!(all[2 * 84 + 20], b'c');
        // More records asked than exist: the ones that exist.
        assert_eq!(read_table(&objs, 2, 5 * 84).unwrap().len(), 2 * 84);
        assert_eq!(read_table(&objs, 4, 84), Err(AdsResult::INVALID_OFFSET));
        assert_eq!(read_table(&objs, 1, 83), Err(AdsResult::INVALID_SIZE));
    }
}
