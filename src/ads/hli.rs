//! The PLC's HLI on AMS port 851: the `HLI_Global_Variables` symbols a TwinCAT 3 CNC PLC
//! exposes, served by the standard ADS symbol services, with the CNC side of the control units
//! played by the channel.
//!
//! Symbols and layouts as TwinSharp uses them (`kimblad/TwinSharp` `TwinSharp/CNC/*.cs`,
//! `Structs.cs` `Pack = 1`): every handle TwinSharp's constructors create resolves. Control
//! unit semantics (Beckhoff infosys `tf5200_hli_interface/174725259.html`, `174858763.html`):
//! the PLC writes `command_w`, then sets `command_semaphor_rw` TRUE; the CNC takes the data
//! and sets the semaphore FALSE. Here that happens when the write of TRUE arrives: the
//! command goes to the channel (mode, program name, state; one request each) and the
//! semaphore reads FALSE afterwards. Errors (`mc_error`, infosys `174914699.html`): one record
//! is posted with `semaphor_rw` TRUE; the next only after the client wrote it FALSE.
//!
//! Technology units (TF5200 HLI "Technology functions", "Data of the M/H function"; the PLC's
//! side as `kimblad/TwinSharp` `TwinSharp/CNC/TechnologyProcesses.cs` runs it):
//! `techno_unit_std_sync`, `techno_unit_late_sync`, their `used_units_*_r` and
//! `head.plc_present_w` are live views of the channel's units (`Status.techno`, see
//! `src/channel/techno.rs`), encoded on every read; `please_rw`, `done_w` and `plc_present_w`
//! writes go to the channel as `Op::Techno`; every other part of them is read-only.
//!
//! Symbols without behaviour in ncchannel (backward motion, manual mode keys, external axis
//! commands …) are plain memory: they resolve, read back what was written and act on nothing
//! (listed as inert in docs/ads.md).
//!
//! Services (ADS index groups of the TwinCAT PLC runtime): 0xF003 handle by name
//! (ReadWrite), 0xF004 value by name (ReadWrite), 0xF005 value by handle (Read/Write, offset =
//! handle), 0xF006 release handle (Write), 0xF009 symbol info by name (ReadWrite); the
//! uploads and runtime data of [`super::symbols`] (0xF008, 0xF00B, 0xF00C, 0xF00E, 0xF00F,
//! 0xF100), a symbol's location by name (0xF007) and data types by name (0xF011) with the layouts of [`super::plc_types`]. A
//! symbol's address (its entry's group and offset) is value-by-handle: 0xF005 and its handle.
//! Handles are stable per symbol (symbol index + 1), so releasing is bookkeeping-free and a
//! client that never releases cannot exhaust anything.

use std::collections::{HashMap, VecDeque};
use std::sync::atomic::{AtomicU16, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};

use super::backend::{CncBackend, DeviceError, Live, ObjectEncoder, Op, Reply, Source};
use super::description::{Access, AdsType, ObjectInfo};
use super::plc_types::DataType;
use super::result::AdsResult;
use super::symbols::{
    self, ads_state, symbol_entry, SymbolInfo, UploadInfo, GROUP_DEVICE_DATA,
    GROUP_LOCATION_BY_NAME, GROUP_SYMBOL_UPLOAD, GROUP_SYMBOL_VERSION, GROUP_TYPE_BY_NAME,
    GROUP_TYPE_UPLOAD, GROUP_UPLOAD_INFO, GROUP_UPLOAD_INFO2,
};
use crate::channel::techno::{
    TechnoStatus, TechnoWrite, Unit as TechnoUnit, UnitSet, LATE_SYNC_UNITS, STD_SYNC_UNITS,
};
use crate::vocab::mode::{Mode, State};

pub const PORT: u16 = 851;
pub(crate) const GROUP_HANDLE_BY_NAME: u32 = 0xF003;
pub(crate) const GROUP_VALUE_BY_NAME: u32 = 0xF004;
pub(crate) const GROUP_VALUE_BY_HANDLE: u32 = 0xF005;
pub(crate) const GROUP_RELEASE_HANDLE: u32 = 0xF006;
pub(crate) const GROUP_INFO_BY_NAME: u32 = 0xF009;
/// ADS error "symbol not found".
pub(crate) const SYMBOL_NOT_FOUND: AdsResult = AdsResult(0x710);
/// Longest symbol name accepted.
const MAX_NAME_BYTES: usize = 255;

/// `HLI_PROC_TRANS_TO_MODE_STATE` (TwinSharp `Structs.cs`): 5 × UDINT, DINT fill, char[299]
/// parameter, DINT fill = 327 bytes.
pub(crate) const MODE_TRANSITION_BYTES: usize = 327;
const PARAMETER_AT: usize = 24;
const PARAMETER_BYTES: usize = 299;
/// `HLI_ERROR_SATZ` (TwinSharp `Structs.cs`): 104-byte head + 838-byte body.
pub(crate) const ERROR_RECORD_BYTES: usize = 942;
/// `TECHNO_UNIT_CH` bytes (TwinSharp `Structs.cs`, Pack = 1): please_rw BOOL @0, done_w BOOL
/// @1, type UINT @2, fill_up_1 DINT @4, the function's data byte[39] @8.
pub(crate) const TECHNO_UNIT_BYTES: usize = 47;
/// Where the function's data (`attribut_r.data`) starts in a unit.
const TECHNO_DATA_AT: usize = 8;
const TECHNO_DATA_BYTES: usize = 39;
/// `techno_unit_std_sync` entries (`[0..19]`) and `techno_unit_late_sync` entries (`[0..9]`).
const TECHNO_UNITS: usize = STD_SYNC_UNITS;
const TECHNO_UNITS_LATE: usize = LATE_SYNC_UNITS;
/// TwinSharp `Constants.cs`: keys `[0..10]`; the kernel dump lists handwheels `[0..5]`.
const KEYS: usize = 11;
const HANDWHEELS: usize = 6;
/// The error id a refused mode-and-state command posts in `mc_error.satz_r`: diagnosis
/// 270061, the kernel's "target state not permitted in this mode" (infosys
/// `tf5200_diagnosis/267091851.html`).
pub(crate) const REFUSED_TRANSITION_ERROR: u32 = 270_061;
/// Refusals kept for posting per channel; the PLC takes one record at a time.
const MAX_REFUSALS_WAITING: usize = 16;
/// Error body type "LEER" (empty): ncchannel's error text travels in `mc_error_message_r`.
const BODY_EMPTY: u32 = 9;

use super::plc_types::adst::{
    BIGTYPE as ADST_BIGTYPE, BIT as ADST_BIT, INT16 as ADST_INT16, INT32 as ADST_INT32,
    STRING as ADST_STRING, UINT16 as ADST_UINT16, UINT32 as ADST_UINT32,
};

/// The parts of a channel's mode-and-state control unit (the GEO task mirrors them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Unit {
    Enable,
    RequestSemaphore,
    CommandSemaphore,
    Request,
    Command,
}

/// What a root area does besides holding bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Plain,
    /// `state_r`: the channel's mode and state, read live.
    ModeState(u16),
    /// `command_semaphor_rw`: TRUE hands `command_w` to the channel.
    CommandSemaphore(u16),
    /// `mc_error.satz_r` / `semaphor_rw`: posts the next error when the semaphore is FALSE.
    ErrorRecord(u16),
    ErrorSemaphore(u16),
    /// `techno_unit_std_sync` / `techno_unit_late_sync`: the channel's units, read live;
    /// `please_rw` and `done_w` written through.
    TechnoUnits(u16, UnitSet),
    /// `used_units_std_sync_r` / `used_units_late_sync_r`, read live, read-only.
    TechnoUsed(u16, UnitSet),
    /// `head.plc_present_w`: the channel's flag, read live and written through.
    PlcPresent(u16),
}

impl Role {
    /// Live symbols whose every byte is the CNC's: a write is refused.
    fn read_only(self) -> bool {
        matches!(
            self,
            Role::ModeState(_) | Role::ErrorRecord(_) | Role::TechnoUsed(..)
        )
    }
}

/// One symbol: a window `[at, at + size)` of a root area.
#[derive(Debug, Clone)]
struct Symbol {
    name: String,
    root: usize,
    at: usize,
    size: usize,
    ty: &'static str,
    adst: u32,
    /// A level above the root areas (`…mode_and_state`, `gpCh[0]^`, `HLI_Global_Variables`):
    /// the root areas below it, back to back; `root`, `at` and `ty` are then unused.
    composite: Option<Composite>,
}

/// The root areas a level above them spans, in layout order, and its type's name.
#[derive(Debug, Clone)]
struct Composite {
    parts: Vec<usize>,
    ty: String,
}

impl Symbol {
    fn type_name(&self) -> &str {
        self.composite.as_ref().map_or(self.ty, |c| c.ty.as_str())
    }
}

/// Levels inside one root's type named at most (the largest HLI type, an error record with
/// its 838-byte body, has under a thousand).
const MAX_LEVELS_PER_ROOT: usize = 4096;

/// Per channel: where its control-unit areas are.
#[derive(Debug, Clone, Copy, Default)]
struct ChannelAreas {
    enable: usize,
    request: usize,
    request_semaphore: usize,
    command: usize,
    command_semaphore: usize,
    error_record: usize,
    error_semaphore: usize,
}

impl ChannelAreas {
    /// The root area holding `unit` of the mode-and-state unit.
    fn unit_root(&self, unit: Unit) -> usize {
        match unit {
            Unit::Enable => self.enable,
            Unit::RequestSemaphore => self.request_semaphore,
            Unit::CommandSemaphore => self.command_semaphore,
            Unit::Request => self.request,
            Unit::Command => self.command,
        }
    }
}

/// The symbol table and its memory, built once the channels are known.
pub(crate) struct Image {
    symbols: Vec<Symbol>,
    /// The symbols the object map and the upload list (`symbols[..listed]`); the rest are
    /// the levels [`Builder::derive`] names.
    listed: usize,
    by_name: HashMap<String, usize>,
    roles: Vec<Role>,
    memory: Mutex<Vec<Vec<u8>>>,
    /// The memory as built (constants set, everything else zero): what a PLC reset restores.
    initial: Vec<Vec<u8>>,
    channels: Vec<ChannelAreas>,
    /// Per channel: errors handed to the PLC so far.
    posted: Mutex<Vec<u64>>,
    /// Per channel: mode-and-state commands refused by the CNC side, waiting to be posted
    /// as error records (at most [`MAX_REFUSALS_WAITING`]; more are only logged).
    refused: Mutex<Vec<VecDeque<u32>>>,
    /// Per channel: the HMI's to-mode and parameter waiting for its to-state (redirection).
    pending: Mutex<Vec<PendingRequest>>,
}

/// What an HMI wrote of a mode transition before the to-state that completes it.
#[derive(Debug, Clone, Default)]
struct PendingRequest {
    to_mode: Option<u32>,
    parameter: Vec<u8>,
}

/// An HMI (COM) mode-and-state command, for redirection to the PLC.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum HmiRequest<'a> {
    ToMode(i32),
    ToState(i32),
    Parameter(&'a str),
}

struct Builder {
    img: Image,
}

impl Builder {
    fn root(
        &mut self,
        name: String,
        size: usize,
        ty: &'static str,
        adst: u32,
        role: Role,
    ) -> usize {
        let root = self.img.roles.len();
        self.img.roles.push(role);
        if let Ok(mut m) = self.img.memory.lock() {
            m.push(vec![0; size]);
        }
        self.sub(name, root, 0, size, ty, adst);
        root
    }

    fn sub(
        &mut self,
        name: String,
        root: usize,
        at: usize,
        size: usize,
        ty: &'static str,
        adst: u32,
    ) {
        self.img
            .by_name
            .insert(name.to_ascii_lowercase(), self.img.symbols.len());
        self.img.symbols.push(Symbol {
            name,
            root,
            at,
            size,
            ty,
            adst,
            composite: None,
        });
    }

    /// Name every level of the type tree the listed symbols leave out, after them (their
    /// handles stay): inside a root, each member and array element its type has
    /// (`…mc_error.satz_r.kopf`, `…rumpf[5]`), a window of the root; above the roots, each
    /// prefix of their names at a `.` or `[` (`…mode_and_state`, `…gpCh[0]^`,
    /// `HLI_Global_Variables`), the roots below it back to back. A pointer array's own
    /// levels (`gpCh`, `gpCh[0]`: addresses in a PLC) are not named: `gpCh[0]^` is.
    fn derive(&mut self) {
        let listed = self.img.symbols.len();
        // Each root's own symbol: the first one naming it.
        let mut seen = vec![false; self.img.roles.len()];
        let roots: Vec<usize> = (0..listed)
            .filter(|&i| !std::mem::replace(&mut seen[self.img.symbols[i].root], true))
            .collect();
        for &i in &roots {
            let (name, root, ty) = {
                let s = &self.img.symbols[i];
                (s.name.clone(), s.root, s.ty)
            };
            let Some(t) = DataType::lookup(ty) else {
                continue;
            };
            for (path, at, sub) in t.sub_paths(MAX_LEVELS_PER_ROOT) {
                let full = format!("{name}{path}");
                let Some(size) = sub.size_bytes() else {
                    continue;
                };
                if !self.img.by_name.contains_key(&full.to_ascii_lowercase()) {
                    self.sub(
                        full,
                        root,
                        at as usize,
                        size as usize,
                        sub.name_a(),
                        sub.adst(),
                    );
                }
            }
        }
        let mut levels: Vec<(String, Vec<usize>)> = Vec::new();
        let mut at_level: HashMap<String, usize> = HashMap::new();
        for &i in &roots {
            let name = &self.img.symbols[i].name;
            for (p, c) in name.char_indices().filter(|&(_, c)| c == '.' || c == '[') {
                let pointers = c == '['
                    && name[p..]
                        .split_once(']')
                        .is_some_and(|(_, rest)| rest.starts_with('^'));
                let key = name[..p].to_ascii_lowercase();
                if pointers || self.img.by_name.contains_key(&key) {
                    continue;
                }
                let k = *at_level.entry(key).or_insert_with(|| {
                    levels.push((name[..p].to_string(), Vec::new()));
                    levels.len() - 1
                });
                levels[k].1.push(i);
            }
        }
        for (name, parts) in levels {
            let size: usize = parts.iter().map(|&p| self.img.symbols[p].size).sum();
            let Some(&first) = parts.first() else {
                continue;
            };
            self.img
                .by_name
                .insert(name.to_ascii_lowercase(), self.img.symbols.len());
            self.img.symbols.push(Symbol {
                name,
                root: self.img.symbols[first].root,
                at: 0,
                size,
                ty: "",
                adst: ADST_BIGTYPE,
                composite: Some(Composite {
                    ty: format!("ARRAY [0..{}] OF BYTE", size.saturating_sub(1)),
                    parts,
                }),
            });
        }
    }

    fn bool(&mut self, name: String) -> usize {
        self.root(name, 1, "BOOL", ADST_BIT, Role::Plain)
    }

    /// A `command_w` / `enable_w` / `command_semaphor_rw` unit of plain memory.
    fn unit(&mut self, prefix: &str, command_size: usize, command_ty: &'static str) {
        self.bool(format!("{prefix}.enable_w"));
        self.root(
            format!("{prefix}.command_w"),
            command_size,
            command_ty,
            ADST_BIGTYPE,
            Role::Plain,
        );
        self.bool(format!("{prefix}.command_semaphor_rw"));
    }

    fn transition(&mut self, name: String, role: Role) -> usize {
        let r = self.root(
            name.clone(),
            MODE_TRANSITION_BYTES,
            "HLI_PROC_TRANS_TO_MODE_STATE",
            ADST_BIGTYPE,
            role,
        );
        for (i, f) in [
            "from_mode",
            "from_state",
            "to_mode",
            "to_state",
            "channel_number",
        ]
        .iter()
        .enumerate()
        {
            self.sub(format!("{name}.{f}"), r, 4 * i, 4, "UDINT", ADST_UINT32);
        }
        self.sub(
            format!("{name}.parameter"),
            r,
            PARAMETER_AT,
            PARAMETER_BYTES,
            "STRING(298)",
            ADST_STRING,
        );
        r
    }

    fn channel(&mut self, i: usize, ch: u16, axes: usize) -> ChannelAreas {
        let p = format!("HLI_Global_Variables.gpCh[{i}]^");
        let areas = self.channel_control(&p, ch);
        self.techno_units(&p, ch);
        self.path_control_units(&p);
        self.manual_mode_units(&p, axes);
        areas
    }

    /// Channel step 1: mode/state interface, PLC presence and error record, the areas the
    /// channel's HLI unit serves (laid out first, in the kernel's order).
    fn channel_control(&mut self, p: &str, ch: u16) -> ChannelAreas {
        let ms = format!("{p}.channel_mc_control.mode_and_state");
        let state = self.root(
            format!("{ms}.state_r"),
            8,
            "HLI_IMCM_MODE_STATE",
            ADST_BIGTYPE,
            Role::ModeState(ch),
        );
        self.sub(
            format!("{ms}.state_r.mode"),
            state,
            0,
            4,
            "UDINT",
            ADST_UINT32,
        );
        self.sub(
            format!("{ms}.state_r.state"),
            state,
            4,
            4,
            "UDINT",
            ADST_UINT32,
        );
        let request = self.transition(format!("{ms}.request_r"), Role::Plain);
        let enable = self.bool(format!("{ms}.enable_w"));
        let command = self.transition(format!("{ms}.command_w"), Role::Plain);
        let request_semaphore = self.bool(format!("{ms}.request_semaphor_rw"));
        let command_semaphore = self.root(
            format!("{ms}.command_semaphor_rw"),
            1,
            "BOOL",
            ADST_BIT,
            Role::CommandSemaphore(ch),
        );
        self.root(
            format!("{p}.head.plc_present_w"),
            1,
            "BOOL",
            ADST_BIT,
            Role::PlcPresent(ch),
        );
        let areas = ChannelAreas {
            request,
            enable,
            command,
            request_semaphore,
            command_semaphore,
            error_record: self.root(
                format!("{p}.mc_error.satz_r"),
                ERROR_RECORD_BYTES,
                "HLI_ERROR_SATZ",
                ADST_BIGTYPE,
                Role::ErrorRecord(ch),
            ),
            error_semaphore: self.root(
                format!("{p}.mc_error.semaphor_rw"),
                1,
                "BOOL",
                ADST_BIT,
                Role::ErrorSemaphore(ch),
            ),
        };
        self.sub(
            format!("{p}.mc_error.satz_r.kopf.error_id"),
            areas.error_record,
            0,
            4,
            "UDINT",
            ADST_UINT32,
        );
        areas
    }

    /// Channel step 2: technology units (TF5200 HLI "Technology functions"), live views of
    /// the channel's units: the arrays, each unit, its `please_rw`, `done_w`, `type` and
    /// `attribut_r.data` (the function's data, `HLI_M_H_PROZESS` for M and H), and the
    /// `used_units_*_r` counts.
    fn techno_units(&mut self, p: &str, ch: u16) {
        for (set, name, n, used) in [
            (
                UnitSet::Std,
                "techno_unit_std_sync",
                TECHNO_UNITS,
                "used_units_std_sync_r",
            ),
            (
                UnitSet::Late,
                "techno_unit_late_sync",
                TECHNO_UNITS_LATE,
                "used_units_late_sync_r",
            ),
        ] {
            let ty: &'static str = match set {
                UnitSet::Std => "ARRAY [0..19] OF TECHNO_UNIT_CH",
                UnitSet::Late => "ARRAY [0..9] OF TECHNO_UNIT_CH",
            };
            let tu = self.root(
                format!("{p}.{name}"),
                n * TECHNO_UNIT_BYTES,
                ty,
                ADST_BIGTYPE,
                Role::TechnoUnits(ch, set),
            );
            for k in 0..n {
                let u = format!("{p}.{name}[{k}]");
                let at = k * TECHNO_UNIT_BYTES;
                self.sub(
                    u.clone(),
                    tu,
                    at,
                    TECHNO_UNIT_BYTES,
                    "TECHNO_UNIT_CH",
                    ADST_BIGTYPE,
                );
                self.sub(format!("{u}.please_rw"), tu, at, 1, "BOOL", ADST_BIT);
                self.sub(format!("{u}.done_w"), tu, at + 1, 1, "BOOL", ADST_BIT);
                self.sub(format!("{u}.type"), tu, at + 2, 2, "UINT", ADST_UINT16);
                self.sub(
                    format!("{u}.attribut_r.data"),
                    tu,
                    at + TECHNO_DATA_AT,
                    TECHNO_DATA_BYTES,
                    "ARRAY [0..38] OF BYTE",
                    ADST_BIGTYPE,
                );
            }
            self.root(
                format!("{p}.{used}"),
                2,
                "UINT",
                ADST_UINT16,
                Role::TechnoUsed(ch, set),
            );
        }
    }

    /// Channel step 3: path control units (TwinSharp BackwardsOnPath.cs,
    /// DeleteDistanceToGo.cs), plain memory.
    fn path_control_units(&mut self, p: &str) {
        let bahn = format!("{p}.bahn_mc_control");
        for unit in [
            "backward_motion",
            "simulate_motion",
            "backward_storage_off",
            "ext_command_speed_valid",
            "delete_distance_to_go",
        ] {
            for f in ["command_w", "enable_w", "state_r"] {
                self.bool(format!("{bahn}.{unit}.{f}"));
            }
        }
        self.root(
            format!("{bahn}.ext_command_speed.command_w"),
            4,
            "UDINT",
            ADST_UINT32,
            Role::Plain,
        );
        self.bool(format!("{bahn}.ext_command_speed.enable_w"));
        self.root(
            format!("{bahn}.ext_command_speed.state_r"),
            4,
            "UDINT",
            ADST_UINT32,
            Role::Plain,
        );
    }

    /// Channel step 4: manual mode units (TwinSharp ManualOperation.cs, Structs.cs sizes)
    /// and each axis's handwheel display, plain memory.
    fn manual_mode_units(&mut self, p: &str, axes: usize) {
        let hb = format!("{p}.hb_mc_control");
        self.unit(&format!("{hb}.activation"), 12, "HLI_HB_ACTIVATION");
        self.unit(&format!("{hb}.tip_parameter"), 8, "HLI_HB_TIP_PARAMETER");
        self.unit(&format!("{hb}.jog_parameter"), 16, "HLI_HB_JOG_PARAMETER");
        self.unit(&format!("{hb}.hr_parameter"), 8, "HLI_HB_HR_PARAMETER");
        self.unit(&format!("{hb}.rapid_key"), 8, "HLI_HB_RAPID_KEY");
        for k in 0..KEYS {
            self.unit(&format!("{hb}.key[{k}]"), 16, "HLI_HB_KEY");
        }
        for k in 0..HANDWHEELS {
            self.bool(format!("{hb}.handwheel_incs[{k}].enable_w"));
            self.root(
                format!("{hb}.handwheel_incs[{k}].command_w"),
                2,
                "INT",
                ADST_INT16,
                Role::Plain,
            );
        }
        for k in 0..axes {
            let d = format!("{p}.bahn_state.coord_r[{k}].hb_display_r");
            let r = self.root(d.clone(), 10, "HLI_HB_DISPLAY", ADST_BIGTYPE, Role::Plain);
            self.sub(format!("{d}.state"), r, 0, 2, "UINT", ADST_UINT16);
            self.sub(format!("{d}.operation_mode"), r, 2, 2, "UINT", ADST_UINT16);
            self.sub(format!("{d}.control_element"), r, 4, 2, "UINT", ADST_UINT16);
            self.sub(format!("{d}.tipp_geschw"), r, 6, 4, "DINT", ADST_INT32);
        }
    }

    fn axis(&mut self, a: usize) {
        let p = format!("HLI_Global_Variables.gpAx[{a}]^");
        self.bool(format!("{p}.head.plc_present_w"));
        let add = format!("{p}.lr_mc_control.add_cmd_values");
        let r = self.root(
            format!("{add}.command_w"),
            32,
            "HLI_ADD_CMD_VALUE",
            ADST_BIGTYPE,
            Role::Plain,
        );
        self.sub(
            format!("{add}.command_w.m_add_pos_value"),
            r,
            0,
            4,
            "DINT",
            ADST_INT32,
        );
        self.sub(
            format!("{add}.command_w.m_add_speed_value"),
            r,
            4,
            4,
            "DINT",
            ADST_INT32,
        );
        self.bool(format!("{add}.enable_w"));
        let dyn_low = format!("{p}.ipo_mc_control.dyn_pos_limit_low");
        self.bool(format!("{dyn_low}.enable_w"));
        self.root(
            format!("{dyn_low}.command_w"),
            4,
            "DINT",
            ADST_INT32,
            Role::Plain,
        );
        self.root(
            format!("{dyn_low}.state_r"),
            4,
            "DINT",
            ADST_INT32,
            Role::Plain,
        );
    }

    fn constant(&mut self, name: &str, value: i32) {
        let r = self.root(name.into(), 4, "DINT", ADST_INT32, Role::Plain);
        if let Ok(mut m) = self.img.memory.lock() {
            m[r].copy_from_slice(&value.to_le_bytes());
        }
    }
}

impl Image {
    fn build(axes_per_channel: &[usize]) -> Image {
        let mut b = Builder {
            img: Image {
                symbols: Vec::new(),
                listed: 0,
                by_name: HashMap::new(),
                roles: Vec::new(),
                memory: Mutex::new(Vec::new()),
                initial: Vec::new(),
                channels: Vec::new(),
                posted: Mutex::new(vec![0; axes_per_channel.len()]),
                refused: Mutex::new(vec![VecDeque::new(); axes_per_channel.len()]),
                pending: Mutex::new(vec![PendingRequest::default(); axes_per_channel.len()]),
            },
        };
        b.constant(
            "HLI_Global_Constants.HLI_TU_CH_STD_SYNC_MAXIDX",
            TECHNO_UNITS as i32 - 1,
        );
        // TECHNO_UNIT_CH's process data is byte[39] (TwinSharp Structs.cs): index 0..38.
        b.constant("HLI_Global_Constants.HLI_TECH_UNIT_CH_MAXIDX", 38);
        for (i, &axes) in axes_per_channel.iter().enumerate() {
            let areas = b.channel(i, (i + 1) as u16, axes);
            b.img.channels.push(areas);
        }
        for a in 0..axes_per_channel.iter().sum::<usize>() {
            b.axis(a);
        }
        b.img.listed = b.img.symbols.len();
        b.derive();
        let initial = b.img.memory().clone();
        b.img.initial = initial;
        b.img
    }

    /// Whether a write of a whole level above root `i` must leave it alone: read-only roots
    /// and the technology units (only their flags are written, one at a time).
    fn composite_read_only(&self, i: usize) -> bool {
        let role = self.roles[self.symbols[i].root];
        role.read_only() || matches!(role, Role::TechnoUnits(..))
    }

    /// Whether symbol `i` is read-only as a whole (its entry's flag).
    fn read_only(&self, i: usize) -> bool {
        let s = &self.symbols[i];
        match &s.composite {
            Some(c) => c.parts.iter().any(|&p| self.composite_read_only(p)),
            None => self.roles[s.root].read_only(),
        }
    }

    /// Read symbol `i`: its bytes, or the first `length` of them (TwinSharp reads
    /// `[MAXIDX]` elements of an array). The live roles read `source`: a Read asks the
    /// runtime, a notification evaluated in the cycle reads its tick.
    fn read_symbol(
        &self,
        i: usize,
        length: u32,
        source: &mut dyn Source,
    ) -> Result<Vec<u8>, AdsResult> {
        let s = &self.symbols[i];
        let n = s.size.min(length as usize);
        if let Some(c) = &s.composite {
            let mut out = Vec::with_capacity(n);
            for &p in &c.parts {
                let Some(left) = n.checked_sub(out.len()).filter(|&l| l > 0) else {
                    break;
                };
                out.extend(self.read_symbol(p, u32::try_from(left).unwrap_or(u32::MAX), source)?);
            }
            return Ok(out);
        }
        if let Some(bytes) = techno_root(self.roles[s.root], source)? {
            return bytes
                .get(s.at..s.at + n)
                .map(<[u8]>::to_vec)
                .ok_or(AdsResult::INVALID_SIZE);
        }
        match self.roles[s.root] {
            Role::ModeState(ch) => {
                let st = source.status(ch).map_err(AdsResult::from)?;
                let (mode, state) = (st.mode as u32, st.state as u32);
                let mut mem = self.memory();
                mem[s.root][0..4].copy_from_slice(&mode.to_le_bytes());
                mem[s.root][4..8].copy_from_slice(&state.to_le_bytes());
            }
            Role::ErrorRecord(ch) | Role::ErrorSemaphore(ch) => self.post_error(ch, source)?,
            _ => {}
        }
        let mem = self.memory();
        Ok(mem[s.root][s.at..s.at + n].to_vec())
    }

    /// Post the channel's next error into `mc_error.satz_r` when the semaphore is FALSE.
    fn post_error(&self, ch: u16, source: &mut dyn Source) -> Result<(), AdsResult> {
        let areas = self.areas(ch)?;
        if self.memory()[areas.error_semaphore][0] != 0 {
            return Ok(());
        }
        let i = usize::from(ch) - 1;
        let refusal = self.refused.lock().unwrap_or_else(|p| p.into_inner())[i].pop_front();
        if let Some(code) = refusal {
            let tick = source.status(ch).map_err(AdsResult::from)?.tick;
            let mut mem = self.memory();
            mem[areas.error_record].copy_from_slice(&error_record(code, ch, tick));
            mem[areas.error_semaphore][0] = 1;
            return Ok(());
        }
        let next = self.posted.lock().unwrap_or_else(|p| p.into_inner())[i];
        let mut rec = source.error_record(ch, next).map_err(AdsResult::from)?;
        if next >= rec.total {
            return Ok(());
        }
        let mut index = next;
        if rec.error.is_none() {
            // No longer kept: skip to the newest.
            index = rec.total - 1;
            rec = source.error_record(ch, index).map_err(AdsResult::from)?;
        }
        let tick = source.status(ch).map_err(AdsResult::from)?.tick;
        let code = rec.error.as_ref().map_or(0, |(c, _)| *c);
        let record = error_record(code, ch, tick);
        let mut mem = self.memory();
        mem[areas.error_record].copy_from_slice(&record);
        mem[areas.error_semaphore][0] = 1;
        drop(mem);
        self.posted.lock().unwrap_or_else(|p| p.into_inner())[i] = index + 1;
        Ok(())
    }

    /// Bytes `[at, at + size)` of a channel's mode-and-state `unit` (for the GEO mirror).
    pub(crate) fn unit_bytes(
        &self,
        ch: u16,
        unit: Unit,
        at: usize,
        size: usize,
    ) -> Result<Vec<u8>, AdsResult> {
        let a = self.areas(ch)?;
        let root = a.unit_root(unit);
        let mem = self.memory();
        let area = &mem[root];
        let mut out = area[at.min(area.len())..(at + size).min(area.len())].to_vec();
        out.resize(size, 0);
        Ok(out)
    }

    fn memory(&self) -> MutexGuard<'_, Vec<Vec<u8>>> {
        self.memory.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn areas(&self, ch: u16) -> Result<ChannelAreas, AdsResult> {
        usize::from(ch)
            .checked_sub(1)
            .and_then(|i| self.channels.get(i))
            .copied()
            .ok_or(AdsResult::INVALID_GROUP)
    }
}

/// The HLI of one server: built on first use from the channels the backend has.
pub struct Hli {
    backend: Arc<dyn CncBackend>,
    /// The PLC runtime's ADS state: RUN, or STOP after WriteControl STOP or RESET.
    state: AtomicU16,
    image: OnceLock<Arc<Image>>,
    uploads: OnceLock<Uploads>,
}

/// The symbol and data-type uploads, encoded once (the symbols never change while serving).
struct Uploads {
    symbols: Vec<u8>,
    types: Vec<u8>,
    info: UploadInfo,
}

impl Hli {
    pub fn new(backend: Arc<dyn CncBackend>) -> Self {
        Hli {
            backend,
            state: AtomicU16::new(ads_state::RUN),
            image: OnceLock::new(),
            uploads: OnceLock::new(),
        }
    }

    /// The PLC runtime's ADS state (ReadState and 0xF100 on port 851).
    pub(crate) fn ads_state(&self) -> u16 {
        self.state.load(Ordering::SeqCst)
    }

    /// WriteControl on port 851 (ads-client `startPlc`/`stopPlc`/`resetPlc`, pyads
    /// `write_control`): RUN starts, STOP stops, RESET puts every variable back to its
    /// initial value and leaves the runtime in STOP, as a TwinCAT PLC reset does. The
    /// symbols stay readable and writable in STOP (as a TwinCAT PLC's are); the channels
    /// keep running. 0x706 for any other state.
    pub(crate) fn control(&self, ads_state: u16) -> Result<(), AdsResult> {
        match ads_state {
            ads_state::RUN | ads_state::STOP => {}
            ads_state::RESET => self.reinitialise(),
            _ => return Err(AdsResult::INVALID_DATA),
        }
        let next = if ads_state == ads_state::RUN {
            ads_state::RUN
        } else {
            ads_state::STOP
        };
        self.state.store(next, Ordering::SeqCst);
        Ok(())
    }

    /// The system restarted: the runtime starts afresh (variables initial) in RUN.
    pub(crate) fn restart(&self) {
        self.reinitialise();
        self.state.store(ads_state::RUN, Ordering::SeqCst);
    }

    /// Every variable back to its initial value; refusals waiting for `mc_error` and HMI
    /// requests half written are dropped with them. Errors already handed over stay so.
    fn reinitialise(&self) {
        let Some(img) = self.image.get() else { return };
        img.memory().clone_from(&img.initial);
        for q in img
            .refused
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .iter_mut()
        {
            q.clear();
        }
        for p in img
            .pending
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .iter_mut()
        {
            *p = PendingRequest::default();
        }
    }

    pub(crate) fn image(&self) -> Result<&Arc<Image>, AdsResult> {
        if let Some(img) = self.image.get() {
            return Ok(img);
        }
        let mut axes = Vec::new();
        for ch in 1..=self.backend.channel_count() {
            axes.push(
                self.backend
                    .status(ch)
                    .map_err(AdsResult::from)?
                    .positions
                    .len(),
            );
        }
        Ok(self.image.get_or_init(|| Arc::new(Image::build(&axes))))
    }

    /// Every symbol, for the object map (`group` 0xF005 and `offset` = its handle).
    pub fn objects(&self) -> Result<Vec<ObjectInfo>, AdsResult> {
        let img = self.image()?;
        Ok(img.symbols[..img.listed]
            .iter()
            .enumerate()
            .map(|(i, s)| ObjectInfo {
                port: PORT,
                group: GROUP_VALUE_BY_HANDLE,
                offset: i as u32 + 1,
                name: s.name.clone(),
                ty: AdsType::Named(s.ty),
                size: s.size as u32,
                access: Access::ReadWrite,
                unit: "",
                source: role_source(img.roles[s.root]),
            })
            .collect())
    }

    fn symbol_by_name(&self, data: &[u8]) -> Result<usize, AdsResult> {
        let end = data.iter().position(|&b| b == 0).unwrap_or(data.len());
        if end > MAX_NAME_BYTES {
            return Err(AdsResult::INVALID_SIZE);
        }
        let name = std::str::from_utf8(&data[..end]).map_err(|_| AdsResult::INVALID_DATA)?;
        let img = self.image()?;
        img.by_name
            .get(&name.trim().to_ascii_lowercase())
            .copied()
            .ok_or(SYMBOL_NOT_FOUND)
    }

    fn symbol_by_handle(&self, handle: u32) -> Result<usize, AdsResult> {
        let img = self.image()?;
        let i = (handle as usize).checked_sub(1).ok_or(SYMBOL_NOT_FOUND)?;
        if i < img.symbols.len() {
            Ok(i)
        } else {
            Err(SYMBOL_NOT_FOUND)
        }
    }

    /// A write into a technology symbol: one byte on a unit's `please_rw` or `done_w`, or
    /// `head.plc_present_w`; any other part (type, data, a whole unit or array) is
    /// read-only.
    fn write_techno(&self, role: Role, s: &Symbol, data: &[u8]) -> Result<(), AdsResult> {
        let (ch, w) = match (role, data) {
            (Role::PlcPresent(ch), [v]) => (ch, TechnoWrite::PlcPresent(*v != 0)),
            (Role::TechnoUnits(ch, set), [v]) if s.size == 1 => {
                let unit = s.at / TECHNO_UNIT_BYTES;
                let value = *v != 0;
                match s.at % TECHNO_UNIT_BYTES {
                    0 => (ch, TechnoWrite::Please { set, unit, value }),
                    1 => (ch, TechnoWrite::Done { set, unit, value }),
                    _ => return Err(AdsResult::ACCESS_DENIED),
                }
            }
            _ => return Err(AdsResult::ACCESS_DENIED),
        };
        match self.backend.call(ch, Op::Techno(w)) {
            Ok(Reply::Techno(Ok(()))) => Ok(()),
            Ok(Reply::Techno(Err(_))) => Err(AdsResult::INVALID_OFFSET),
            Ok(_) => Err(AdsResult::NOT_READY),
            Err(e) => Err(e.into()),
        }
    }

    fn write_symbol(&self, i: usize, data: &[u8]) -> Result<(), AdsResult> {
        let img = self.image()?;
        let s = &img.symbols[i];
        if data.is_empty() || data.len() > s.size {
            return Err(AdsResult::INVALID_SIZE);
        }
        if let Some(c) = &s.composite {
            return self.write_composite(img, c, data);
        }
        let role = img.roles[s.root];
        if role.read_only() {
            return Err(AdsResult::ACCESS_DENIED);
        }
        if matches!(role, Role::TechnoUnits(..) | Role::PlcPresent(_)) {
            return self.write_techno(role, s, data);
        }
        img.memory()[s.root][s.at..s.at + data.len()].copy_from_slice(data);
        if let (Role::CommandSemaphore(ch), [1, ..]) = (role, data) {
            self.take_command(img, ch);
        }
        Ok(())
    }

    /// A write to a level above the roots: the bytes go to the roots below it in order, each
    /// as its own write (a semaphore written TRUE acts as it does alone). Refused as a whole,
    /// 0x704, when a root it reaches is read-only (`state_r`, `satz_r`, the technology
    /// units), as a write to a read-only symbol is.
    fn write_composite(&self, img: &Image, c: &Composite, data: &[u8]) -> Result<(), AdsResult> {
        let mut touched = Vec::new();
        let mut rest = data;
        for &p in &c.parts {
            if rest.is_empty() {
                break;
            }
            let (head, tail) = rest.split_at(rest.len().min(img.symbols[p].size));
            touched.push((p, head));
            rest = tail;
        }
        if touched.iter().any(|&(p, _)| img.composite_read_only(p)) {
            return Err(AdsResult::ACCESS_DENIED);
        }
        for (p, d) in touched {
            self.write_symbol(p, d)?;
        }
        Ok(())
    }

    /// The CNC side of the mode-and-state unit: take `command_w` (to mode, parameter, to
    /// state; 0 = no change) and clear the semaphore. A transition the channel refuses
    /// leaves mode and state as they are (`state_r` shows it) and posts error 270061 in
    /// `mc_error.satz_r`, as the kernel reports a refused transition; so does an MDI block
    /// (MDI parameter), which the model cannot execute.
    fn take_command(&self, img: &Image, ch: u16) {
        let Ok(areas) = img.areas(ch) else { return };
        let cmd = img.memory()[areas.command].clone();
        let word = |at: usize| u32::from_le_bytes([cmd[at], cmd[at + 1], cmd[at + 2], cmd[at + 3]]);
        let (to_mode, to_state) = (word(8), word(12));
        let param = &cmd[PARAMETER_AT..PARAMETER_AT + PARAMETER_BYTES];
        let end = param.iter().position(|&b| b == 0).unwrap_or(param.len());
        let program = String::from_utf8_lossy(&param[..end]).trim().to_string();
        let b = &self.backend;
        let before = b.status(ch).ok();
        let r = (|| {
            let st = b.status(ch)?;
            let mode = st.mode;
            let target = if to_mode == 0 { mode as u32 } else { to_mode };
            if target == Mode::Mdi as u32 && !program.is_empty() {
                return Err(DeviceError::NotReady);
            }
            // To STANDBY is the way out of a running program or ERROR (TwinSharp
            // `OperationModeManager.Reset()` commands STANDBY, then the old mode): the channel
            // is reset first, then it changes mode.
            if to_mode == Mode::Standby as u32
                && matches!(st.state, State::Active | State::Hold | State::Error)
            {
                b.command(ch, Op::Reset)?;
            }
            if to_mode != 0 && to_mode != mode as u32 {
                b.command(ch, Op::CommandMode(to_mode as i32))?;
            }
            if !program.is_empty() {
                b.command(ch, Op::SetProgram(program))?;
            }
            match to_state {
                0 => Ok(()),
                // "Resetting" as a target state (diagnosis 270061).
                15 => b.command(ch, Op::Reset),
                s => b.command(ch, Op::CommandState(s as i32)),
            }
        })();
        if let Err(e) = r {
            log::warn!("HLI channel {ch}: mode/state command {to_mode}/{to_state} refused: {e}");
            // Refused as a whole: a mode or program set before the to-state was refused is
            // put back, so the command is applied or refused, never half of it.
            if let Some(st) = before {
                let _ = b.command(ch, Op::CommandMode(st.mode as i32));
                if let Some(p) = st.program {
                    let _ = b.command(ch, Op::SetProgram(p));
                }
            }
            let i = usize::from(ch) - 1;
            let mut refused = img.refused.lock().unwrap_or_else(|p| p.into_inner());
            if refused[i].len() < MAX_REFUSALS_WAITING {
                refused[i].push_back(REFUSED_TRANSITION_ERROR);
            }
        }
        img.memory()[areas.command_semaphore][0] = 0;
        // Shown at once when the PLC has taken the last record (else on its next read).
        let _ = img.post_error(ch, &mut Live::new(self.backend.as_ref()));
    }

    /// A mode or state command of channel `ch` that the HMI gave through COM was refused by
    /// its mode and state: 270061 waits for `mc_error` as one the PLC's own command posts.
    /// Nothing when no PLC client has read the HLI yet (no one to take the record).
    pub(crate) fn note_refusal(&self, ch: u16) {
        let Some(img) = self.image.get() else { return };
        let Some(i) = usize::from(ch).checked_sub(1) else {
            return;
        };
        {
            let mut refused = img.refused.lock().unwrap_or_else(|p| p.into_inner());
            match refused.get_mut(i) {
                Some(q) if q.len() < MAX_REFUSALS_WAITING => q.push_back(REFUSED_TRANSITION_ERROR),
                _ => return,
            }
        }
        let _ = img.post_error(ch, &mut Live::new(self.backend.as_ref()));
    }

    /// infosys 174725259: with `enable_w` TRUE "the PLC operates this command": an HMI's mode
    /// and state commands (COM `mcm_command_*_w`) are not executed but handed to the PLC in
    /// `request_r` with `request_semaphor_rw` TRUE; the PLC decides and commands through
    /// `command_w`. `None` when the PLC does not operate the unit (the channel executes the
    /// command itself). A to-state while the PLC has not taken the last request is 0x708.
    pub(crate) fn redirect(&self, ch: u16, req: HmiRequest<'_>) -> Option<Result<(), AdsResult>> {
        // Without a PLC client the image may not exist yet: then nobody set enable_w.
        let img = self.image.get()?;
        let areas = img.areas(ch).ok()?;
        if img.memory()[areas.enable][0] == 0 {
            return None;
        }
        let i = usize::from(ch) - 1;
        let mut pending = img.pending.lock().unwrap_or_else(|p| p.into_inner());
        let p = &mut pending[i];
        match req {
            HmiRequest::ToMode(m) => p.to_mode = u32::try_from(m).ok(),
            HmiRequest::Parameter(text) => {
                p.parameter = text.as_bytes()[..text.len().min(PARAMETER_BYTES - 1)].to_vec()
            }
            HmiRequest::ToState(s) => {
                // `pending` stays locked: redirections of a channel are one at a time.
                if img.memory()[areas.request_semaphore][0] != 0 {
                    return Some(Err(AdsResult::BUSY));
                }
                let (mode, state) = match self.backend.status(ch) {
                    Ok(st) => (st.mode as u32, st.state as u32),
                    Err(e) => return Some(Err(e.into())),
                };
                let mut mem = img.memory();
                let r = &mut mem[areas.request];
                r.fill(0);
                let words = [
                    mode,
                    state,
                    p.to_mode.unwrap_or(mode),
                    s as u32,
                    u32::from(ch),
                ];
                for (k, w) in words.iter().enumerate() {
                    r[4 * k..4 * k + 4].copy_from_slice(&w.to_le_bytes());
                }
                r[PARAMETER_AT..PARAMETER_AT + p.parameter.len()].copy_from_slice(&p.parameter);
                mem[areas.request_semaphore][0] = 1;
                *p = PendingRequest::default();
            }
        }
        Some(Ok(()))
    }

    /// Write `data` at byte `at` of channel `ch`'s mode-and-state `unit` (the HLD's view of
    /// it on port 551); the caller checked the element's size.
    pub(crate) fn write_unit_bytes(
        &self,
        ch: u16,
        unit: Unit,
        at: usize,
        data: &[u8],
    ) -> Result<(), AdsResult> {
        let img = self.image()?;
        let a = img.areas(ch)?;
        let root = a.unit_root(unit);
        let mut mem = img.memory();
        let area = &mut mem[root];
        let end = at.checked_add(data.len()).ok_or(AdsResult::INVALID_SIZE)?;
        area.get_mut(at..end)
            .ok_or(AdsResult::INVALID_SIZE)?
            .copy_from_slice(data);
        Ok(())
    }

    /// What the symbol entry of symbol `i` says: its address is value-by-handle.
    fn info<'i>(&self, img: &'i Image, i: usize) -> SymbolInfo<'i> {
        let s = &img.symbols[i];
        SymbolInfo {
            name: &s.name,
            ty: s.type_name(),
            group: GROUP_VALUE_BY_HANDLE,
            offset: i as u32 + 1,
            size_bytes: s.size as u32,
            adst: s.adst,
            read_only: img.read_only(i),
        }
    }

    /// The uploads: one entry per root variable (members are reached through the types, as
    /// a PLC lists `GVL.struct` and not its members) and every type those refer to.
    fn uploads(&self) -> Result<&Uploads, AdsResult> {
        if let Some(u) = self.uploads.get() {
            return Ok(u);
        }
        let img = self.image()?;
        let mut symbols = Vec::new();
        let mut count = 0u32;
        let mut type_names = Vec::new();
        let mut last_root = None;
        for (i, s) in img.symbols[..img.listed].iter().enumerate() {
            if last_root == Some(s.root) {
                continue;
            }
            last_root = Some(s.root);
            symbols.extend(symbol_entry(&self.info(img, i)));
            count += 1;
            if let Some(t) = DataType::lookup(s.ty) {
                t.closure(&mut type_names);
            }
        }
        let mut types = Vec::new();
        for name in &type_names {
            if let Some(e) = DataType::lookup(name).and_then(|t| t.entry()) {
                types.extend(e);
            }
        }
        let info = UploadInfo {
            symbols: count,
            symbol_bytes: symbols.len() as u32,
            types: type_names.len() as u32,
            type_bytes: types.len() as u32,
        };
        Ok(self.uploads.get_or_init(|| Uploads {
            symbols,
            types,
            info,
        }))
    }

    /// The encoder of a symbol's value by handle (`offset`), read `length` bytes at a time:
    /// what a Read by handle runs once and a notification evaluated in the cycle runs every
    /// due tick (`machine::watch`). `Err` for the other groups (uploads, info, device data),
    /// which are read whole.
    pub(crate) fn encoder(
        &self,
        group: u32,
        offset: u32,
        length: u32,
    ) -> Result<ObjectEncoder, AdsResult> {
        if group != GROUP_VALUE_BY_HANDLE {
            return Err(AdsResult::ACCESS_DENIED);
        }
        let i = self.symbol_by_handle(offset)?;
        let img = Arc::clone(self.image()?);
        Ok(Box::new(move |s: &mut dyn Source| {
            img.read_symbol(i, length, s)
        }))
    }

    /// ADS Read on port 851.
    pub fn read(&self, group: u32, offset: u32, length: u32) -> Result<Vec<u8>, AdsResult> {
        match group {
            GROUP_VALUE_BY_HANDLE => self.image()?.read_symbol(
                self.symbol_by_handle(offset)?,
                length,
                &mut Live::new(self.backend.as_ref()),
            ),
            GROUP_SYMBOL_VERSION => symbols::symbol_version(length),
            GROUP_DEVICE_DATA => symbols::device_data(self.ads_state(), offset, length),
            GROUP_UPLOAD_INFO => symbols::fit(self.uploads()?.info.v1(), length),
            GROUP_UPLOAD_INFO2 => self.uploads()?.info.for_length(length),
            GROUP_SYMBOL_UPLOAD => symbols::fit(self.uploads()?.symbols.clone(), length),
            GROUP_TYPE_UPLOAD => symbols::fit(self.uploads()?.types.clone(), length),
            GROUP_HANDLE_BY_NAME
            | GROUP_VALUE_BY_NAME
            | GROUP_INFO_BY_NAME
            | GROUP_RELEASE_HANDLE
            | GROUP_TYPE_BY_NAME
            | GROUP_LOCATION_BY_NAME => Err(AdsResult::ACCESS_DENIED),
            _ => Err(AdsResult::INVALID_GROUP),
        }
    }

    /// ADS Write on port 851.
    pub fn write(&self, group: u32, offset: u32, data: &[u8]) -> Result<(), AdsResult> {
        match group {
            GROUP_VALUE_BY_HANDLE => self.write_symbol(self.symbol_by_handle(offset)?, data),
            GROUP_RELEASE_HANDLE => {
                let [a, b, c, d] = *data else {
                    return Err(AdsResult::INVALID_SIZE);
                };
                self.symbol_by_handle(u32::from_le_bytes([a, b, c, d]))
                    .map(|_| ())
            }
            GROUP_HANDLE_BY_NAME | GROUP_VALUE_BY_NAME | GROUP_INFO_BY_NAME
            | GROUP_TYPE_BY_NAME => Err(AdsResult::ACCESS_DENIED),
            _ => Err(AdsResult::INVALID_GROUP),
        }
    }

    /// ADS ReadWrite on port 851.
    pub fn read_write(
        &self,
        group: u32,
        offset: u32,
        read_length: u32,
        data: &[u8],
    ) -> Result<Vec<u8>, AdsResult> {
        match group {
            GROUP_HANDLE_BY_NAME => {
                if read_length < 4 {
                    return Err(AdsResult::INVALID_SIZE);
                }
                let i = self.symbol_by_name(data)?;
                let mut reply = handle_reply(&self.image()?.symbols[i], i as u32 + 1);
                reply.truncate(read_length as usize);
                Ok(reply)
            }
            GROUP_VALUE_BY_NAME => self.image()?.read_symbol(
                self.symbol_by_name(data)?,
                read_length,
                &mut Live::new(self.backend.as_ref()),
            ),
            GROUP_INFO_BY_NAME => {
                let i = self.symbol_by_name(data)?;
                let entry = symbol_entry(&self.info(self.image()?, i));
                symbols::fit(entry, read_length)
            }
            GROUP_LOCATION_BY_NAME => {
                let info = self.info(self.image()?, self.symbol_by_name(data)?);
                let words = [info.group, info.offset, info.size_bytes];
                symbols::fit(
                    words.iter().flat_map(|w| w.to_le_bytes()).collect(),
                    read_length,
                )
            }
            GROUP_TYPE_BY_NAME => {
                let end = data.iter().position(|&b| b == 0).unwrap_or(data.len());
                let name =
                    std::str::from_utf8(&data[..end]).map_err(|_| AdsResult::INVALID_DATA)?;
                let entry = DataType::lookup(name)
                    .and_then(|t| t.entry())
                    .ok_or(SYMBOL_NOT_FOUND)?;
                symbols::fit(entry, read_length)
            }
            GROUP_VALUE_BY_HANDLE | GROUP_RELEASE_HANDLE => Err(AdsResult::ACCESS_DENIED),
            // The read-only services (uploads, version, device data) by ReadWrite too.
            _ => self.read(group, offset, read_length),
        }
    }
}

/// 0xF003's reply: the handle; a client that asks for more (`jisotalo/ads-client`
/// `createVariableHandle` asks for any length) also gets the symbol's size, the type
/// decoration (0: no decoration), the type name's length (u16) and the type name with NUL.
/// The encoder of symbol `i` of `img`, `length` bytes at a time.
fn symbol_encoder(img: &Arc<Image>, i: usize, length: u32) -> ObjectEncoder {
    let img = Arc::clone(img);
    Box::new(move |s: &mut dyn Source| img.read_symbol(i, length, s))
}

/// `bench --load cycle --notify-on hli`: the encoders of `count` handles on the channels'
/// `…mode_and_state.state_r` in turn (a live symbol: the tick's mode and state written into
/// the image, then copied out), over one image of `channels` channels (their symbols only).
pub(crate) fn bench_encoders(channels: usize, count: usize) -> Vec<ObjectEncoder> {
    let img = Arc::new(Image::build(&vec![0; channels]));
    (0..count)
        .filter_map(|k| {
            let name = format!(
                "hli_global_variables.gpch[{}]^.channel_mc_control.mode_and_state.state_r",
                k % channels.max(1)
            );
            let i = *img.by_name.get(&name)?;
            Some(symbol_encoder(&img, i, 8))
        })
        .collect()
}

/// A technology root's bytes, encoded from the channel's status in `source`; `None` for the
/// other roles.
fn techno_root(role: Role, source: &mut dyn Source) -> Result<Option<Vec<u8>>, AdsResult> {
    let (ch, f): (u16, fn(&TechnoStatus) -> Vec<u8>) = match role {
        Role::TechnoUnits(ch, UnitSet::Std) => (ch, |t| encode_units(&t.std, TECHNO_UNITS)),
        Role::TechnoUnits(ch, UnitSet::Late) => (ch, |t| encode_units(&t.late, TECHNO_UNITS_LATE)),
        Role::TechnoUsed(ch, UnitSet::Std) => (ch, |t| t.used_std.to_le_bytes().to_vec()),
        Role::TechnoUsed(ch, UnitSet::Late) => (ch, |t| t.used_late.to_le_bytes().to_vec()),
        Role::PlcPresent(ch) => (ch, |t| vec![u8::from(t.plc_present)]),
        _ => return Ok(None),
    };
    let st = source.status(ch).map_err(AdsResult::from)?;
    Ok(Some(f(&st.techno)))
}

fn handle_reply(s: &Symbol, handle: u32) -> Vec<u8> {
    let ty = s.type_name();
    let mut out = Vec::with_capacity(15 + ty.len());
    for w in [handle, s.size as u32, 0] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    out.extend_from_slice(&(ty.len() as u16).to_le_bytes());
    out.extend_from_slice(ty.as_bytes());
    out.push(0);
    out
}

fn role_source(role: Role) -> &'static str {
    match role {
        Role::Plain => "TwinSharp; inert",
        _ => "TwinSharp; HLI docs",
    }
}

/// `count` units as `TECHNO_UNIT_CH` (47 bytes each, Pack = 1, little-endian; TwinSharp
/// `Structs.cs`): please_rw, done_w, type (1 M, 2 H, 3 S, 4 T; 0 = never filled), fill, then
/// the function's data. For every kind the data is `HLI_M_H_PROZESS` (TF5200 HLI "Data of the
/// M/H function"): nr UDINT @0, time DINT @4 [µs], block_nr UDINT @8, prg_line UDINT @12,
/// add_value DINT @16, nr_late_sync UINT @20, fill UINT @22, synch_mode UDINT @24, fill DINT
/// @28; the last 7 bytes are zero. S and T have no public layout: S carries its speed (rpm,
/// rounded) in nr and add_value, T its tool number in nr.
pub(crate) fn encode_units(units: &[TechnoUnit], count: usize) -> Vec<u8> {
    let mut out = vec![0u8; count * TECHNO_UNIT_BYTES];
    for (u, b) in units.iter().zip(out.chunks_exact_mut(TECHNO_UNIT_BYTES)) {
        b[0] = u8::from(u.please);
        b[1] = u8::from(u.done);
        let Some(f) = &u.function else { continue };
        b[2..4].copy_from_slice(&(f.kind as u16).to_le_bytes());
        let d = &mut b[TECHNO_DATA_AT..];
        d[0..4].copy_from_slice(&f.number.to_le_bytes());
        let time = i32::try_from(f.process_time_us).unwrap_or(i32::MAX);
        d[4..8].copy_from_slice(&time.to_le_bytes());
        d[8..12].copy_from_slice(&f.block_nr.to_le_bytes());
        d[12..16].copy_from_slice(&f.line.to_le_bytes());
        d[16..20].copy_from_slice(&f.add_value.to_le_bytes());
        d[24..28].copy_from_slice(&f.synch_mode.to_le_bytes());
    }
    out
}

/// `HLI_ERROR_SATZ` for error `code` of channel `ch` (TwinSharp `Structs.cs`,
/// `HLI_ERROR_SATZ_KOPF`, Pack = 1): error_id @0, modul_name @8, cnc_channel @56, time
/// stamp cycle counter @68, version_name @72, body type @100; the body stays empty.
pub(crate) fn error_record(code: u32, ch: u16, tick: u64) -> [u8; ERROR_RECORD_BYTES] {
    let mut r = [0u8; ERROR_RECORD_BYTES];
    r[0..4].copy_from_slice(&code.to_le_bytes());
    put(&mut r[8..24], "ncchannel");
    r[56..58].copy_from_slice(&ch.to_le_bytes());
    r[68..72].copy_from_slice(&(tick as u32).to_le_bytes());
    put(&mut r[72..88], env!("CARGO_PKG_VERSION"));
    r[100..104].copy_from_slice(&BODY_EMPTY.to_le_bytes());
    r
}

fn put(field: &mut [u8], text: &str) {
    let n = text.len().min(field.len() - 1);
    field[..n].copy_from_slice(&text.as_bytes()[..n]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ads::testing;
    use crate::vocab::mode::{Mode, State};
    use std::sync::Arc;

    /// Mode and state of channel 1.
    fn mode_state(b: &dyn CncBackend) -> (Mode, State) {
        let s = b.status(1).unwrap();
        (s.mode, s.state)
    }

    #[test]
    fn names_resolve_case_insensitively_to_stable_handles() {
        let t = testing::channels(1);
        let hli = Hli::new(Arc::clone(&t.backend));
        let name = b"HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state.state_r\0";
        let h = hli.read_write(GROUP_HANDLE_BY_NAME, 0, 4, name).unwrap();
        let lower = name.to_ascii_lowercase();
        assert_eq!(
            hli.read_write(GROUP_HANDLE_BY_NAME, 0, 4, &lower).unwrap(),
            h
        );
        let h = u32::from_le_bytes([h[0], h[1], h[2], h[3]]);
        let v = hli.read(GROUP_VALUE_BY_HANDLE, h, 8).unwrap();
        assert_eq!(v, [2, 0, 0, 0, 3, 0, 0, 0], "AUTOMATIC / READY");
        assert_eq!(
            hli.read_write(GROUP_HANDLE_BY_NAME, 0, 4, b"HLI_Global_Variables.nope"),
            Err(SYMBOL_NOT_FOUND)
        );
        assert_eq!(hli.write(GROUP_RELEASE_HANDLE, 0, &h.to_le_bytes()), Ok(()));
    }

    fn handle_of(hli: &Hli, name: &str) -> u32 {
        let h = hli
            .read_write(GROUP_HANDLE_BY_NAME, 0, 4, name.as_bytes())
            .unwrap();
        u32::from_le_bytes([h[0], h[1], h[2], h[3]])
    }

    #[test]
    fn command_unit_is_taken_when_the_semaphore_is_set_and_cleared() {
        let t = testing::channels(1);
        let b = t.backend.as_ref();
        b.command(1, Op::CommandMode(Mode::Standby as i32)).unwrap();
        let hli = Hli::new(Arc::clone(&t.backend));
        let ms = "HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state";
        let mut cmd = vec![0u8; MODE_TRANSITION_BYTES];
        cmd[8..12].copy_from_slice(&2u32.to_le_bytes());
        cmd[12..16].copy_from_slice(&4u32.to_le_bytes());
        cmd[24..36].copy_from_slice(b"streaming.nc");
        let command = handle_of(&hli, &format!("{ms}.command_w"));
        hli.write(GROUP_VALUE_BY_HANDLE, command, &cmd).unwrap();
        // Written but not handed over: nothing happens.
        assert_eq!(mode_state(b), (Mode::Standby, State::Ready));
        let sem = handle_of(&hli, &format!("{ms}.command_semaphor_rw"));
        hli.write(GROUP_VALUE_BY_HANDLE, sem, &[1]).unwrap();
        assert_eq!(mode_state(b), (Mode::Automatic, State::Active));
        assert_eq!(
            b.status(1).unwrap().program.as_deref(),
            Some("streaming.nc")
        );
        assert_eq!(hli.read(GROUP_VALUE_BY_HANDLE, sem, 1).unwrap(), [0]);
        let state = handle_of(&hli, &format!("{ms}.state_r.state"));
        assert_eq!(
            hli.read(GROUP_VALUE_BY_HANDLE, state, 4).unwrap(),
            [4, 0, 0, 0]
        );
        // A read-only live symbol refuses writes; a too long write is refused.
        assert_eq!(
            hli.write(GROUP_VALUE_BY_HANDLE, state, &[0; 4]),
            Err(AdsResult::ACCESS_DENIED)
        );
        assert_eq!(
            hli.write(GROUP_VALUE_BY_HANDLE, sem, &[1, 0]),
            Err(AdsResult::INVALID_SIZE)
        );
    }

    #[test]
    fn with_enable_w_hmi_commands_become_requests_for_the_plc() {
        let t = testing::channels(1);
        let b = t.backend.as_ref();
        b.command(1, Op::CommandMode(Mode::Standby as i32)).unwrap();
        let hli = Hli::new(Arc::clone(&t.backend));
        assert_eq!(hli.redirect(1, HmiRequest::ToState(4)), None, "no PLC yet");
        let ms = "HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state";
        let enable = handle_of(&hli, &format!("{ms}.enable_w"));
        hli.write(GROUP_VALUE_BY_HANDLE, enable, &[1]).unwrap();
        assert_eq!(hli.redirect(1, HmiRequest::ToMode(2)), Some(Ok(())));
        assert_eq!(hli.redirect(1, HmiRequest::Parameter("a.nc")), Some(Ok(())));
        assert_eq!(hli.redirect(1, HmiRequest::ToState(4)), Some(Ok(())));
        assert_eq!(mode_state(b), (Mode::Standby, State::Ready), "not executed");
        let req = handle_of(&hli, &format!("{ms}.request_r"));
        let r = hli.read(GROUP_VALUE_BY_HANDLE, req, 327).unwrap();
        let word =
            |k: usize| u32::from_le_bytes([r[4 * k], r[4 * k + 1], r[4 * k + 2], r[4 * k + 3]]);
        assert_eq!(
            (word(0), word(1), word(2), word(3), word(4)),
            (1, 3, 2, 4, 1)
        );
        assert_eq!(&r[24..29], b"a.nc\0");
        let sem = handle_of(&hli, &format!("{ms}.request_semaphor_rw"));
        assert_eq!(hli.read(GROUP_VALUE_BY_HANDLE, sem, 1).unwrap(), [1]);
        assert_eq!(
            hli.redirect(1, HmiRequest::ToState(5)),
            Some(Err(AdsResult::BUSY)),
            "the PLC has not taken the last request"
        );
        hli.write(GROUP_VALUE_BY_HANDLE, sem, &[0]).unwrap();
        assert_eq!(hli.redirect(1, HmiRequest::ToState(3)), Some(Ok(())));
    }

    #[test]
    fn errors_are_posted_one_at_a_time() {
        let t = testing::channels(1);
        let b = t.backend.as_ref();
        let hli = Hli::new(Arc::clone(&t.backend));
        let sem = handle_of(&hli, "HLI_Global_Variables.gpCh[0]^.mc_error.semaphor_rw");
        let rec = handle_of(&hli, "HLI_Global_Variables.gpCh[0]^.mc_error.satz_r");
        assert_eq!(
            hli.read(GROUP_VALUE_BY_HANDLE, sem, 1).unwrap(),
            [0],
            "no error yet"
        );
        // A line without CR LF while no program runs: the channel raises error 21476.
        assert_eq!(
            crate::ads::backend::write_stream(b, 1, b"N10 X1\n"),
            AdsResult::INVALID_DATA
        );
        assert_eq!(hli.read(GROUP_VALUE_BY_HANDLE, sem, 1).unwrap(), [1]);
        let r = hli.read(GROUP_VALUE_BY_HANDLE, rec, 942).unwrap();
        assert_eq!(r.len(), ERROR_RECORD_BYTES);
        assert_eq!(&r[0..4], &21476u32.to_le_bytes());
        hli.write(GROUP_VALUE_BY_HANDLE, sem, &[0]).unwrap();
        assert_eq!(
            hli.read(GROUP_VALUE_BY_HANDLE, sem, 1).unwrap(),
            [0],
            "posted once"
        );
    }

    /// Write `command_w` (to mode, to state, parameter) and hand it over.
    fn command(hli: &Hli, to_mode: u32, to_state: u32, parameter: &str) {
        let ms = "HLI_Global_Variables.gpCh[0]^.channel_mc_control.mode_and_state";
        let mut cmd = vec![0u8; MODE_TRANSITION_BYTES];
        cmd[8..12].copy_from_slice(&to_mode.to_le_bytes());
        cmd[12..16].copy_from_slice(&to_state.to_le_bytes());
        cmd[24..24 + parameter.len()].copy_from_slice(parameter.as_bytes());
        let h = handle_of(hli, &format!("{ms}.command_w"));
        hli.write(GROUP_VALUE_BY_HANDLE, h, &cmd).unwrap();
        let sem = handle_of(hli, &format!("{ms}.command_semaphor_rw"));
        hli.write(GROUP_VALUE_BY_HANDLE, sem, &[1]).unwrap();
        assert_eq!(
            hli.read(GROUP_VALUE_BY_HANDLE, sem, 1).unwrap(),
            [0],
            "taken"
        );
    }

    #[test]
    fn refused_commands_post_error_270061_one_at_a_time() {
        let t = testing::channels(1);
        let b = t.backend.as_ref();
        let hli = Hli::new(Arc::clone(&t.backend));
        let err = "HLI_Global_Variables.gpCh[0]^.mc_error";
        let sem = handle_of(&hli, &format!("{err}.semaphor_rw"));
        let id = handle_of(&hli, &format!("{err}.satz_r.kopf.error_id"));
        // MDI with a block: the model has no MDI execution.
        command(
            &hli,
            Mode::Mdi as u32,
            State::Active as u32,
            "G01 X10 F1000",
        );
        assert_eq!(
            mode_state(b),
            (Mode::Automatic, State::Ready),
            "nothing applied"
        );
        assert_eq!(hli.read(GROUP_VALUE_BY_HANDLE, sem, 1).unwrap(), [1]);
        assert_eq!(
            hli.read(GROUP_VALUE_BY_HANDLE, id, 4).unwrap(),
            REFUSED_TRANSITION_ERROR.to_le_bytes()
        );
        // MANUAL/ACTIVE: refused by the channel as a whole (the mode stays); posted after
        // the PLC took the first.
        command(&hli, Mode::Manual as u32, State::Active as u32, "");
        assert_eq!(
            mode_state(b),
            (Mode::Automatic, State::Ready),
            "nothing applied"
        );
        hli.write(GROUP_VALUE_BY_HANDLE, sem, &[0]).unwrap();
        assert_eq!(hli.read(GROUP_VALUE_BY_HANDLE, sem, 1).unwrap(), [1]);
        assert_eq!(
            hli.read(GROUP_VALUE_BY_HANDLE, id, 4).unwrap(),
            REFUSED_TRANSITION_ERROR.to_le_bytes()
        );
        hli.write(GROUP_VALUE_BY_HANDLE, sem, &[0]).unwrap();
        assert_eq!(
            hli.read(GROUP_VALUE_BY_HANDLE, sem, 1).unwrap(),
            [0],
            "no more"
        );
        // An accepted command posts nothing.
        command(&hli, Mode::Automatic as u32, State::Ready as u32, "");
        assert_eq!(hli.read(GROUP_VALUE_BY_HANDLE, sem, 1).unwrap(), [0]);
    }

    #[test]
    fn every_member_symbol_is_where_its_root_type_says() {
        let t = testing::channels(2);
        let hli = Hli::new(Arc::clone(&t.backend));
        let img = hli.image().unwrap();
        let mut roots: HashMap<usize, &Symbol> = HashMap::new();
        for s in img.symbols.iter().filter(|s| s.composite.is_none()) {
            let ty = DataType::lookup(s.ty).unwrap_or_else(|| panic!("type {}", s.ty));
            assert_eq!(ty.size_bytes(), Some(s.size as u32), "{}", s.name);
            assert_eq!(ty.adst(), s.adst, "{}", s.name);
            let Some(root) = roots.get(&s.root) else {
                roots.insert(s.root, s);
                continue;
            };
            let path = &s.name[root.name.len()..];
            let root_ty = DataType::lookup(root.ty).unwrap();
            assert_eq!(
                root_ty.member_at(path),
                Some((s.at as u32, s.size as u32, s.ty)),
                "{}",
                s.name
            );
        }
    }

    #[test]
    fn every_level_between_the_listed_symbols_resolves() {
        let t = testing::channels(2);
        let hli = Hli::new(Arc::clone(&t.backend));
        let p = "HLI_Global_Variables.gpCh[0]^";
        let ms = format!("{p}.channel_mc_control.mode_and_state");
        // Inside a root: the error record's head, a window of it.
        let kopf = handle_of(&hli, &format!("{p}.mc_error.satz_r.kopf"));
        assert_eq!(
            hli.read(GROUP_VALUE_BY_HANDLE, kopf, 1000).unwrap().len(),
            104
        );
        handle_of(&hli, &format!("{p}.mc_error.satz_r.rumpf[837]"));
        handle_of(&hli, &format!("{ms}.command_w.fill_up_2"));
        // Above the roots: the unit's areas back to back (state_r, request_r, enable_w,
        // command_w, request_semaphor_rw, command_semaphor_rw).
        let unit = handle_of(&hli, &ms);
        let bytes = hli.read(GROUP_VALUE_BY_HANDLE, unit, 4096).unwrap();
        assert_eq!(bytes.len(), 8 + 327 + 1 + 327 + 1 + 1);
        assert_eq!(&bytes[0..8], &[2, 0, 0, 0, 3, 0, 0, 0], "state_r first");
        assert_eq!(
            hli.write(GROUP_VALUE_BY_HANDLE, unit, &[0; 20]),
            Err(AdsResult::ACCESS_DENIED),
            "state_r is read-only"
        );
        let info = hli
            .read_write(GROUP_INFO_BY_NAME, 0, 1024, ms.as_bytes())
            .unwrap();
        assert_eq!(&info[20..24], &0x20u32.to_le_bytes(), "read-only flag");
        // A writable level: the activation unit (enable_w, command_w, semaphore).
        let act = handle_of(&hli, &format!("{p}.hb_mc_control.activation"));
        hli.write(GROUP_VALUE_BY_HANDLE, act, &[1, 7]).unwrap();
        let en = handle_of(&hli, &format!("{p}.hb_mc_control.activation.enable_w"));
        let cmd = handle_of(&hli, &format!("{p}.hb_mc_control.activation.command_w"));
        assert_eq!(hli.read(GROUP_VALUE_BY_HANDLE, en, 1).unwrap(), [1]);
        assert_eq!(hli.read(GROUP_VALUE_BY_HANDLE, cmd, 1).unwrap(), [7]);
        for name in [p, "HLI_Global_Variables", "hli_global_constants"] {
            assert!(hli.symbol_by_name(name.as_bytes()).is_ok(), "{name}");
        }
        for name in ["HLI_Global_Variables.gpCh", "HLI_Global_Variables.gpCh[0]"] {
            assert_eq!(
                hli.symbol_by_name(name.as_bytes()),
                Err(SYMBOL_NOT_FOUND),
                "{name}: pointers are not served"
            );
        }
        // The listed symbols keep their handles; the levels are not in the object map.
        let img = hli.image().unwrap();
        assert_eq!(
            handle_of(&hli, &format!("{ms}.state_r")),
            3,
            "after the constants"
        );
        assert_eq!(hli.objects().unwrap().len(), img.listed);
    }

    #[test]
    fn uploads_agree_with_their_upload_info() {
        let t = testing::channels(1);
        let hli = Hli::new(Arc::clone(&t.backend));
        let info = hli.read(GROUP_UPLOAD_INFO2, 0, 64).unwrap();
        assert_eq!(info.len(), 64, "upload info 3");
        assert_eq!(
            hli.read(GROUP_UPLOAD_INFO2, 0, 24).unwrap(),
            info[..24],
            "upload info 2"
        );
        let w = |k: usize| {
            u32::from_le_bytes([
                info[4 * k],
                info[4 * k + 1],
                info[4 * k + 2],
                info[4 * k + 3],
            ])
        };
        let syms = hli.read(GROUP_SYMBOL_UPLOAD, 0, w(1)).unwrap();
        assert_eq!(syms.len() as u32, w(1));
        let mut at = 0;
        let mut count = 0;
        while at < syms.len() {
            at += u32::from_le_bytes([syms[at], syms[at + 1], syms[at + 2], syms[at + 3]]) as usize;
            count += 1;
        }
        assert_eq!((at, count), (syms.len(), w(0)));
        let types = hli.read(GROUP_TYPE_UPLOAD, 0, w(3)).unwrap();
        assert_eq!(types.len() as u32, w(3));
        assert_eq!(
            hli.read(GROUP_SYMBOL_UPLOAD, 0, w(1) - 1),
            Err(AdsResult::INVALID_SIZE)
        );
        let by_name = hli
            .read_write(
                GROUP_TYPE_BY_NAME,
                0,
                u32::MAX,
                b"HLI_PROC_TRANS_TO_MODE_STATE\0",
            )
            .unwrap();
        assert_eq!(&by_name[16..20], &327u32.to_le_bytes());
        assert_eq!(
            hli.read_write(GROUP_TYPE_BY_NAME, 0, u32::MAX, b"NO_SUCH_TYPE\0"),
            Err(SYMBOL_NOT_FOUND)
        );
    }

    #[test]
    fn units_encode_as_techno_unit_ch_with_hli_m_h_prozess() {
        use crate::channel::techno::UnitFunction;
        use crate::vocab::techno::{SyncType, TechnoKind};
        let f = |kind, number, add_value| UnitFunction {
            seq: 0,
            kind,
            number,
            process_time_us: 1500,
            block_nr: 20,
            line: 2,
            add_value,
            synch_mode: 2,
            sync: SyncType::MvsSvs,
            output_at: std::time::Duration::ZERO,
            waited: true,
        };
        let units = [
            TechnoUnit {
                please: true,
                done: false,
                function: Some(f(TechnoKind::M, 200, 1200)),
            },
            TechnoUnit {
                please: false,
                done: true,
                function: Some(f(TechnoKind::S, 1000, 1000)),
            },
            TechnoUnit::default(),
        ];
        let b = encode_units(&units, TECHNO_UNITS);
        assert_eq!(b.len(), 940);
        let word = |at: usize| u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]);
        assert_eq!(&b[0..4], &[1, 0, 1, 0], "please, done, type M");
        assert_eq!(
            (word(8), word(12), word(16), word(20), word(24), word(32)),
            (200, 1500, 20, 2, 1200, 2),
            "nr, time µs, block_nr, prg_line, add_value, synch_mode"
        );
        assert!(b[36..47].iter().all(|&x| x == 0));
        let s = &b[47..94];
        assert_eq!(&s[0..4], &[0, 1, 3, 0], "done, type S");
        assert_eq!(&s[8..12], &1000u32.to_le_bytes(), "S: the speed in nr");
        assert_eq!(&s[24..28], &1000i32.to_le_bytes(), "and in add_value");
        assert!(b[94..].iter().all(|&x| x == 0), "never filled: zero");
    }

    #[test]
    fn record_is_942_bytes_with_the_error_id_first() {
        let r = error_record(21476, 1, 5);
        assert_eq!(r.len(), 942);
        assert_eq!(&r[0..4], &21476u32.to_le_bytes());
        assert_eq!(&r[100..104], &9u32.to_le_bytes());
    }
}
