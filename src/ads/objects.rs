//! The CNC object table on AMS port 553: which (index group, index offset) means which channel
//! request, with what size, and which ADS result each outcome gets.
//!
//! Index group: `0x20100 + ch` (ISG docs: `0x000201<ii>`, `<ii>` = channel) or the newer
//! `0x120100 + ch`, with **channel 1 → 0x20101** (there is no channel 0). Offsets from the ISG
//! SDK (REFERENCE §8) plus ncchannel extensions in 0x8000..; see the README's object table.

use super::backend::{CncBackend, DeviceError};
use super::result::AdsResult;

/// AMS port of the CNC's COM task; every other port is "not found" (AMS error 6).
pub const PORT_CNC_COM: u16 = 553;

/// Channel index group base (ISG SDK); the channel number is added.
pub const GROUP_CHANNEL: u32 = 0x20100;
/// Channel index group base of newer documentation; same objects.
pub const GROUP_CHANNEL_NEW: u32 = 0x120100;

/// Index offsets inside a channel's index group.
pub mod offset {
    /// `mc_program_stream_w`: write one packet of whole CR LF lines (≤ 992 bytes).
    pub const STREAM: u32 = 0x90;
    /// Read: active mode and state, two i32 (8 bytes).
    pub const MODE_STATE: u32 = 0x103;
    /// Write: command to mode, i32 (2 or 4 bytes accepted).
    pub const COMMAND_MODE: u32 = 0x104;
    /// Write: command to state, i32 (2 or 4 bytes accepted).
    pub const COMMAND_STATE: u32 = 0x105;
    /// Write: command parameter = program name, text, NUL-terminated or not.
    pub const COMMAND_PROGRAM: u32 = 0x108;
    /// Write (any 0..=4 bytes): automatic stop = feed hold.
    pub const HOLD: u32 = 0x136;
    /// Write (any 0..=4 bytes): resume after hold.
    pub const RESUME: u32 = 0x137;
    /// Write (any 0..=4 bytes): automatic reset.
    pub const RESET: u32 = 0x13C;
    /// Read: last error message, text + NUL, cut to the requested length.
    pub const ERROR_MESSAGE: u32 = 0x26;
    /// Extension. Read: stream buffer fill, u32 used bytes + u32 free bytes (8 bytes).
    pub const STREAM_FILL: u32 = 0x8001;
    /// Extension. Read: block counter, u64 (8 bytes).
    pub const BLOCK_COUNTER: u32 = 0x8002;
    /// Extension. Read: actual axis positions, one f64 (mm) per axis.
    pub const POSITIONS: u32 = 0x8003;
    /// Extension. Write: feed override in percent 0..=200, f64 (8 bytes) or u32 (4 bytes).
    pub const FEED_OVERRIDE: u32 = 0x8004;
    /// Extension. V.E. variables. ReadWrite: write the name, read f64 (8 bytes).
    /// Write: text `name=value`. Names with or without the `V.E.` prefix.
    pub const VE_VARIABLE: u32 = 0x8005;
}

/// Longest program name or V.E. text accepted (bytes); longer is 0x705.
pub const MAX_NAME_BYTES: usize = 255;

/// Find the channel an index group addresses, or 0x702.
pub fn channel_of(group: u32, backend: &dyn CncBackend) -> Result<u16, AdsResult> {
    let ch = if (GROUP_CHANNEL_NEW..GROUP_CHANNEL_NEW + 0x100).contains(&group) {
        group - GROUP_CHANNEL_NEW
    } else if (GROUP_CHANNEL..GROUP_CHANNEL + 0x100).contains(&group) {
        group - GROUP_CHANNEL
    } else {
        return Err(AdsResult::INVALID_GROUP);
    };
    if ch == 0 || ch > u32::from(backend.channel_count()) {
        return Err(AdsResult::INVALID_GROUP);
    }
    Ok(ch as u16)
}

fn known_offset(offset: u32) -> bool {
    use offset::*;
    matches!(
        offset,
        STREAM
            | MODE_STATE
            | COMMAND_MODE
            | COMMAND_STATE
            | COMMAND_PROGRAM
            | HOLD
            | RESUME
            | RESET
            | ERROR_MESSAGE
            | STREAM_FILL
            | BLOCK_COUNTER
            | POSITIONS
            | FEED_OVERRIDE
            | VE_VARIABLE
    )
}

fn dev(e: DeviceError) -> AdsResult {
    e.result()
}

/// The bytes of a readable object, whole. `Err` for unknown or write-only objects.
fn object_bytes(backend: &dyn CncBackend, ch: u16, offset: u32) -> Result<Vec<u8>, AdsResult> {
    match offset {
        offset::MODE_STATE => {
            let (m, s) = backend.mode_state(ch).map_err(dev)?;
            Ok([m.to_le_bytes(), s.to_le_bytes()].concat())
        }
        offset::ERROR_MESSAGE => {
            let mut text = backend.last_error(ch).map_err(dev)?.into_bytes();
            text.push(0);
            Ok(text)
        }
        offset::STREAM_FILL => {
            let f = backend.stream_fill(ch).map_err(dev)?;
            Ok([f.used_bytes.to_le_bytes(), f.free_bytes.to_le_bytes()].concat())
        }
        offset::BLOCK_COUNTER => Ok(backend
            .block_counter(ch)
            .map_err(dev)?
            .to_le_bytes()
            .to_vec()),
        offset::POSITIONS => Ok(backend
            .positions(ch)
            .map_err(dev)?
            .iter()
            .flat_map(|p| p.to_le_bytes())
            .collect()),
        o if known_offset(o) => Err(AdsResult::ACCESS_DENIED),
        _ => Err(AdsResult::INVALID_OFFSET),
    }
}

/// ADS Read of `length` bytes. Fixed-size objects need at least their size (else 0x705) and
/// answer with exactly their size; text is cut to `length`. Never more than `length` bytes.
pub fn read(
    backend: &dyn CncBackend,
    group: u32,
    offset: u32,
    length: u32,
) -> Result<Vec<u8>, AdsResult> {
    let ch = channel_of(group, backend)?;
    let mut bytes = object_bytes(backend, ch, offset)?;
    let length = length as usize;
    if offset == offset::ERROR_MESSAGE {
        bytes.truncate(length);
        return Ok(bytes);
    }
    if bytes.len() > length {
        return Err(AdsResult::INVALID_SIZE);
    }
    Ok(bytes)
}

/// A text argument: up to the first NUL, at most MAX_NAME_BYTES, UTF-8.
fn text_arg(data: &[u8]) -> Result<&str, AdsResult> {
    let end = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    let text = &data[..end];
    if text.is_empty() || text.len() > MAX_NAME_BYTES {
        return Err(AdsResult::INVALID_SIZE);
    }
    std::str::from_utf8(text)
        .map(str::trim)
        .map_err(|_| AdsResult::INVALID_DATA)
}

/// An integer command argument: i16 or i32 little-endian.
fn int_arg(data: &[u8]) -> Result<i32, AdsResult> {
    match *data {
        [a, b] => Ok(i32::from(i16::from_le_bytes([a, b]))),
        [a, b, c, d] => Ok(i32::from_le_bytes([a, b, c, d])),
        _ => Err(AdsResult::INVALID_SIZE),
    }
}

/// `V.E.name`, `v.e.name` or `name` → `name`.
fn ve_name(text: &str) -> &str {
    match text.get(..4) {
        Some(p) if p.eq_ignore_ascii_case("V.E.") => &text[4..],
        _ => text,
    }
}

fn unit(r: Result<(), DeviceError>) -> Result<(), AdsResult> {
    r.map_err(dev)
}

/// ADS Write.
pub fn write(
    backend: &dyn CncBackend,
    group: u32,
    offset: u32,
    data: &[u8],
) -> Result<(), AdsResult> {
    let ch = channel_of(group, backend)?;
    match offset {
        offset::STREAM => {
            let r = backend.stream_write(ch, data).result();
            if r.is_ok() {
                Ok(())
            } else {
                Err(r)
            }
        }
        offset::COMMAND_MODE => unit(backend.command_mode(ch, int_arg(data)?)),
        offset::COMMAND_STATE => unit(backend.command_state(ch, int_arg(data)?)),
        offset::COMMAND_PROGRAM => unit(backend.command_program(ch, text_arg(data)?)),
        offset::HOLD | offset::RESUME | offset::RESET => {
            if data.len() > 4 {
                return Err(AdsResult::INVALID_SIZE);
            }
            unit(match offset {
                offset::HOLD => backend.hold(ch),
                offset::RESUME => backend.resume(ch),
                _ => backend.reset(ch),
            })
        }
        offset::FEED_OVERRIDE => {
            let percent = match *data {
                [a, b, c, d] => f64::from(u32::from_le_bytes([a, b, c, d])),
                [a, b, c, d, e, f, g, h] => f64::from_le_bytes([a, b, c, d, e, f, g, h]),
                _ => return Err(AdsResult::INVALID_SIZE),
            };
            if !(0.0..=200.0).contains(&percent) {
                return Err(AdsResult::INVALID_DATA);
            }
            unit(backend.set_override(ch, percent))
        }
        offset::VE_VARIABLE => {
            let text = text_arg(data)?;
            let (name, value) = text.split_once('=').ok_or(AdsResult::INVALID_DATA)?;
            let value: f64 = value.trim().parse().map_err(|_| AdsResult::INVALID_DATA)?;
            let name = ve_name(name.trim());
            if name.is_empty() || !value.is_finite() {
                return Err(AdsResult::INVALID_DATA);
            }
            unit(backend.write_ve(ch, name, value))
        }
        o if known_offset(o) => Err(AdsResult::ACCESS_DENIED),
        _ => Err(AdsResult::INVALID_OFFSET),
    }
}

/// ADS ReadWrite: only V.E. variables (write the name, read the f64); other objects 0x704.
pub fn read_write(
    backend: &dyn CncBackend,
    group: u32,
    offset: u32,
    read_length: u32,
    data: &[u8],
) -> Result<Vec<u8>, AdsResult> {
    let ch = channel_of(group, backend)?;
    match offset {
        offset::VE_VARIABLE => {
            if read_length < 8 {
                return Err(AdsResult::INVALID_SIZE);
            }
            let name = ve_name(text_arg(data)?);
            Ok(backend
                .read_ve(ch, name)
                .map_err(dev)?
                .to_le_bytes()
                .to_vec())
        }
        o if known_offset(o) => Err(AdsResult::ACCESS_DENIED),
        _ => Err(AdsResult::INVALID_OFFSET),
    }
}
