//! Technology functions (M, H, S, T): what the channel list configures for them, what the
//! decoder attaches to a block, what the planner places around its motion and what the
//! channel hands to the PLC through the HLI's technology units (TF5200 "M and H functions",
//! "Synchronisation types"; TF5200 HLI "Technology functions").

use std::fmt;

/// Which kind of technology function; the number is the HLI unit's `type` field
/// (`TECHNO_UNIT_CH.type`: 1 M, 2 H, 3 S, 4 T).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TechnoKind {
    M = 1,
    H = 2,
    S = 3,
    T = 4,
}

impl TechnoKind {
    /// The letter as programmed.
    pub fn letter(self) -> char {
        match self {
            TechnoKind::M => 'M',
            TechnoKind::H => 'H',
            TechnoKind::S => 'S',
            TechnoKind::T => 'T',
        }
    }
}

/// When a function is output to the PLC and when the channel waits for its acknowledgement
/// (TF5200 "Parameterisation of synchronisation types", P-CHAN-00041 `m_synch`; the values
/// of MEP_SVS and MET_SVS from the TwinCAT CNC channel parameter page "Synchronization types
/// MET_SVS, MEP_SVS", `m_synch[96] 0x01000000 MEP_SVS`). The modifier `PLC_INFO` (0x20000,
/// spindle functions: also tell the PLC) is kept apart in [`SyncSpec`]. The kernel's other
/// types (MNE_SNS, MOS_TS, MEP_MOS, MET_MOS, BWD_SYNCH, FWD_SYNCH, FAW_SYNCH) are not
/// modelled: a channel list that uses one is refused at start-up, naming it
/// ([`UNMODELLED_SYNC`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "SCREAMING_SNAKE_CASE")]
pub enum SyncType {
    /// 0x0: not output to the PLC.
    NoSynch,
    /// 0x1: output without synchronisation (before the motion of a motion block).
    Mos,
    /// 0x2: output before the motion block; the motion starts after the acknowledgement.
    MvsSvs,
    /// 0x4: output before the motion block; synchronisation at the block end.
    MvsSns,
    /// 0x8: output after the motion of the block; synchronisation then.
    MnsSns,
    /// 0x4000: output before the motion block; late synchronisation before the next feed
    /// motion block (G01/G02/G03), through the late-sync units `techno_unit_late_sync`.
    MvsSlm,
    /// 0x8000: output before the motion block; late synchronisation at the next `#EXPL SYN`.
    MvsSlp,
    /// 0x1000000: output a path distance (`m_pre_outp`, 0.1 µm) before the synchronisation
    /// point at the start of the motion block; synchronisation there.
    MepSvs,
    /// 0x2000000: output a time (`m_pre_outp`, µs) before the synchronisation point at the
    /// start of the motion block; synchronisation there.
    MetSvs,
}

impl SyncType {
    /// The kernel's symbols and values, in its table's order.
    pub const ALL: [(SyncType, &'static str, u32); 9] = [
        (SyncType::NoSynch, "NO_SYNCH", 0x0),
        (SyncType::Mos, "MOS", 0x1),
        (SyncType::MvsSvs, "MVS_SVS", 0x2),
        (SyncType::MvsSns, "MVS_SNS", 0x4),
        (SyncType::MnsSns, "MNS_SNS", 0x8),
        (SyncType::MvsSlm, "MVS_SLM", 0x4000),
        (SyncType::MvsSlp, "MVS_SLP", 0x8000),
        (SyncType::MepSvs, "MEP_SVS", 0x0100_0000),
        (SyncType::MetSvs, "MET_SVS", 0x0200_0000),
    ];

    /// The kernel's value (`synch_mode` in `HLI_M_H_PROZESS`).
    pub fn value(self) -> u32 {
        SyncType::ALL
            .iter()
            .find(|(t, _, _)| *t == self)
            .map_or(0, |(_, _, v)| *v)
    }

    pub fn name(self) -> &'static str {
        SyncType::ALL
            .iter()
            .find(|(t, _, _)| *t == self)
            .map_or("NO_SYNCH", |(_, n, _)| *n)
    }

    pub fn from_value(v: u32) -> Option<SyncType> {
        SyncType::ALL
            .iter()
            .find(|(_, _, x)| *x == v)
            .map(|(t, _, _)| *t)
    }

    /// Output before the block's motion (else after it).
    pub fn outputs_before_motion(self) -> bool {
        !matches!(self, SyncType::MnsSns)
    }

    /// The channel waits for the acknowledgement before the block's motion starts.
    pub fn waits_before_motion(self) -> bool {
        matches!(self, SyncType::MvsSvs | SyncType::MepSvs | SyncType::MetSvs)
    }

    /// The channel waits for the acknowledgement at the end of the block (after its motion).
    pub fn waits_after_motion(self) -> bool {
        matches!(self, SyncType::MvsSns | SyncType::MnsSns)
    }

    /// Synchronised later (the late-sync units): MVS_SLM before the next feed block, MVS_SLP
    /// at `#EXPL SYN`.
    pub fn is_late(self) -> bool {
        matches!(self, SyncType::MvsSlm | SyncType::MvsSlp)
    }
}

impl fmt::Display for SyncType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The kernel's synchronisation types ncchannel does not model, by name (and value where the
/// pages give one): refused at start-up rather than treated as another type.
pub const UNMODELLED_SYNC: [(&str, Option<u32>); 7] = [
    ("MNE_SNS", Some(0x20)),
    ("MOS_TS", None),
    ("MEP_MOS", None),
    ("MET_MOS", None),
    ("BWD_SYNCH", None),
    ("FWD_SYNCH", None),
    ("FAW_SYNCH", None),
];

/// `PLC_INFO`: the function is also reported to the PLC (spindle M functions).
pub const PLC_INFO: u32 = 0x20000;

/// A configured synchronisation: the type and whether `PLC_INFO` was given with it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SyncSpec {
    pub sync: SyncType,
    pub plc_info: bool,
}

impl SyncSpec {
    pub const NONE: SyncSpec = SyncSpec {
        sync: SyncType::NoSynch,
        plc_info: false,
    };

    /// The value as the kernel writes it (type | `PLC_INFO`).
    pub fn value(self) -> u32 {
        self.sync.value() | if self.plc_info { PLC_INFO } else { 0 }
    }

    /// Is the function handed to the PLC at all? `NO_SYNCH` alone is not; `PLC_INFO |
    /// NO_SYNCH` is reported without a wait.
    pub fn outputs(self) -> bool {
        self.sync != SyncType::NoSynch || self.plc_info
    }

    /// The type the timing follows: `PLC_INFO | NO_SYNCH` is output like MOS.
    pub fn timing(self) -> SyncType {
        if self.sync == SyncType::NoSynch && self.plc_info {
            SyncType::Mos
        } else {
            self.sync
        }
    }
}

/// What the channel list says of one function number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FunctionDef {
    pub sync: SyncSpec,
    /// P-CHAN-00040 / P-CHAN-00026: the expected execution time, µs; without a PLC the
    /// channel acknowledges its own unit after it.
    pub process_time_us: u32,
    /// P-CHAN-00070 `m_pre_outp`: for MEP_SVS a path distance in 0.1 µm, for MET_SVS a time
    /// in µs.
    pub pre_output: u32,
}

impl FunctionDef {
    pub const fn new(sync: SyncSpec) -> FunctionDef {
        FunctionDef {
            sync,
            process_time_us: 0,
            pre_output: 0,
        }
    }
}

/// The technology configuration of a channel, read from its channel list.
#[derive(Debug, Clone, PartialEq)]
pub struct TechnoTable {
    /// M functions by number, sorted by number.
    pub m: Vec<(u32, FunctionDef)>,
    /// H functions by number, sorted by number.
    pub h: Vec<(u32, FunctionDef)>,
    /// The spindle's S word (P-CHAN-00081 `spindel[0].s_synch`, its process time).
    pub s: FunctionDef,
    /// The spindle's M3 / M4 / M5 / M19 (P-CHAN-00045 … `spindel[0].m3_synch` …).
    pub spindle_m: [(u32, FunctionDef); 4],
    /// The tool's T word (P-CHAN-00086 `tool.synch`, P-CHAN-00072 `tool.prozess_zeit`).
    pub t: FunctionDef,
}

/// The M functions the kernel knows itself; without an entry in the channel list they are
/// NO_SYNCH (P-CHAN-00041, note on internal M functions).
pub const INTERNAL_M: [u32; 9] = [0, 1, 2, 17, 29, 30, 3, 4, 19];

impl Default for TechnoTable {
    fn default() -> TechnoTable {
        TechnoTable::kernel_defaults()
    }
}

impl TechnoTable {
    /// The table of a channel list that configures nothing: the internal M functions as
    /// NO_SYNCH, S and T not output.
    pub fn kernel_defaults() -> TechnoTable {
        let none = FunctionDef::new(SyncSpec::NONE);
        TechnoTable {
            m: Vec::new(),
            h: Vec::new(),
            s: none,
            spindle_m: [(3, none), (4, none), (5, none), (19, none)],
            t: none,
        }
    }

    /// The definition of M `n`: the channel list's, a spindle M's, or an internal M's
    /// default; `None` = not defined (the kernel's 20157).
    pub fn m_def(&self, n: u32) -> Option<FunctionDef> {
        if let Some((_, d)) = self.spindle_m.iter().find(|(m, _)| *m == n) {
            return Some(*d);
        }
        if let Ok(i) = self.m.binary_search_by_key(&n, |(k, _)| *k) {
            return Some(self.m[i].1);
        }
        INTERNAL_M
            .contains(&n)
            .then_some(FunctionDef::new(SyncSpec::NONE))
    }

    /// The definition of H `n`; `None` = not defined (the kernel's 20162).
    pub fn h_def(&self, n: u32) -> Option<FunctionDef> {
        self.h
            .binary_search_by_key(&n, |(k, _)| *k)
            .ok()
            .map(|i| self.h[i].1)
    }

    /// Change M `n`'s synchronisation (`V.G.M_FCT[n].SYNCH`); defines it if it was not.
    pub fn set_m_sync(&mut self, n: u32, sync: SyncSpec) {
        if let Some((_, d)) = self.spindle_m.iter_mut().find(|(m, _)| *m == n) {
            d.sync = sync;
            return;
        }
        set_sync(&mut self.m, n, sync);
    }

    /// Change H `n`'s synchronisation (`V.G.H_FCT[n].SYNCH`).
    pub fn set_h_sync(&mut self, n: u32, sync: SyncSpec) {
        set_sync(&mut self.h, n, sync);
    }
}

fn set_sync(table: &mut Vec<(u32, FunctionDef)>, n: u32, sync: SyncSpec) {
    match table.binary_search_by_key(&n, |(k, _)| *k) {
        Ok(i) => table[i].1.sync = sync,
        Err(i) => table.insert(i, (n, FunctionDef::new(sync))),
    }
}

/// Sequence number of a technology function in its channel: given by the decoder in program
/// order, so output order is sequence order.
pub type TechnoSeq = u64;

/// One technology function as the decoder found it in a block, with its configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct TechnoFn {
    pub seq: TechnoSeq,
    pub kind: TechnoKind,
    /// M/H number; S: the spindle speed in rpm (rounded); T: the tool number.
    pub number: u32,
    /// `M200=1200`: the additional value; S: the programmed speed.
    pub value: Option<f64>,
    pub def: FunctionDef,
}

/// The functions a block hands to the PLC at one point of its execution, with the block's
/// data the unit shows.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputGroup {
    pub fns: Vec<TechnoFn>,
    /// The block's N number (0 = none).
    pub block_nr: u32,
    /// Its line in its program, 1-based.
    pub line: u32,
}

/// Which acknowledgements a part that waits can see (the channel's technology units answer;
/// the interpolator asks at a wait entry).
pub trait Acknowledgements {
    /// Has function `seq` been acknowledged (or was it never waited for)?
    fn is_acknowledged(&self, seq: TechnoSeq) -> bool;

    /// Is every function output so far finished (nothing waits to be output either)? The
    /// program end waits for it: no function is left behind in a unit.
    fn all_acknowledged(&self) -> bool;
}

/// No technology units: every wait passes at once. For a motion driven without a channel
/// (the motion benches and tests), where no function is ever output.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoUnits;

impl Acknowledgements for NoUnits {
    fn is_acknowledged(&self, _seq: TechnoSeq) -> bool {
        true
    }

    fn all_acknowledged(&self) -> bool {
        true
    }
}
