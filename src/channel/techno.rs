//! The channel's PLC half: the HLI technology units through which M, H, S and T functions go
//! to the PLC and come back acknowledged (TF5200 HLI "Technology functions", "Data of the M/H
//! function"; the PLC's side of the handshake as `kimblad/TwinSharp`
//! `TwinSharp/CNC/TechnologyProcesses.cs` runs it).
//!
//! The handshake, per unit: the channel fills the unit and sets `please_rw`; the PLC reads it
//! and may write `please_rw` FALSE (fetched); it acknowledges by writing `done_w` TRUE. A
//! function is finished when `done_w` is TRUE, or, for one that is not waited for (MOS,
//! `PLC_INFO | NO_SYNCH`), once fetched. The standard units hold one output group (the
//! functions a block outputs at one point) at a time, `used_units_std_sync_r` of them; the next
//! group is output when every unit of the last one is finished. Late-synchronised functions
//! (MVS_SLM, MVS_SLP) take a late unit each and are waited for later.
//!
//! Without a PLC (no client has set `plc_present_w`), the channel finishes its own units once
//! the function's process time (P-CHAN-00040 / -00026, µs) has passed in channel time (TF5200
//! HLI "Operation with and without PLC"; the kernelV DLL's execution time simulation does the
//! same with the same parameters).

use std::collections::VecDeque;
use std::time::Duration;

use crate::vocab::techno::{
    Acknowledgements, OutputGroup, SyncType, TechnoFn, TechnoKind, TechnoSeq,
};

/// Standard-synchronisation units per channel (`techno_unit_std_sync[0..19]`,
/// `HLI_TU_CH_STD_SYNC_MAXIDX` = 19).
pub const STD_SYNC_UNITS: usize = 20;
/// Late-synchronisation units per channel (`techno_unit_late_sync[0..9]`, from the GEO
/// mirror's `techno.late_sync[0..9]`).
pub const LATE_SYNC_UNITS: usize = 10;
/// Output groups waiting for the standard units: the lookahead window bounds how many blocks
/// can have passed their output point, this bounds it again.
const MAX_PENDING: usize = 1024;

/// One unit as the HLI shows it.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Unit {
    pub please: bool,
    pub done: bool,
    /// The function it holds (kept after it finished, as the HLI memory keeps it, until the
    /// unit is filled again).
    pub function: Option<UnitFunction>,
}

/// The payload of a unit (`HLI_M_H_PROZESS` for M and H; S and T carry their number and value
/// in the same places).
#[derive(Debug, Clone, PartialEq)]
pub struct UnitFunction {
    pub seq: TechnoSeq,
    pub kind: TechnoKind,
    pub number: u32,
    /// The expected execution time, µs (`time`).
    pub process_time_us: u32,
    pub block_nr: u32,
    pub line: u32,
    /// `M200=1200`: 1200; S: the speed in rpm (`add_value`, rounded).
    pub add_value: i32,
    /// The synchronisation value (`synch_mode`).
    pub synch_mode: u32,
    pub sync: SyncType,
    /// Channel time it was output.
    pub output_at: Duration,
    /// The function waits for `done_w` (else fetching finishes it).
    pub waited: bool,
}

/// What a client writes into the technology interface.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TechnoWrite {
    /// `head.plc_present_w`.
    PlcPresent(bool),
    /// `techno_unit_std_sync[unit].please_rw` / `techno_unit_late_sync[unit].please_rw`.
    Please {
        set: UnitSet,
        unit: usize,
        value: bool,
    },
    /// `…[unit].done_w`.
    Done {
        set: UnitSet,
        unit: usize,
        value: bool,
    },
}

/// Which array of units.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnitSet {
    Std,
    Late,
}

/// A write the interface does not take: it changes nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum TechnoRefusal {
    #[error("technology unit {0} does not exist")]
    NoSuchUnit(usize),
}

/// What happened in the units, for the channel's log.
#[derive(Debug, Clone, PartialEq)]
pub enum TechnoNote {
    Output {
        unit: usize,
        set: UnitSet,
        function: UnitFunction,
    },
    Acknowledged {
        function: UnitFunction,
        at: Duration,
    },
}

/// Counters for the report.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TechnoStats {
    pub output: u64,
    pub acknowledged: u64,
    /// Functions dropped by a reset while output or waiting to be.
    pub dropped_by_reset: u64,
    /// Channel time from output to acknowledgement, summed over the acknowledged functions.
    pub waited: Duration,
}

/// A snapshot of the interface for clients.
#[derive(Debug, Clone, PartialEq)]
pub struct TechnoStatus {
    pub plc_present: bool,
    pub used_std: u16,
    pub used_late: u16,
    pub std: Vec<Unit>,
    pub late: Vec<Unit>,
}

/// What [`TechnoUnits`] records for a checker while observed (`Op::ObserveTechno`), in the
/// order it happened: every function's way through the units, and each block start that had
/// functions waiting before it (MVS_SVS).
#[derive(Debug, Clone, PartialEq)]
pub enum TechnoSeen {
    /// The function went into a unit at channel time `at`.
    Output {
        seq: TechnoSeq,
        kind: TechnoKind,
        number: u32,
        sync: SyncType,
        at: Duration,
    },
    /// The function was finished (acknowledged, or fetched when not waited for).
    Acknowledged { seq: TechnoSeq, at: Duration },
    /// A reset or an error dropped it, output or not yet.
    Dropped { seq: TechnoSeq },
    /// A block took effect, the first after these functions that must be acknowledged before
    /// the motion (`waits_before_motion`) were handed to the units.
    BlockStarted {
        at: Duration,
        waited: Vec<TechnoSeq>,
    },
}

/// Observations kept between two drains at most; more are counted as lost.
const MAX_SEEN: usize = 1 << 16;

/// The observation record (off: `None`, one comparison per output, finish and block start).
#[derive(Debug, Default)]
struct Observation {
    seen: Vec<TechnoSeen>,
    lost: u64,
    /// Functions waited for before the motion, handed over since the last block start.
    before_motion: Vec<TechnoSeq>,
}

impl Observation {
    fn push(&mut self, s: TechnoSeen) {
        if self.seen.len() < MAX_SEEN {
            self.seen.push(s);
        } else {
            self.lost += 1;
        }
    }
}

/// The units and everything waiting for them.
#[derive(Debug)]
pub struct TechnoUnits {
    plc_present: bool,
    std: Vec<Unit>,
    used_std: usize,
    late: Vec<Unit>,
    /// Groups waiting for the standard units, in output order.
    pending: VecDeque<OutputGroup>,
    /// Late functions waiting for a free late unit.
    pending_late: VecDeque<(TechnoFn, u32, u32)>,
    /// Functions output or pending and not finished: what a wait asks about.
    open: Vec<TechnoSeq>,
    /// One past the highest sequence number handed to [`TechnoUnits::output`]: a wait may be
    /// reached before its output is (both in one tick); a function not yet output is not
    /// acknowledged.
    next_seq: TechnoSeq,
    stats: TechnoStats,
    notes: Vec<TechnoNote>,
    observation: Option<Box<Observation>>,
}

impl Default for TechnoUnits {
    fn default() -> Self {
        TechnoUnits::new()
    }
}

impl TechnoUnits {
    pub fn new() -> TechnoUnits {
        TechnoUnits {
            plc_present: false,
            std: vec![Unit::default(); STD_SYNC_UNITS],
            used_std: 0,
            late: vec![Unit::default(); LATE_SYNC_UNITS],
            pending: VecDeque::new(),
            pending_late: VecDeque::new(),
            open: Vec::new(),
            next_seq: 0,
            stats: TechnoStats::default(),
            notes: Vec::new(),
            observation: None,
        }
    }

    pub fn stats(&self) -> TechnoStats {
        self.stats
    }

    pub fn plc_present(&self) -> bool {
        self.plc_present
    }

    /// Nothing output and nothing waiting: the common case, one comparison per tick.
    #[inline]
    pub fn idle(&self) -> bool {
        self.open.is_empty()
    }

    /// The units that hold an open function (output, not finished): set, index, the
    /// function and whether `please_rw` is still set. What a PLC polls.
    pub fn open_units(&self) -> impl Iterator<Item = (UnitSet, usize, &UnitFunction, bool)> {
        let std = self.std[..self.used_std]
            .iter()
            .enumerate()
            .map(|(k, u)| (UnitSet::Std, k, u));
        let late = self
            .late
            .iter()
            .enumerate()
            .map(|(k, u)| (UnitSet::Late, k, u));
        std.chain(late).filter_map(|(set, k, u)| {
            let f = u.function.as_ref()?;
            self.open.contains(&f.seq).then_some((set, k, f, u.please))
        })
    }

    /// Is function `seq` output or waiting to be, and not finished?
    pub fn is_open(&self, seq: TechnoSeq) -> bool {
        self.open.contains(&seq)
    }

    /// Record [`TechnoSeen`] observations (on) or stop and forget them (off).
    pub fn observe(&mut self, on: bool) {
        self.observation = on.then(Box::default);
    }

    /// Is the record on?
    #[inline]
    pub fn observing(&self) -> bool {
        self.observation.is_some()
    }

    /// Whether [`TechnoUnits::drain_seen`] has anything to hand over.
    pub fn seen_pending(&self) -> bool {
        self.observation
            .as_ref()
            .is_some_and(|o| !o.seen.is_empty() || o.lost > 0)
    }

    /// The observations since the last drain, and how many did not fit.
    pub fn drain_seen(&mut self) -> (Vec<TechnoSeen>, u64) {
        match &mut self.observation {
            Some(o) => (std::mem::take(&mut o.seen), std::mem::take(&mut o.lost)),
            None => (Vec::new(), 0),
        }
    }

    /// A block took effect at `now` (observed channels only).
    pub fn block_started(&mut self, now: Duration) {
        if let Some(o) = &mut self.observation {
            if !o.before_motion.is_empty() {
                let waited = std::mem::take(&mut o.before_motion);
                o.push(TechnoSeen::BlockStarted { at: now, waited });
            }
        }
    }

    pub fn status(&self) -> TechnoStatus {
        TechnoStatus {
            plc_present: self.plc_present,
            used_std: self.used_std as u16,
            used_late: self
                .late
                .iter()
                .filter(|u| u.please || self.is_busy(u))
                .count() as u16,
            std: self.std.clone(),
            late: self.late.clone(),
        }
    }

    /// Does `u` hold a function that is output and not yet finished?
    fn is_busy(&self, u: &Unit) -> bool {
        u.function
            .as_ref()
            .is_some_and(|f| self.open.contains(&f.seq))
    }

    /// Hand a group to the PLC: into the standard units if they are free, else behind the
    /// groups already waiting. Late functions take a late unit each.
    pub fn output(&mut self, group: OutputGroup, now: Duration) {
        if let Some(last) = group.fns.iter().map(|f| f.seq).max() {
            self.next_seq = self.next_seq.max(last + 1);
        }
        if let Some(o) = &mut self.observation {
            for f in &group.fns {
                if f.def.sync.timing().waits_before_motion() {
                    o.before_motion.push(f.seq);
                }
            }
        }
        let (late, std): (Vec<TechnoFn>, Vec<TechnoFn>) = group
            .fns
            .into_iter()
            .partition(|f| f.def.sync.timing().is_late());
        for f in late {
            self.open.push(f.seq);
            self.pending_late.push_back((f, group.block_nr, group.line));
        }
        if !std.is_empty() {
            for f in &std {
                self.open.push(f.seq);
            }
            if self.pending.len() < MAX_PENDING {
                self.pending.push_back(OutputGroup {
                    fns: std,
                    block_nr: group.block_nr,
                    line: group.line,
                });
            }
        }
        self.fill(now);
    }

    /// The tick's share, before the motion runs: without a PLC finish what has had its
    /// process time; finish the fetched and acknowledged units; output what waits.
    pub fn tick(&mut self, now: Duration) {
        if self.open.is_empty() {
            return;
        }
        if !self.plc_present {
            for u in self.std.iter_mut().chain(self.late.iter_mut()) {
                if let Some(f) = &u.function {
                    let due = f.output_at + Duration::from_micros(u64::from(f.process_time_us));
                    if u.please && due <= now {
                        u.please = false;
                        u.done = true;
                    }
                }
            }
        }
        self.finish(now);
        self.fill(now);
    }

    /// A client's write. Writes that would not change the handshake (a `done_w` on a unit
    /// that holds no open function, `please_rw` TRUE from the PLC side) are taken and
    /// ignored, as the kernel overwrites them at the next output; a unit that does not exist
    /// is refused.
    pub fn write(&mut self, w: TechnoWrite) -> Result<(), TechnoRefusal> {
        let (set, unit) = match w {
            TechnoWrite::PlcPresent(v) => {
                self.plc_present = v;
                return Ok(());
            }
            TechnoWrite::Please { set, unit, .. } | TechnoWrite::Done { set, unit, .. } => {
                (set, unit)
            }
        };
        let u = match set {
            UnitSet::Std => self.std.get(unit),
            UnitSet::Late => self.late.get(unit),
        }
        .ok_or(TechnoRefusal::NoSuchUnit(unit))?;
        if !self.is_busy(u) {
            return Ok(());
        }
        let u = match set {
            UnitSet::Std => &mut self.std[unit],
            UnitSet::Late => &mut self.late[unit],
        };
        match w {
            TechnoWrite::Please { value: false, .. } => u.please = false,
            TechnoWrite::Done { value, .. } => u.done = value,
            _ => {}
        }
        Ok(())
    }

    /// The channel was reset: what was output or waiting is dropped (the reset the operator
    /// commanded); the units are cleared for the next program. `plc_present` stays.
    pub fn reset(&mut self) {
        self.stats.dropped_by_reset += self.open.len() as u64;
        if let Some(o) = &mut self.observation {
            o.before_motion.clear();
            for &seq in &self.open {
                o.push(TechnoSeen::Dropped { seq });
            }
        }
        self.open.clear();
        self.pending.clear();
        self.pending_late.clear();
        for u in self.std.iter_mut().chain(self.late.iter_mut()) {
            u.please = false;
            u.done = false;
        }
        self.used_std = 0;
    }

    /// The notes since the last call, for the log.
    pub fn drain_notes(&mut self) -> std::vec::Drain<'_, TechnoNote> {
        self.notes.drain(..)
    }

    /// Step: units whose function is finished give it up.
    fn finish(&mut self, now: Duration) {
        let mut waited = Duration::ZERO;
        let mut observation = self.observation.as_deref_mut();
        let mut finished =
            |u: &mut Unit, open: &mut Vec<TechnoSeq>, notes: &mut Vec<TechnoNote>| {
                let Some(f) = &u.function else { return false };
                if !open.contains(&f.seq) {
                    return false;
                }
                let fetched = !u.please;
                let done = u.done || (!f.waited && fetched);
                if !done {
                    return false;
                }
                u.please = false;
                open.retain(|s| *s != f.seq);
                waited += now.saturating_sub(f.output_at);
                if let Some(o) = observation.as_deref_mut() {
                    o.push(TechnoSeen::Acknowledged {
                        seq: f.seq,
                        at: now,
                    });
                }
                notes.push(TechnoNote::Acknowledged {
                    function: f.clone(),
                    at: now,
                });
                true
            };
        let mut acked = 0u64;
        for u in &mut self.late {
            if finished(u, &mut self.open, &mut self.notes) {
                acked += 1;
            }
        }
        for u in &mut self.std[..self.used_std] {
            if finished(u, &mut self.open, &mut self.notes) {
                acked += 1;
            }
        }
        self.stats.acknowledged += acked;
        self.stats.waited += waited;
        let std_busy = self.std[..self.used_std].iter().any(|u| self.is_busy(u));
        if !std_busy && self.used_std > 0 {
            for u in &mut self.std[..self.used_std] {
                u.done = false;
            }
            self.used_std = 0;
        }
    }

    /// Step: output the next waiting group into free standard units, late functions into free
    /// late units.
    fn fill(&mut self, now: Duration) {
        if self.used_std == 0 {
            if let Some(g) = self.pending.pop_front() {
                let n = g.fns.len().min(STD_SYNC_UNITS);
                for (k, f) in g.fns.into_iter().take(n).enumerate() {
                    self.put(UnitSet::Std, k, unit_function(f, g.block_nr, g.line, now));
                }
                self.used_std = n;
            }
        }
        while !self.pending_late.is_empty() {
            let Some(k) = self.late.iter().position(|u| !self.is_busy(u)) else {
                break;
            };
            let Some((f, block_nr, line)) = self.pending_late.pop_front() else {
                break;
            };
            self.put(UnitSet::Late, k, unit_function(f, block_nr, line, now));
        }
    }

    /// Output one function into unit `k` of `set`: `please_rw` TRUE, counted, observed, noted.
    fn put(&mut self, set: UnitSet, k: usize, function: UnitFunction) {
        let units = match set {
            UnitSet::Std => &mut self.std,
            UnitSet::Late => &mut self.late,
        };
        units[k] = Unit {
            please: true,
            done: false,
            function: Some(function.clone()),
        };
        self.stats.output += 1;
        if let Some(o) = &mut self.observation {
            o.push(seen_output(&function));
        }
        self.notes.push(TechnoNote::Output {
            unit: k,
            set,
            function,
        });
    }
}

fn seen_output(f: &UnitFunction) -> TechnoSeen {
    TechnoSeen::Output {
        seq: f.seq,
        kind: f.kind,
        number: f.number,
        sync: f.sync,
        at: f.output_at,
    }
}

fn unit_function(f: TechnoFn, block_nr: u32, line: u32, now: Duration) -> UnitFunction {
    let timing = f.def.sync.timing();
    UnitFunction {
        seq: f.seq,
        kind: f.kind,
        number: f.number,
        process_time_us: f.def.process_time_us,
        block_nr,
        line,
        add_value: f.value.map_or(0, |v| {
            v.round().clamp(i32::MIN as f64, i32::MAX as f64) as i32
        }),
        synch_mode: f.def.sync.value(),
        sync: timing,
        output_at: now,
        waited: timing != SyncType::Mos,
    }
}

impl Acknowledgements for TechnoUnits {
    #[inline]
    fn is_acknowledged(&self, seq: TechnoSeq) -> bool {
        seq < self.next_seq && !self.open.contains(&seq)
    }

    #[inline]
    fn all_acknowledged(&self) -> bool {
        self.open.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::techno::{FunctionDef, SyncSpec};

    fn m25(seq: TechnoSeq) -> OutputGroup {
        OutputGroup {
            fns: vec![TechnoFn {
                seq,
                kind: TechnoKind::M,
                number: 25,
                value: None,
                def: FunctionDef::new(SyncSpec {
                    sync: SyncType::MvsSvs,
                    plc_info: false,
                }),
            }],
            block_nr: 40,
            line: 3,
        }
    }

    #[test]
    fn a_plcs_writes_that_would_not_change_the_handshake_change_nothing() {
        let mut u = TechnoUnits::new();
        u.write(TechnoWrite::PlcPresent(true)).unwrap();
        // Nothing waits: done_w and please_rw TRUE are taken and change nothing.
        let free = u.status();
        u.write(TechnoWrite::Done {
            set: UnitSet::Std,
            unit: 0,
            value: true,
        })
        .unwrap();
        u.write(TechnoWrite::Please {
            set: UnitSet::Std,
            unit: 3,
            value: true,
        })
        .unwrap();
        assert_eq!(u.status(), free);
        assert_eq!(
            u.write(TechnoWrite::Done {
                set: UnitSet::Late,
                unit: 10,
                value: true
            }),
            Err(TechnoRefusal::NoSuchUnit(10))
        );
        // M25 waits: a please_rw TRUE from the PLC does not ask again, a FALSE fetches, and
        // only done_w acknowledges.
        u.output(m25(0), Duration::ZERO);
        u.write(TechnoWrite::Please {
            set: UnitSet::Std,
            unit: 0,
            value: true,
        })
        .unwrap();
        u.write(TechnoWrite::Please {
            set: UnitSet::Std,
            unit: 0,
            value: false,
        })
        .unwrap();
        u.tick(Duration::from_millis(1));
        assert!(!u.is_acknowledged(0), "fetched, not acknowledged");
        assert_eq!(u.status().used_std, 1);
        u.write(TechnoWrite::Done {
            set: UnitSet::Std,
            unit: 0,
            value: true,
        })
        .unwrap();
        u.tick(Duration::from_millis(2));
        assert!(u.is_acknowledged(0));
        assert_eq!((u.stats().output, u.stats().acknowledged), (1, 1));
        assert_eq!(u.status().used_std, 0);
    }

    #[test]
    fn without_a_plc_the_channel_acknowledges_after_the_process_time_and_a_reset_drops() {
        let mut u = TechnoUnits::new();
        let mut g = m25(0);
        g.fns[0].def.process_time_us = 500_000;
        u.output(g, Duration::ZERO);
        u.tick(Duration::from_millis(499));
        assert!(!u.is_acknowledged(0));
        u.tick(Duration::from_millis(500));
        assert!(u.is_acknowledged(0));
        // A function not yet output is not acknowledged; a reset drops what waits.
        assert!(!u.is_acknowledged(1));
        let mut g = m25(1);
        g.fns[0].def.process_time_us = 500_000;
        u.output(g, Duration::from_secs(1));
        u.reset();
        assert_eq!(u.stats().dropped_by_reset, 1);
        assert!(u.all_acknowledged());
    }
}
