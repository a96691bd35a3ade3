//! The TwinCAT PLC runtime's symbol services, encoded: symbol entries (0xF009 info by name,
//! 0xF00B upload), upload info (0xF00C, 0xF00F), symbol version (0xF008) and the runtime's
//! device data (0xF100). The HLI ([`super::hli`]) answers them over its symbol table.
//!
//! Index groups and layouts: Beckhoff InfoSys "ADS Index Groups" (TwinCAT 3 PLC runtime);
//! Beckhoff AdsLib `AdsDef.h` (`ADSIGRP_SYM_*`, `AdsSymbolEntry`, `AdsSymbolUploadInfo2`);
//! `stlehmann/pyads` `structs.py` `SAdsSymbolEntry` and `Connection.get_all_symbols`;
//! `jisotalo/ads-client` `parseAdsResponseSymbol`, `readPlcUploadInfo`, `setupPlcConnection`.

use super::result::AdsResult;

/// 0xF008: the symbol version, one byte; changes when the PLC's symbols change.
pub(crate) const GROUP_SYMBOL_VERSION: u32 = 0xF008;
/// 0xF00B: every symbol entry, back to back.
pub(crate) const GROUP_SYMBOL_UPLOAD: u32 = 0xF00B;
/// 0xF00C: upload info 1 (symbol count, symbol bytes).
pub(crate) const GROUP_UPLOAD_INFO: u32 = 0xF00C;
/// 0xF00E: every data type entry, back to back.
pub(crate) const GROUP_TYPE_UPLOAD: u32 = 0xF00E;
/// 0xF00F: upload info 2 (adds data type count and bytes, dynamic symbols).
pub(crate) const GROUP_UPLOAD_INFO2: u32 = 0xF00F;
/// 0xF007: a symbol's group, offset and size by name (ReadWrite, name written; 12 bytes).
pub(crate) const GROUP_LOCATION_BY_NAME: u32 = 0xF007;
/// 0xF011: one data type entry by name (ReadWrite, name written).
pub(crate) const GROUP_TYPE_BY_NAME: u32 = 0xF011;
/// 0xF100: ADS state (u16) and device state (u16) of the runtime, as ReadState answers.
pub(crate) const GROUP_DEVICE_DATA: u32 = 0xF100;
/// ADS states (`ADSSTATE_*`, Beckhoff AdsLib `AdsDef.h`): what ReadState and 0xF100 answer
/// and WriteControl asks for (the system service's are in [`super::system`]).
pub(crate) mod ads_state {
    pub const RESET: u16 = 2;
    pub const RUN: u16 = 5;
    pub const STOP: u16 = 6;
    pub const CONFIG: u16 = 15;
    pub const RECONFIG: u16 = 16;
}
/// The symbol version served: the HLI's symbols are fixed while the server runs.
const SYMBOL_VERSION: u8 = 1;
/// Code page of STRING data and names in upload info 3: Windows-1252 (the HLI's names and
/// texts are ASCII; ads-client reads UTF-8 only for 65001).
const CODE_PAGE_1252: u32 = 1252;
/// Upload info 3 flag `IncludesBaseTypes` (ads-client `ADS_UPLOAD_INFO_FLAGS`): the data-type
/// upload lists the base types too.
const UPLOAD_INCLUDES_BASE_TYPES: u32 = 0x2;
/// `ADSSYMBOLFLAG_READONLY`.
const FLAG_READ_ONLY: u32 = 0x20;

/// What a symbol entry says about one symbol.
pub(crate) struct SymbolInfo<'a> {
    pub name: &'a str,
    pub ty: &'a str,
    pub group: u32,
    pub offset: u32,
    pub size_bytes: u32,
    pub adst: u32,
    pub read_only: bool,
}

/// `AdsSymbolEntry`: entry length, group, offset, size, ADS data type, flags (u32 each),
/// name/type/comment lengths (u16 each), then the three NUL-terminated texts.
pub(crate) fn symbol_entry(s: &SymbolInfo<'_>) -> Vec<u8> {
    let mut out = Vec::with_capacity(30 + s.name.len() + s.ty.len() + 3);
    out.extend_from_slice(&[0; 4]);
    let flags = if s.read_only { FLAG_READ_ONLY } else { 0 };
    for w in [s.group, s.offset, s.size_bytes, s.adst, flags] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    for n in [s.name.len(), s.ty.len(), 0] {
        out.extend_from_slice(&(n as u16).to_le_bytes());
    }
    for text in [s.name, s.ty, ""] {
        out.extend_from_slice(text.as_bytes());
        out.push(0);
    }
    let n = out.len() as u32;
    out[0..4].copy_from_slice(&n.to_le_bytes());
    out
}

/// Counts and byte totals of the two uploads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct UploadInfo {
    pub symbols: u32,
    pub symbol_bytes: u32,
    pub types: u32,
    pub type_bytes: u32,
}

impl UploadInfo {
    /// 0xF00C: upload info 1, 8 bytes.
    pub(crate) fn v1(&self) -> Vec<u8> {
        [self.symbols, self.symbol_bytes]
            .iter()
            .flat_map(|w| w.to_le_bytes())
            .collect()
    }

    /// 0xF00F: upload info 2, 24 bytes (no dynamic symbols: max and used are 0).
    pub(crate) fn v2(&self) -> Vec<u8> {
        [
            self.symbols,
            self.symbol_bytes,
            self.types,
            self.type_bytes,
            0,
            0,
        ]
        .iter()
        .flat_map(|w| w.to_le_bytes())
        .collect()
    }

    /// 0xF00F asked for 64 bytes: upload info 3 adds invalid dynamic symbols (0), the code
    /// page and flags, then 28 reserved bytes (ads-client `readPlcUploadInfo`; the `ads`
    /// crate's `get_symbol_info` reads exactly 64).
    pub(crate) fn v3(&self) -> Vec<u8> {
        let mut out = self.v2();
        for w in [0, CODE_PAGE_1252, UPLOAD_INCLUDES_BASE_TYPES] {
            out.extend_from_slice(&w.to_le_bytes());
        }
        out.resize(64, 0);
        out
    }

    /// 0xF00F: version 3 when `length` has room for it, else version 2.
    pub(crate) fn for_length(&self, length: u32) -> Result<Vec<u8>, AdsResult> {
        match length {
            64.. => Ok(self.v3()),
            24.. => Ok(self.v2()),
            _ => Err(AdsResult::INVALID_SIZE),
        }
    }
}

/// The reply to a read of `length` bytes of a block that has exactly `bytes`: the block when
/// it fits, else 0x705 (a client learns the size from the upload info first).
pub(crate) fn fit(bytes: Vec<u8>, length: u32) -> Result<Vec<u8>, AdsResult> {
    if (length as usize) < bytes.len() {
        return Err(AdsResult::INVALID_SIZE);
    }
    Ok(bytes)
}

/// 0xF008 offset 0: the symbol version (first `length` bytes of one byte).
pub(crate) fn symbol_version(length: u32) -> Result<Vec<u8>, AdsResult> {
    if length == 0 {
        return Err(AdsResult::INVALID_SIZE);
    }
    Ok(vec![SYMBOL_VERSION])
}

/// 0xF100: the runtime's ADS state (`ads_state`: RUN, or STOP after WriteControl STOP or
/// RESET) and device state 0 from `offset` (0 = both, 2 = device state), at most `length`
/// bytes.
pub(crate) fn device_data(ads_state: u16, offset: u32, length: u32) -> Result<Vec<u8>, AdsResult> {
    let mut all = ads_state.to_le_bytes().to_vec();
    all.extend_from_slice(&0u16.to_le_bytes());
    let from = usize::try_from(offset)
        .ok()
        .filter(|&o| o < all.len() && o % 2 == 0)
        .ok_or(AdsResult::INVALID_OFFSET)?;
    let n = (length as usize).min(all.len() - from);
    if n == 0 {
        return Err(AdsResult::INVALID_SIZE);
    }
    Ok(all[from..from + n].to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entry_is_length_prefixed_with_nul_terminated_texts() {
        let e = symbol_entry(&SymbolInfo {
            name: "A.b",
            ty: "BOOL",
            group: 0xF005,
            offset: 7,
            size_bytes: 1,
            adst: 33,
            read_only: true,
        });
        assert_eq!(e.len(), 30 + 4 + 5 + 1);
        assert_eq!(&e[0..4], &(e.len() as u32).to_le_bytes());
        assert_eq!(&e[20..24], &0x20u32.to_le_bytes());
        assert_eq!(&e[30..34], b"A.b\0");
        assert_eq!(&e[34..39], b"BOOL\0");
    }

    #[test]
    fn device_data_is_ads_state_and_device_state() {
        assert_eq!(device_data(5, 0, 4), Ok(vec![5, 0, 0, 0]));
        assert_eq!(device_data(6, 0, 2), Ok(vec![6, 0]));
        assert_eq!(device_data(5, 2, 2), Ok(vec![0, 0]));
        assert_eq!(device_data(5, 4, 2), Err(AdsResult::INVALID_OFFSET));
        assert_eq!(fit(vec![1, 2], 1), Err(AdsResult::INVALID_SIZE));
    }
}
