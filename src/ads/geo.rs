//! The GEO task (AMS port 551): the interpolator and HLD class instances of each channel and
//! the class address query.
//!
//! Class groups (Beckhoff infosys `tf5200_ads_access_to_cnc/312767243.html`, `…/312768779.html`):
//! interpolator `0x121300 + ch`, HLD `0x123300 + ch`; the address query is a ReadWrite at the
//! class group plus 0x600 with `{i32 channel, i32 axis}` → `{u32 group, u32 offset}`, `(0, 0)`
//! when the instance does not exist. Elements, types and units from the ISG object dump
//! (`SamWieHTWG/web-api` `examples/example1-hello-cnc/cnc_objects.csv`, groups `0x21301`,
//! `0x23301`); TwinSharp `Interpolator.cs` reads exactly these interpolator offsets and
//! `OperationModeManager.cs` publishes HLD 0x1F (state) and 0x20 (mode).
//!
//! The HLD's mode-and-state unit (0x21–0x2F) mirrors the PLC's HLI unit
//! (`gpCh[i]^.channel_mc_control.mode_and_state`, see [`super::hli`]): one store, two views.
//! The technology elements 0x02–0x07 (`used_units_*_sync_r`, the first standard and late
//! unit's please/done), 0x3F–0x138 (every unit's elements) and 0x0E (`head.plc_present_w`)
//! read the channel's technology units
//! (`Status.techno`, src/channel/techno.rs), as the HLI symbols do; they are read-only here.

use std::sync::Arc;

use super::backend::{CncBackend, Live, ObjectEncoder, Source, Status};
use super::description::{Access, AdsType, ObjectInfo};
use super::hli::{Hli, Unit};
use super::result::AdsResult;
use crate::channel::techno::{UnitSet, LATE_SYNC_UNITS, STD_SYNC_UNITS};

pub const PORT: u16 = 551;
/// Position controller, platform instance (ISG sample client `cnc_demo_samples.c` waits
/// ticks on its tick counter).
pub(crate) const GROUP_POS_CTRL: u32 = 0x120300;
/// Interpolator instance of channel ch: `GROUP_IPO + ch`.
pub(crate) const GROUP_IPO: u32 = 0x121300;
/// HLD instance of channel ch: `GROUP_HLD + ch`.
pub(crate) const GROUP_HLD: u32 = 0x123300;
/// Attribute add-on of the address query.
const ADDRESS_QUERY: u32 = 0x600;
/// Logical-addressing bit of index groups (infosys "logical vs index-based", 312762635).
const LOGICAL: u32 = 0x100000;

const SRC: &str = "ISG object dump; TwinSharp";
const SRC_DUMP: &str = "ISG object dump";

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Class {
    PosCtrl,
    Ipo,
    Hld,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Field {
    Elements,
    CycleTime,
    PlatformAxes,
    TickCounter,
    AxisCount,
    SlopeBufLevel,
    IpoBufLevel,
    PathVelocity,
    ProgrammedVelocity,
    BlockNumber,
    BlockCount,
    InputBlockCount,
    OverrideFactor,
    /// The active D's tool radius.
    ToolRadius,
    PlcPresent,
    /// `used_units_std_sync_r` / `used_units_late_sync_r`.
    UsedUnits(UnitSet),
    /// `techno_std_sync[0]` / `techno_late_sync[0]`: `please` or `done`.
    TechnoFlag(UnitSet, bool),
    /// One element of one unit, `techno.std_sync[k]` / `techno.late_sync[k]` (0x3F–0x138).
    TechnoElement(UnitSet, usize, TechnoPart),
    OverrideEnable,
    OverrideCommand,
    OverrideRequest,
    OverrideState,
    State,
    Mode,
    Unit(Unit, u32),
}

/// The elements of a unit in the HLD mirror, in the dump's order: `type`, `please`, `done`,
/// `m_h.nr`, `m_h.time`, `m_h.block_nr`, `m_h.prg_line_nr`, `m_h.add_value`, and for a late
/// unit `nr_late_sync`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum TechnoPart {
    Type,
    Please,
    Done,
    Nr,
    Time,
    BlockNr,
    PrgLine,
    AddValue,
    NrLateSync,
}

const TECHNO_PARTS: [(TechnoPart, &str, AdsType, u32); 9] = [
    (TechnoPart::Type, "type", AdsType::Word, 2),
    (TechnoPart::Please, "please", AdsType::Bool, 1),
    (TechnoPart::Done, "done", AdsType::Bool, 1),
    (TechnoPart::Nr, "m_h.nr", AdsType::Dword, 4),
    (TechnoPart::Time, "m_h.time", AdsType::Dint, 4),
    (TechnoPart::BlockNr, "m_h.block_nr", AdsType::Dword, 4),
    (TechnoPart::PrgLine, "m_h.prg_line_nr", AdsType::Dword, 4),
    (TechnoPart::AddValue, "m_h.add_value", AdsType::Dint, 4),
    (TechnoPart::NrLateSync, "nr_late_sync", AdsType::Word, 2),
];

/// The first unit element's offset in the HLD mirror (the ISG object dump: 0x3F–0x138 are
/// `techno.std_sync[0..19]`, 8 elements each, then `techno.late_sync[0..9]`, 9 each).
const TECHNO_FIRST: u32 = 0x3F;

/// The unit elements, built once (their names are made from the unit index).
fn techno_defs() -> &'static [Def] {
    static DEFS: std::sync::OnceLock<Vec<Def>> = std::sync::OnceLock::new();
    DEFS.get_or_init(|| {
        let mut v = Vec::new();
        let mut element = TECHNO_FIRST;
        let sets = [
            (UnitSet::Std, "techno.std_sync", STD_SYNC_UNITS, 8),
            (UnitSet::Late, "techno.late_sync", LATE_SYNC_UNITS, 9),
        ];
        for (set, prefix, units, parts) in sets {
            for k in 0..units {
                for &(part, name, ty, size) in &TECHNO_PARTS[..parts] {
                    v.push(Def {
                        class: Class::Hld,
                        element,
                        name: std::borrow::Cow::Owned(format!("{prefix}[{k}]::{name}")),
                        ty,
                        size,
                        unit: "",
                        source: SRC_DUMP,
                        field: Field::TechnoElement(set, k, part),
                    });
                    element += 1;
                }
            }
        }
        v
    })
}

/// Every entry: the table and the unit elements.
fn all_defs() -> impl Iterator<Item = &'static Def> {
    TABLE.iter().chain(techno_defs())
}

struct Def {
    class: Class,
    element: u32,
    name: std::borrow::Cow<'static, str>,
    ty: AdsType,
    size: u32,
    unit: &'static str,
    source: &'static str,
    field: Field,
}

#[allow(clippy::too_many_arguments)]
const fn d(
    class: Class,
    element: u32,
    name: &'static str,
    ty: AdsType,
    size: u32,
    unit: &'static str,
    source: &'static str,
    field: Field,
) -> Def {
    Def {
        class,
        element,
        name: std::borrow::Cow::Borrowed(name),
        ty,
        size,
        unit,
        source,
        field,
    }
}

use AdsType::*;
use Class::{Hld, Ipo, PosCtrl};
use Field as F;

#[rustfmt::skip]
static TABLE: &[Def] = &[
    d(PosCtrl, 0x00, "POS-CTRL: elements", Dword, 4, "element types served", SRC_DUMP, F::Elements),
    d(PosCtrl, 0x01, "cycle time", Lreal, 8, "s", SRC_DUMP, F::CycleTime),
    d(PosCtrl, 0x02, "number of axes", Word, 2, "", SRC_DUMP, F::PlatformAxes),
    d(PosCtrl, 0x07, "tick counter", Dword, 4, "CNC ticks", SRC_DUMP, F::TickCounter),
    d(Ipo, 0x00, "IPO: elements", Dword, 4, "element types served", SRC, F::Elements),
    d(Ipo, 0x01, "number of axes", Word, 2, "", SRC, F::AxisCount),
    d(Ipo, 0x04, "slope_buf_level", Dword, 4, "blocks waiting for the lookahead", SRC, F::SlopeBufLevel),
    d(Ipo, 0x05, "ipo_buf_level", Dword, 4, "blocks", SRC, F::IpoBufLevel),
    d(Ipo, 0x15, "Actual velocity on path", Lreal, 8, "µm/s", SRC, F::PathVelocity),
    d(Ipo, 0x16, "Programmed velocity on path", Lreal, 8, "µm/s", SRC, F::ProgrammedVelocity),
    d(Ipo, 0x21, "actual_block_nr", Dint, 4, "N number", SRC, F::BlockNumber),
    d(Ipo, 0x2C, "Actual tool radius", Lreal, 8, "0.1 µm, the active D's", SRC_DUMP, F::ToolRadius),
    d(Ipo, 0x2E, "actual_block_count", Dint, 4, "block counter", SRC_DUMP, F::BlockCount),
    d(Ipo, 0x2F, "latest_input_block_clount", Dint, 4, "block counter", SRC_DUMP, F::InputBlockCount),
    d(Ipo, 0x70, "override feed factor", Lreal, 8, "1 = 100 %", SRC_DUMP, F::OverrideFactor),
    d(Hld, 0x00, "HLD : elements", Dword, 4, "element types served", SRC_DUMP, F::Elements),
    d(Hld, 0x02, "used_units_late_sync_r", Word, 2, "units", SRC_DUMP, F::UsedUnits(UnitSet::Late)),
    d(Hld, 0x03, "used_units_std_sync_r", Word, 2, "units", SRC_DUMP, F::UsedUnits(UnitSet::Std)),
    d(Hld, 0x04, "techno_std_sync[0]::please", Bool, 1, "", SRC_DUMP, F::TechnoFlag(UnitSet::Std, true)),
    d(Hld, 0x05, "techno_std_sync[0]::done", Bool, 1, "", SRC_DUMP, F::TechnoFlag(UnitSet::Std, false)),
    d(Hld, 0x06, "techno_late_sync[0]::please", Bool, 1, "", SRC_DUMP, F::TechnoFlag(UnitSet::Late, true)),
    d(Hld, 0x07, "techno_late_sync[0]::done", Bool, 1, "", SRC_DUMP, F::TechnoFlag(UnitSet::Late, false)),
    d(Hld, 0x0E, "head.plc_present_w", Bool, 1, "", SRC_DUMP, F::PlcPresent),
    d(Hld, 0x1B, "override_feedrate.enable_w", Bool, 1, "", SRC_DUMP, F::OverrideEnable),
    d(Hld, 0x1C, "override_feedrate.command_w", Word, 2, "0.1 %", SRC_DUMP, F::OverrideCommand),
    d(Hld, 0x1D, "override_feedrate.request_r", Word, 2, "0.1 %", SRC_DUMP, F::OverrideRequest),
    d(Hld, 0x1E, "override_feedrate.state_r", Word, 2, "0.1 %", SRC_DUMP, F::OverrideState),
    d(Hld, 0x1F, "mcm_mode_state", Dword, 4, "state", SRC, F::State),
    d(Hld, 0x20, "active_mcm_mode", Dword, 4, "mode", SRC, F::Mode),
    d(Hld, 0x21, "mode_and_state.enable_w", Bool, 1, "", SRC_DUMP, F::Unit(Unit::Enable, 0)),
    d(Hld, 0x22, "mode_and_state.request_semaphor_rw", Bool, 1, "", SRC_DUMP, F::Unit(Unit::RequestSemaphore, 0)),
    d(Hld, 0x23, "mode_and_state.command_semaphor_rw", Bool, 1, "", SRC_DUMP, F::Unit(Unit::CommandSemaphore, 0)),
    d(Hld, 0x24, "mode_and_state.request_r.from_mode", Dword, 4, "", SRC_DUMP, F::Unit(Unit::Request, 0)),
    d(Hld, 0x25, "mode_and_state.request_r.from_state", Dword, 4, "", SRC_DUMP, F::Unit(Unit::Request, 4)),
    d(Hld, 0x26, "mode_and_state.request_r.to_mode", Dword, 4, "", SRC_DUMP, F::Unit(Unit::Request, 8)),
    d(Hld, 0x27, "mode_and_state.request_r.to_state", Dword, 4, "", SRC_DUMP, F::Unit(Unit::Request, 12)),
    d(Hld, 0x28, "mode_and_state.request_r.channel_number", Dword, 4, "", SRC_DUMP, F::Unit(Unit::Request, 16)),
    d(Hld, 0x29, "mode_and_state.request_r.parameter", String, 300, "", SRC_DUMP, F::Unit(Unit::Request, 24)),
    d(Hld, 0x2A, "mode_and_state.command_w.from_mode", Dword, 4, "", SRC_DUMP, F::Unit(Unit::Command, 0)),
    d(Hld, 0x2B, "mode_and_state.command_w.from_state", Dword, 4, "", SRC_DUMP, F::Unit(Unit::Command, 4)),
    d(Hld, 0x2C, "mode_and_state.command_w.to_mode", Dword, 4, "", SRC_DUMP, F::Unit(Unit::Command, 8)),
    d(Hld, 0x2D, "mode_and_state.command_w.to_state", Dword, 4, "", SRC_DUMP, F::Unit(Unit::Command, 12)),
    d(Hld, 0x2E, "mode_and_state.command_w.channel_number", Dword, 4, "", SRC_DUMP, F::Unit(Unit::Command, 16)),
    d(Hld, 0x2F, "mode_and_state.command_w.parameter", String, 300, "", SRC_DUMP, F::Unit(Unit::Command, 24)),
];

fn class_group(c: Class) -> u32 {
    match c {
        Class::PosCtrl => GROUP_POS_CTRL,
        Class::Ipo => GROUP_IPO,
        Class::Hld => GROUP_HLD,
    }
}

/// Objects of channel `ch`'s interpolator and HLD, for the object map.
pub fn objects(ch: u16) -> Vec<ObjectInfo> {
    let mut defs: Vec<&Def> = all_defs().collect();
    defs.sort_by_key(|d| (d.class as u8, d.element));
    defs.into_iter()
        .map(|d| ObjectInfo {
            port: PORT,
            group: class_group(d.class)
                + if d.class == Class::PosCtrl {
                    0
                } else {
                    u32::from(ch)
                },
            offset: d.element,
            name: d.name.to_string(),
            ty: d.ty,
            size: d.size,
            access: if writable(d.field) {
                Access::ReadWrite
            } else {
                Access::Read
            },
            unit: d.unit,
            source: d.source,
        })
        .collect()
}

/// The HLD elements an HMI writes: the request side of the mode-and-state unit
/// (`request_semaphor_rw`, `request_r.*`), writable in the kernel's object dump, where the HMI
/// posts a mode or state request for the PLC to read (ISG "MC_CONTROL_UNIT", infosys
/// 174725259). Everything else in this task is written by the CNC or the PLC only.
fn writable(field: Field) -> bool {
    matches!(
        field,
        Field::Unit(Unit::Request | Unit::RequestSemaphore, _)
    )
}

/// Find channel `ch`'s table entry of a logical group, or the error a Read or Write gets.
fn locate(channels: u16, group: u32, offset: u32) -> Result<(u16, &'static Def), AdsResult> {
    let group = logical(group);
    let (class, ch) = if group == GROUP_POS_CTRL {
        (Class::PosCtrl, 1)
    } else if (GROUP_IPO + 1..GROUP_IPO + 0x100).contains(&group) {
        (Class::Ipo, group - GROUP_IPO)
    } else if (GROUP_HLD + 1..GROUP_HLD + 0x100).contains(&group) {
        (Class::Hld, group - GROUP_HLD)
    } else if group == GROUP_IPO + ADDRESS_QUERY || group == GROUP_HLD + ADDRESS_QUERY {
        return Err(AdsResult::ACCESS_DENIED);
    } else {
        return Err(AdsResult::INVALID_GROUP);
    };
    if ch > u32::from(channels) {
        return Err(AdsResult::INVALID_GROUP);
    }
    let def = all_defs()
        .find(|d| d.class == class && d.element == offset)
        .ok_or(AdsResult::INVALID_OFFSET)?;
    Ok((ch as u16, def))
}

/// ADS Write on port 551: the HMI's side of the HLD mode-and-state unit, written into the
/// same HLI image the PLC reads on port 851; any other element is 0x704, as the kernel's
/// object dump marks it read-only.
pub fn write(
    backend: &dyn CncBackend,
    hli: &Hli,
    group: u32,
    offset: u32,
    data: &[u8],
) -> Result<(), AdsResult> {
    let (ch, def) = locate(backend.channel_count(), group, offset)?;
    match def.field {
        Field::Unit(unit, at) if writable(def.field) => {
            if data.is_empty() || data.len() > def.size as usize {
                return Err(AdsResult::INVALID_SIZE);
            }
            hli.write_unit_bytes(ch, unit, at as usize, data)
        }
        _ => Err(AdsResult::ACCESS_DENIED),
    }
}

fn logical(group: u32) -> u32 {
    if group < LOGICAL {
        group | LOGICAL
    } else {
        group
    }
}

fn fixed(bytes: Vec<u8>, length: u32) -> Result<Vec<u8>, AdsResult> {
    if (length as usize) < bytes.len() {
        return Err(AdsResult::INVALID_SIZE);
    }
    Ok(bytes)
}

/// ADS Read on port 551.
pub fn read(
    backend: &dyn CncBackend,
    hli: &Hli,
    group: u32,
    offset: u32,
    length: u32,
) -> Result<Vec<u8>, AdsResult> {
    encoder(backend.channel_count(), hli, group, offset, length)?(&mut Live::new(backend))
}

/// The encoder of element `(group, offset)`, read `length` bytes at a time: what [`read`]
/// runs once and a notification evaluated in the cycle runs every due tick
/// (`machine::watch`). The HLD's mode-and-state elements read the HLI image.
pub(crate) fn encoder(
    channels: u16,
    hli: &Hli,
    group: u32,
    offset: u32,
    length: u32,
) -> Result<ObjectEncoder, AdsResult> {
    let (ch, def) = locate(channels, group, offset)?;
    let class = def.class;
    if let Field::Unit(unit, at) = def.field {
        let img = Arc::clone(hli.image()?);
        let (at, size) = (at as usize, def.size as usize);
        return Ok(Box::new(move |_: &mut dyn Source| {
            fixed(img.unit_bytes(ch, unit, at, size)?, length)
        }));
    }
    if def.field == Field::PlatformAxes {
        return Ok(Box::new(move |s: &mut dyn Source| {
            let mut n = 0usize;
            for c in 1..=s.channel_count() {
                n += s.status(c).map_err(AdsResult::from)?.positions.len();
            }
            fixed((n as u16).to_le_bytes().to_vec(), length)
        }));
    }
    Ok(Box::new(move |s: &mut dyn Source| {
        let v = s.status(ch).map_err(AdsResult::from)?;
        fixed(value(v, class, def.field)?, length)
    }))
}

fn value(v: &Status, class: Class, field: Field) -> Result<Vec<u8>, AdsResult> {
    let feed_um_s = v.modal.feed_mm_per_min * 1000.0 / 60.0;
    let active = v.active_block.as_ref();
    let tenths = (v.override_pct * 10.0).round().clamp(0.0, 2000.0) as u16;
    Ok(match field {
        Field::Elements => {
            let n = all_defs().filter(|d| d.class == class).count() as u32 - 1;
            n.to_le_bytes().to_vec()
        }
        Field::AxisCount => (v.positions.len() as u16).to_le_bytes().to_vec(),
        Field::CycleTime => v.period.as_secs_f64().to_le_bytes().to_vec(),
        Field::TickCounter => (v.tick as u32).to_le_bytes().to_vec(),
        Field::SlopeBufLevel => (v.queued_blocks as u32).to_le_bytes().to_vec(),
        Field::IpoBufLevel => (v.ipo_blocks as u32).to_le_bytes().to_vec(),
        Field::PathVelocity => (v.velocity_mm_per_s * 1000.0).to_le_bytes().to_vec(),
        Field::ProgrammedVelocity => feed_um_s.to_le_bytes().to_vec(),
        Field::BlockNumber => active
            .and_then(|a| a.n)
            .map_or(0, |n| i32::try_from(n).unwrap_or(i32::MAX))
            .to_le_bytes()
            .to_vec(),
        Field::BlockCount => active
            .map_or(0, |a| i32::try_from(a.counter).unwrap_or(i32::MAX))
            .to_le_bytes()
            .to_vec(),
        Field::InputBlockCount => i32::try_from(v.block_counter)
            .unwrap_or(i32::MAX)
            .to_le_bytes()
            .to_vec(),
        Field::OverrideFactor => (v.override_pct / 100.0).to_le_bytes().to_vec(),
        Field::ToolRadius => (v.active_tool.1 * 10_000.0).to_le_bytes().to_vec(),
        // ncchannel has no PLC override unit: the HMI's override request is taken directly.
        Field::OverrideEnable => vec![0],
        Field::OverrideCommand | Field::OverrideRequest | Field::OverrideState => {
            tenths.to_le_bytes().to_vec()
        }
        Field::State => (v.state as u32).to_le_bytes().to_vec(),
        Field::Mode => (v.mode as u32).to_le_bytes().to_vec(),
        Field::PlcPresent => vec![u8::from(v.techno.plc_present)],
        Field::UsedUnits(set) => match set {
            UnitSet::Std => v.techno.used_std,
            UnitSet::Late => v.techno.used_late,
        }
        .to_le_bytes()
        .to_vec(),
        Field::TechnoFlag(set, please) => {
            let units = match set {
                UnitSet::Std => &v.techno.std,
                UnitSet::Late => &v.techno.late,
            };
            vec![units
                .first()
                .map_or(0, |u| u8::from(if please { u.please } else { u.done }))]
        }
        Field::TechnoElement(set, k, part) => techno_element(v, set, k, part),
        Field::Unit(..) | Field::PlatformAxes => return Err(AdsResult::ACCESS_DENIED),
    })
}

/// ADS ReadWrite on port 551: the address queries of the interpolator and HLD classes.
pub fn read_write(
    backend: &dyn CncBackend,
    group: u32,
    offset: u32,
    read_length: u32,
    data: &[u8],
) -> Result<Vec<u8>, AdsResult> {
    let group = logical(group);
    let base = match group.checked_sub(ADDRESS_QUERY) {
        Some(g) if g == GROUP_IPO || g == GROUP_HLD => g,
        _ if (GROUP_IPO..GROUP_IPO + 0x100).contains(&group)
            || (GROUP_HLD..GROUP_HLD + 0x100).contains(&group) =>
        {
            return Err(AdsResult::ACCESS_DENIED)
        }
        _ => return Err(AdsResult::INVALID_GROUP),
    };
    if offset != 0 {
        return Err(AdsResult::INVALID_OFFSET);
    }
    if read_length < 8 {
        return Err(AdsResult::INVALID_SIZE);
    }
    let [a, b, c, e, f, g, h, i] = *data else {
        return Err(AdsResult::INVALID_SIZE);
    };
    let ch = i32::from_le_bytes([a, b, c, e]);
    let axis = i32::from_le_bytes([f, g, h, i]);
    let exists = axis == 0 && ch >= 1 && ch <= i32::from(backend.channel_count());
    let (group, offset) = if exists {
        (base + ch as u32, 0u32)
    } else {
        (0, 0)
    };
    Ok([group.to_le_bytes(), offset.to_le_bytes()].concat())
}

/// One element of unit `k` (a unit that never held a function reads zero).
fn techno_element(v: &Status, set: UnitSet, k: usize, part: TechnoPart) -> Vec<u8> {
    let units = match set {
        UnitSet::Std => &v.techno.std,
        UnitSet::Late => &v.techno.late,
    };
    let Some(u) = units.get(k) else {
        return vec![0; 4];
    };
    let f = u.function.as_ref();
    let dword = |x: u32| x.to_le_bytes().to_vec();
    match part {
        TechnoPart::Type => (f.map_or(0, |f| f.kind as u16)).to_le_bytes().to_vec(),
        TechnoPart::Please => vec![u8::from(u.please)],
        TechnoPart::Done => vec![u8::from(u.done)],
        TechnoPart::Nr => dword(f.map_or(0, |f| f.number)),
        TechnoPart::Time => (f.map_or(0, |f| i32::try_from(f.process_time_us).unwrap_or(i32::MAX)))
            .to_le_bytes()
            .to_vec(),
        TechnoPart::BlockNr => dword(f.map_or(0, |f| f.block_nr)),
        TechnoPart::PrgLine => dword(f.map_or(0, |f| f.line)),
        TechnoPart::AddValue => f.map_or(0, |f| f.add_value).to_le_bytes().to_vec(),
        // ncchannel numbers no late synchronisations apart (the HLI unit's field reads 0 too).
        TechnoPart::NrLateSync => 0u16.to_le_bytes().to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ads::testing;
    use std::sync::Arc;

    fn query(b: &dyn CncBackend, group: u32, ch: i32, axis: i32) -> (u32, u32) {
        let data = [ch.to_le_bytes(), axis.to_le_bytes()].concat();
        let r = read_write(b, group, 0, 8, &data).unwrap();
        (
            u32::from_le_bytes([r[0], r[1], r[2], r[3]]),
            u32::from_le_bytes([r[4], r[5], r[6], r[7]]),
        )
    }

    #[test]
    fn address_query_names_existing_instances_only() {
        let t = testing::channels(1);
        let b = &t.backend;
        assert_eq!(query(b.as_ref(), 0x121900, 1, 0), (0x121301, 0));
        assert_eq!(query(b.as_ref(), 0x123900, 1, 0), (0x123301, 0));
        assert_eq!(
            query(b.as_ref(), 0x21900, 1, 0),
            (0x121301, 0),
            "index-based"
        );
        assert_eq!(query(b.as_ref(), 0x121900, 2, 0), (0, 0));
        assert_eq!(query(b.as_ref(), 0x121900, 0, 1), (0, 0));
        assert_eq!(
            read_write(b.as_ref(), 0x121900, 0, 8, &[0; 4]),
            Err(AdsResult::INVALID_SIZE)
        );
    }

    #[test]
    fn hld_shows_mode_state_and_the_hli_unit() {
        let t = testing::channels(1);
        let b = &t.backend;
        let hli = Hli::new(Arc::clone(b));
        assert_eq!(
            read(b.as_ref(), &hli, 0x123301, 0x1F, 4).unwrap(),
            [3, 0, 0, 0]
        );
        assert_eq!(
            read(b.as_ref(), &hli, 0x123301, 0x20, 4).unwrap(),
            [2, 0, 0, 0],
            "AUTOMATIC, as a channel starts"
        );
        assert_eq!(
            read(b.as_ref(), &hli, 0x123301, 0x2F, 300).unwrap().len(),
            300
        );
        assert_eq!(
            read(b.as_ref(), &hli, 0x20300, 0x01, 8).unwrap(),
            0.001f64.to_le_bytes(),
            "position controller: cycle time in s"
        );
        assert_eq!(read(b.as_ref(), &hli, 0x120300, 0x02, 2).unwrap(), [3, 0]);
        assert_eq!(
            read(b.as_ref(), &hli, 0x121301, 0x70, 8).unwrap(),
            1.0f64.to_le_bytes()
        );
        assert_eq!(
            read(b.as_ref(), &hli, 0x121301, 0x15, 4),
            Err(AdsResult::INVALID_SIZE)
        );
        assert_eq!(
            read(b.as_ref(), &hli, 0x121301, 0x02, 8),
            Err(AdsResult::INVALID_OFFSET),
            "moved path is not modelled"
        );
    }
}
