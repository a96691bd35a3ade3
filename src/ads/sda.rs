//! The SDA task (AMS port 552): NC variable access in the decoder class `0x122300 + ch`.
//!
//! Offsets as documented (ISG kernel docs "Channel-specific interface", 312791435, and "read
//! by handle", 312799627): 0x46 handle by name (ReadWrite: name → u32 handle), 0x47 read by
//! handle (ReadWrite: `{u32 handle, u32 ndims, u32 index…}` → value), 0x48 read by name
//! (ReadWrite: name → value), 0x49 write by handle (Write: `{u32 handle, u32 ndims, u32
//! index…, value}`), 0x4A write by name (Write: name, NUL, value). TwinSharp `ZeroOffsets.cs`
//! also reads and writes a variable with the handle as index offset: `Read/Write(0x1223<ch>,
//! handle)`; that form is served too.
//!
//! Variables served: the external variables `V.E.<name>` — with members and indices as a
//! program writes them (`V.E.SCH.PREFLOW`, `V.E.FARBE[2]`) — in the PLC type of their
//! declared type (TF5200 External variables: BOOLEAN → BOOL, SGN08 … UNS32 → SINT … UDINT,
//! REAL64 → LREAL, STRING → STRING(n), n + 1 bytes NUL-padded), LREAL when no list declares
//! them (read and write; a write takes exactly the type's bytes, a string up to n + 1), and
//! the zero offsets `V.G.NP[i].V`, i = 1…6 for G54…G59 and 0 for G53, all zero (read only: one DINT per configured
//! axis of the channel, 0.1 µm, as TwinSharp `ZeroOffsets.cs` reads and decodes them). Other
//! variable kinds (`V.A.*`, `V.P.*` …) are not modelled and answer "not found" (0x70C).
//! Handles are `0x2000_0000 + n` for the n-th distinct name asked for (at most
//! [`MAX_HANDLES`]); the same name always gets the same handle.

use std::sync::{Arc, Mutex};

use super::backend::{CncBackend, DeviceError, Live, ObjectEncoder, Source, Status};
use super::description::{Access, AdsType, ObjectInfo};
use super::result::AdsResult;
use crate::decoder::vars::ExternalValue;
use crate::lang::block::VarType;
use crate::vocab::axis::slot_of;

pub const PORT: u16 = 552;
/// Decoder class instance of channel ch: `GROUP_DECODER + ch`.
pub(crate) const GROUP_DECODER: u32 = 0x122300;
pub(crate) const HANDLE_BY_NAME: u32 = 0x46;
pub(crate) const READ_BY_HANDLE: u32 = 0x47;
pub(crate) const READ_BY_NAME: u32 = 0x48;
pub(crate) const WRITE_BY_HANDLE: u32 = 0x49;
pub(crate) const WRITE_BY_NAME: u32 = 0x4A;
/// First handle; handles look like the documented `0x20012341`.
const HANDLE_BASE: u32 = 0x2000_0000;
/// Distinct variable names a server hands out handles for.
pub(crate) const MAX_HANDLES: usize = 4096;
const MAX_NAME_BYTES: usize = 255;
/// ADS "insufficient memory": the handle table is full.
const NO_MEMORY: AdsResult = AdsResult(0x70A);
const LOGICAL: u32 = 0x100000;
/// Bytes of a V.E. value no list declares: an LREAL.
const VALUE_BYTES: usize = 8;
/// Zero-offset groups `V.G.NP[0]` … `V.G.NP[6]` in the kernel's numbering (TF5200 "Zero
/// offset group"): 0 is G53 (no offset), 1 … 6 are G54 … G59, as the zero-offset list's
/// `np_grp[i]` and a program's `V.G.NP[i]` number them.
const ZERO_OFFSETS: std::ops::RangeInclusive<usize> = 0..=6;
/// 0.1 µm per mm: zero offsets on the wire.
const TENTH_UM_PER_MM: f64 = 10_000.0;

/// A variable a handle names.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Var {
    /// `V.E.<name>`, the name upper case without `V.E.`.
    External(String),
    /// `V.G.NP[i].V`, i in [`ZERO_OFFSETS`].
    ZeroOffset(usize),
}

/// The objects of channel `ch`'s decoder class, for the object map.
pub fn objects(ch: u16) -> Vec<ObjectInfo> {
    let group = GROUP_DECODER + u32::from(ch);
    let o = |offset, name: &str, access, size| ObjectInfo {
        port: PORT,
        group,
        offset,
        name: name.into(),
        ty: AdsType::Named("V.E.* declared type (LREAL without a list); V.G.NP[i].V DINT[axes]"),
        size,
        access,
        unit: "",
        source: "ISG docs 312791435; TwinSharp ZeroOffsets.cs",
    };
    vec![
        o(
            HANDLE_BY_NAME,
            "variable handle by name (ReadWrite)",
            Access::ReadWrite,
            4,
        ),
        o(
            READ_BY_HANDLE,
            "read variable by handle (ReadWrite)",
            Access::ReadWrite,
            8,
        ),
        o(
            READ_BY_NAME,
            "read variable by name (ReadWrite)",
            Access::ReadWrite,
            8,
        ),
        o(
            WRITE_BY_HANDLE,
            "write variable by handle",
            Access::Write,
            8,
        ),
        o(WRITE_BY_NAME, "write variable by name", Access::Write, 8),
        o(
            HANDLE_BASE,
            "variable value at its handle (0x2000_0000 + n)",
            Access::ReadWrite,
            8,
        ),
    ]
}

/// The SDA task of one server: its variable handles.
pub(crate) struct Sda {
    backend: Arc<dyn CncBackend>,
    /// Handle n ↔ `names[n]`.
    names: Mutex<Vec<Var>>,
}

/// `V.E.name` (any case) → `NAME`, `V.G.NP[i].V` → zero offset i; other variables → not
/// found.
fn var_name(data: &[u8]) -> Result<Var, AdsResult> {
    let end = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    if end == 0 || end > MAX_NAME_BYTES {
        return Err(AdsResult::INVALID_SIZE);
    }
    let text = std::str::from_utf8(&data[..end])
        .map_err(|_| AdsResult::INVALID_DATA)?
        .trim();
    let upper = text.to_ascii_uppercase();
    if let Some(name) = upper.strip_prefix("V.E.").filter(|n| !n.is_empty()) {
        return Ok(Var::External(name.to_string()));
    }
    upper
        .strip_prefix("V.G.NP[")
        .and_then(|rest| rest.strip_suffix("].V"))
        .filter(|i| !i.is_empty() && i.bytes().all(|b| b.is_ascii_digit()))
        .and_then(|i| i.parse::<usize>().ok())
        .filter(|i| ZERO_OFFSETS.contains(i))
        .map(Var::ZeroOffset)
        .ok_or(AdsResult::NOT_FOUND)
}

fn value_arg(data: &[u8]) -> Result<f64, AdsResult> {
    let bytes: [u8; VALUE_BYTES] = data.try_into().map_err(|_| AdsResult::INVALID_SIZE)?;
    let v = f64::from_le_bytes(bytes);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(AdsResult::INVALID_DATA)
    }
}

/// A V.E. value in its PLC type's bytes (little-endian; a STRING(n) NUL-padded to n + 1).
fn encode(v: &ExternalValue) -> Vec<u8> {
    match v {
        ExternalValue::Str(text, max) => {
            let mut out = text.as_bytes().to_vec();
            out.resize(usize::from(*max) + 1, 0);
            out
        }
        // The store holds whole numbers in range for an integer type: the casts are exact.
        ExternalValue::Num(v, ty) => match ty {
            None | Some(VarType::Real) | Some(VarType::String(_)) => v.to_le_bytes().to_vec(),
            Some(VarType::Boolean | VarType::Uns08) => vec![*v as u8],
            Some(VarType::Sgn08) => (*v as i8).to_le_bytes().to_vec(),
            Some(VarType::Sgn16) => (*v as i16).to_le_bytes().to_vec(),
            Some(VarType::Uns16) => (*v as u16).to_le_bytes().to_vec(),
            Some(VarType::Sgn32) => (*v as i32).to_le_bytes().to_vec(),
            Some(VarType::Uns32) => (*v as u32).to_le_bytes().to_vec(),
        },
    }
}

/// The number a write of `data` to a V.E. of type `ty` carries: exactly the type's bytes.
fn decode(data: &[u8], ty: Option<VarType>) -> Result<f64, AdsResult> {
    let Some(ty) = ty.filter(|t| *t != VarType::Real) else {
        return value_arg(data);
    };
    // Each type takes exactly its bytes: any other length is the size error.
    Ok(match (ty, data) {
        (VarType::Sgn08, [b]) => f64::from(*b as i8),
        (VarType::Boolean | VarType::Uns08, [b]) => f64::from(*b),
        (VarType::Sgn16, [a, b]) => f64::from(i16::from_le_bytes([*a, *b])),
        (VarType::Uns16, [a, b]) => f64::from(u16::from_le_bytes([*a, *b])),
        (VarType::Sgn32, [a, b, c, d]) => f64::from(i32::from_le_bytes([*a, *b, *c, *d])),
        (VarType::Uns32, [a, b, c, d]) => f64::from(u32::from_le_bytes([*a, *b, *c, *d])),
        _ => return Err(AdsResult::INVALID_SIZE),
    })
}

/// The text of a write to a STRING(max): up to the first NUL, at most `max + 1` bytes.
fn string_arg(data: &[u8], max: u8) -> Result<String, AdsResult> {
    if data.len() > usize::from(max) + 1 {
        return Err(AdsResult::INVALID_SIZE);
    }
    let end = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    std::str::from_utf8(&data[..end])
        .map(str::to_string)
        .map_err(|_| AdsResult::INVALID_DATA)
}

fn u32_at(data: &[u8], at: usize) -> Result<u32, AdsResult> {
    data.get(at..at + 4)
        .and_then(|b| b.try_into().ok())
        .map(u32::from_le_bytes)
        .ok_or(AdsResult::INVALID_SIZE)
}

impl Sda {
    pub fn new(backend: Arc<dyn CncBackend>) -> Self {
        Sda {
            backend,
            names: Mutex::new(Vec::new()),
        }
    }

    fn channel(&self, group: u32) -> Result<u16, AdsResult> {
        let group = if group < LOGICAL {
            group | LOGICAL
        } else {
            group
        };
        let ch = group
            .checked_sub(GROUP_DECODER)
            .filter(|&c| (1..=u32::from(self.backend.channel_count())).contains(&c))
            .ok_or(AdsResult::INVALID_GROUP)?;
        Ok(ch as u16)
    }

    fn name_of(&self, handle: u32) -> Result<Var, AdsResult> {
        let i = handle
            .checked_sub(HANDLE_BASE)
            .ok_or(AdsResult::INVALID_OFFSET)? as usize;
        let names = self.names.lock().unwrap_or_else(|p| p.into_inner());
        names.get(i).cloned().ok_or(AdsResult::NOT_FOUND)
    }

    fn handle(&self, ch: u16, name: Var) -> Result<u32, AdsResult> {
        // Only a variable that exists gets a handle (zero offsets 1…6 always do).
        if let Var::External(n) = &name {
            self.backend.read_ve_typed(ch, n).map_err(AdsResult::from)?;
        }
        let mut names = self.names.lock().unwrap_or_else(|p| p.into_inner());
        let i = match names.iter().position(|n| *n == name) {
            Some(i) => i,
            None if names.len() < MAX_HANDLES => {
                names.push(name);
                names.len() - 1
            }
            None => return Err(NO_MEMORY),
        };
        Ok(HANDLE_BASE + i as u32)
    }

    /// Zero offsets are read only: the decoder takes its table from the parameter lists at
    /// the start and runs ahead of execution by the lookahead (docs/ads.md).
    fn store(&self, ch: u16, var: &Var, data: &[u8]) -> Result<(), AdsResult> {
        match var {
            Var::External(name) => {
                let now = match self.backend.read_ve_typed(ch, name) {
                    Ok(v) => v,
                    // Not there: without a list the first write makes it (an LREAL); with
                    // one, the name is not declared.
                    Err(DeviceError::NotFound) => {
                        return self
                            .backend
                            .write_ve(ch, name, value_arg(data)?)
                            .map_err(|_| AdsResult::NOT_FOUND)
                    }
                    Err(e) => return Err(e.into()),
                };
                match now {
                    ExternalValue::Str(_, max) => {
                        let text = string_arg(data, max)?;
                        self.backend.write_ve_str(ch, name, &text)
                    }
                    ExternalValue::Num(_, ty) => self.backend.write_ve(ch, name, decode(data, ty)?),
                }
                .map_err(AdsResult::from)
            }
            Var::ZeroOffset(_) => Err(AdsResult::ACCESS_DENIED),
        }
    }

    /// `{u32 handle, u32 ndims, u32 index × ndims}` → (handle, bytes used). ncchannel's
    /// variables are read whole: ndims must be 0.
    fn handle_head(data: &[u8]) -> Result<(u32, usize), AdsResult> {
        let handle = u32_at(data, 0)?;
        let ndims = u32_at(data, 4)?;
        if ndims != 0 {
            return Err(AdsResult::INVALID_DATA);
        }
        Ok((handle, 8))
    }

    /// ADS Read on port 552: a variable's value at its handle.
    pub fn read(&self, group: u32, offset: u32, length: u32) -> Result<Vec<u8>, AdsResult> {
        self.encoder(group, offset, length)?(&mut self.live())
    }

    /// The encoder of the variable at handle `offset` of `group`, read `length` bytes at a
    /// time: what a Read runs once and a notification evaluated in the cycle runs every due
    /// tick (`machine::watch`). The handle is resolved here, once.
    pub(crate) fn encoder(
        &self,
        group: u32,
        offset: u32,
        length: u32,
    ) -> Result<ObjectEncoder, AdsResult> {
        let ch = self.channel(group)?;
        if offset < HANDLE_BASE {
            return Err(AdsResult::INVALID_OFFSET);
        }
        let var = self.name_of(offset)?;
        Ok(Box::new(move |s: &mut dyn Source| {
            value(s, ch, &var, length)
        }))
    }

    fn live(&self) -> Live<'_> {
        Live::new(self.backend.as_ref())
    }

    /// ADS Write on port 552.
    pub fn write(&self, group: u32, offset: u32, data: &[u8]) -> Result<(), AdsResult> {
        let ch = self.channel(group)?;
        match offset {
            WRITE_BY_HANDLE => {
                let (handle, used) = Self::handle_head(data)?;
                self.store(ch, &self.name_of(handle)?, &data[used..])
            }
            WRITE_BY_NAME => {
                let end = data
                    .iter()
                    .position(|&b| b == 0)
                    .ok_or(AdsResult::INVALID_DATA)?;
                let var = var_name(&data[..end])?;
                self.store(ch, &var, &data[end + 1..])
            }
            o if o >= HANDLE_BASE => self.store(ch, &self.name_of(o)?, data),
            HANDLE_BY_NAME | READ_BY_HANDLE | READ_BY_NAME => Err(AdsResult::ACCESS_DENIED),
            _ => Err(AdsResult::INVALID_OFFSET),
        }
    }

    /// ADS ReadWrite on port 552.
    pub fn read_write(
        &self,
        group: u32,
        offset: u32,
        read_length: u32,
        data: &[u8],
    ) -> Result<Vec<u8>, AdsResult> {
        let ch = self.channel(group)?;
        match offset {
            HANDLE_BY_NAME => {
                if read_length < 4 {
                    return Err(AdsResult::INVALID_SIZE);
                }
                let h = self.handle(ch, var_name(data)?)?;
                Ok(h.to_le_bytes().to_vec())
            }
            READ_BY_HANDLE => {
                let (handle, _) = Self::handle_head(data)?;
                value(&mut self.live(), ch, &self.name_of(handle)?, read_length)
            }
            READ_BY_NAME => value(&mut self.live(), ch, &var_name(data)?, read_length),
            WRITE_BY_HANDLE | WRITE_BY_NAME => Err(AdsResult::ACCESS_DENIED),
            _ => Err(AdsResult::INVALID_OFFSET),
        }
    }
}

/// Variable `var` of channel `ch` read from `source`, at most `read_length` bytes asked for.
fn value(
    source: &mut dyn Source,
    ch: u16,
    var: &Var,
    read_length: u32,
) -> Result<Vec<u8>, AdsResult> {
    let bytes = match var {
        Var::External(name) => encode(&source.read_ve_typed(ch, name).map_err(AdsResult::from)?),
        Var::ZeroOffset(i) => zero_offset(source.status(ch).map_err(AdsResult::from)?, *i)?,
    };
    if (read_length as usize) < bytes.len() {
        return Err(AdsResult::INVALID_SIZE);
    }
    Ok(bytes)
}

/// `V.G.NP[i].V`: one DINT (0.1 µm, saturating) per configured axis of the channel, in
/// the channel's axis order.
fn zero_offset(v: &Status, i: usize) -> Result<Vec<u8>, AdsResult> {
    let table = match i.checked_sub(1) {
        None => &[0.0; crate::vocab::axis::MAX_AXES],
        Some(row) => v.zero_offsets.get(row).ok_or(AdsResult::NOT_FOUND)?,
    };
    Ok(v.positions
        .iter()
        .filter_map(|(letter, _)| u8::try_from(*letter).ok().and_then(slot_of))
        .flat_map(|slot| {
            let tenth_um = (table[slot] * TENTH_UM_PER_MM).round();
            (tenth_um.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32).to_le_bytes()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ads::testing;
    use std::sync::Arc;

    #[test]
    fn handle_then_plain_read_and_write_as_twinsharp_does() {
        let t = testing::channels(1);
        t.backend.write_ve(1, "DEPTH", 1.5).unwrap();
        let sda = Sda::new(Arc::clone(&t.backend));
        let h = sda
            .read_write(0x122301, HANDLE_BY_NAME, 4, b"V.E.depth")
            .unwrap();
        let h = u32::from_le_bytes([h[0], h[1], h[2], h[3]]);
        assert_eq!(h, 0x2000_0000);
        assert_eq!(sda.read(0x122301, h, 1024).unwrap(), 1.5f64.to_le_bytes());
        sda.write(0x122301, h, &(-2.0f64).to_le_bytes()).unwrap();
        let by_name = sda
            .read_write(0x122301, READ_BY_NAME, 8, b"V.E.DEPTH\0")
            .unwrap();
        assert_eq!(by_name, (-2.0f64).to_le_bytes());
        let mut req = h.to_le_bytes().to_vec();
        req.extend_from_slice(&0u32.to_le_bytes());
        assert_eq!(
            sda.read_write(0x22301, READ_BY_HANDLE, 8, &req).unwrap(),
            by_name
        );
        assert_eq!(
            sda.read_write(0x122301, HANDLE_BY_NAME, 4, b"V.G.NP[7].V"),
            Err(AdsResult::NOT_FOUND)
        );
        assert_eq!(
            sda.read_write(0x122301, HANDLE_BY_NAME, 4, b"V.G.NP[1].X"),
            Err(AdsResult::NOT_FOUND)
        );
        assert_eq!(
            sda.read_write(0x122301, HANDLE_BY_NAME, 4, b"V.E.missing"),
            Err(AdsResult::NOT_FOUND)
        );
    }
}
