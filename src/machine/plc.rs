//! A simulated PLC for one channel, played inside the machine: the PLC half of the HLI
//! technology units (README "Technology functions: the PLC half"). It sets `plc_present_w`,
//! polls the channel's units each tick and acknowledges each function after a delay, the way a
//! PLC task runs the handshake (`kimblad/TwinSharp` `TwinSharp/CNC/TechnologyProcesses.cs`:
//! read `please_rw`, work, write `please_rw` FALSE and `done_w` TRUE). Everything it writes goes
//! through the channel's door (`Channel::apply(Op::Techno(..))`), as an ADS client's writes do.
//!
//! The delays are channel time, as the kernel's own execution time simulation counts its
//! process times (TF5200 HLI "Operation with and without PLC"): a run in virtual time shows the
//! same waits as one in real time, and a seed gives the same run.

use std::time::Duration;

use super::rng::SplitMix64;
use super::Op;
use crate::channel::techno::{TechnoWrite, UnitSet};
use crate::channel::Channel;
use crate::runtime::Tick;
use crate::vocab::techno::{TechnoKind, TechnoSeq};

/// A delay in ms, `[min, max]`, drawn uniformly; a fixed delay is `[n, n]`.
pub type DelayMs = [u64; 2];

/// What the simulated PLC does (runtime.toml `[plc]`, a soak scenario's `[channel.plc]`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlcConfig {
    /// Delay of a function no override names.
    pub delay_ms: DelayMs,
    /// Per-function delays: kind and number (`None`: every number of the kind, as `S`, `T`);
    /// a numbered entry wins over a kind's.
    pub overrides: Vec<(TechnoKind, Option<u32>, DelayMs)>,
    /// Every `late_every`-th acknowledgement comes `late_ms` later.
    pub late_every: Option<u64>,
    pub late_ms: u64,
    /// After this many acknowledgements the PLC answers no more: the functions stay in their
    /// units with `please_rw` set, the channel waits for them.
    pub stop_after: Option<u64>,
    /// Seed of the delays drawn from ranges.
    pub seed: u64,
}

impl Default for PlcConfig {
    /// Answers at once (the next tick), never late, never stops.
    fn default() -> Self {
        PlcConfig {
            delay_ms: [0, 0],
            overrides: Vec::new(),
            late_every: None,
            late_ms: 0,
            stop_after: None,
            seed: 0,
        }
    }
}

impl PlcConfig {
    /// The delay range of one function.
    pub fn delay_of(&self, kind: TechnoKind, number: u32) -> DelayMs {
        let exact = self
            .overrides
            .iter()
            .find(|(k, n, _)| *k == kind && *n == Some(number));
        let any = || {
            self.overrides
                .iter()
                .find(|(k, n, _)| *k == kind && n.is_none())
        };
        exact.or_else(any).map_or(self.delay_ms, |(_, _, d)| *d)
    }
}

/// What the simulated PLC did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PlcStats {
    /// Functions it took and will acknowledge (or has).
    pub taken: u64,
    /// Acknowledgements written (`please_rw` FALSE, `done_w` TRUE).
    pub acknowledged: u64,
    /// Acknowledgements made late by `late_every`.
    pub late: u64,
    /// Functions it saw after `stop_after` and left unanswered.
    pub unanswered: u64,
    /// Functions a reset took away while it was working on them.
    pub dropped: u64,
}

/// An acknowledgement due.
#[derive(Debug, Clone, Copy)]
struct Due {
    set: UnitSet,
    unit: usize,
    seq: TechnoSeq,
    at: Duration,
}

/// The PLC of one channel.
#[derive(Debug)]
pub struct SimulatedPlc {
    /// 1-based channel number.
    channel: u32,
    config: PlcConfig,
    rng: SplitMix64,
    present_written: bool,
    due: Vec<Due>,
    /// Functions seen after it stopped answering.
    ignored: Vec<TechnoSeq>,
    /// Functions seen this tick, not yet handled (kept to reuse its allocation).
    fresh: Vec<(UnitSet, usize, TechnoSeq, TechnoKind, u32)>,
    stats: PlcStats,
}

impl SimulatedPlc {
    pub fn new(channel: u32, config: PlcConfig) -> Self {
        SimulatedPlc {
            channel,
            rng: SplitMix64::new(config.seed ^ u64::from(channel).wrapping_mul(0x9E37_79B9)),
            config,
            present_written: false,
            due: Vec::new(),
            ignored: Vec::new(),
            fresh: Vec::new(),
            stats: PlcStats::default(),
        }
    }

    pub fn channel(&self) -> u32 {
        self.channel
    }

    pub fn config(&self) -> &PlcConfig {
        &self.config
    }

    pub fn stats(&self) -> PlcStats {
        self.stats
    }

    /// Acknowledgements scheduled and not yet written.
    pub fn pending(&self) -> usize {
        self.due.len()
    }

    /// One PLC cycle, before the channel's tick: take new functions, write what is due.
    pub fn tick(&mut self, tick: &Tick, channel: &mut Channel) {
        if !self.present_written {
            self.present_written = true;
            let _ = channel.apply(tick, Op::Techno(TechnoWrite::PlcPresent(true)));
        }
        let units = channel.techno();
        if units.idle() {
            // A reset took what it was working on.
            if !self.due.is_empty() || !self.ignored.is_empty() {
                self.stats.dropped += self.due.len() as u64;
                self.due.clear();
                self.ignored.clear();
            }
            return;
        }
        let before = self.due.len();
        self.due.retain(|d| units.is_open(d.seq));
        self.stats.dropped += (before - self.due.len()) as u64;
        self.ignored.retain(|s| units.is_open(*s));
        self.fresh.clear();
        for (set, unit, f, _please) in units.open_units() {
            let seq = f.seq;
            if !self.due.iter().any(|d| d.seq == seq) && !self.ignored.contains(&seq) {
                self.fresh.push((set, unit, seq, f.kind, f.number));
            }
        }
        for &(set, unit, seq, kind, number) in &self.fresh {
            if self
                .config
                .stop_after
                .is_some_and(|n| self.stats.taken >= n)
            {
                self.ignored.push(seq);
                self.stats.unanswered += 1;
                continue;
            }
            self.stats.taken += 1;
            let [lo, hi] = self.config.delay_of(kind, number);
            let mut ms = if hi > lo { self.rng.range(lo, hi) } else { lo };
            if self
                .config
                .late_every
                .is_some_and(|k| k > 0 && self.stats.taken.is_multiple_of(k))
            {
                ms = ms.saturating_add(self.config.late_ms);
                self.stats.late += 1;
            }
            self.due.push(Due {
                set,
                unit,
                seq,
                at: tick.time.saturating_add(Duration::from_millis(ms)),
            });
        }
        let now = tick.time;
        let mut k = 0;
        while k < self.due.len() {
            let d = self.due[k];
            if d.at > now {
                k += 1;
                continue;
            }
            self.due.swap_remove(k);
            let (set, unit) = (d.set, d.unit);
            let _ = channel.apply(
                tick,
                Op::Techno(TechnoWrite::Please {
                    set,
                    unit,
                    value: false,
                }),
            );
            let _ = channel.apply(
                tick,
                Op::Techno(TechnoWrite::Done {
                    set,
                    unit,
                    value: true,
                }),
            );
            self.stats.acknowledged += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_numbered_override_wins_over_its_kind_and_the_default() {
        let c = PlcConfig {
            delay_ms: [5, 5],
            overrides: vec![
                (TechnoKind::M, None, [1, 2]),
                (TechnoKind::M, Some(8), [300, 300]),
                (TechnoKind::S, None, [7, 7]),
            ],
            ..PlcConfig::default()
        };
        assert_eq!(c.delay_of(TechnoKind::M, 8), [300, 300]);
        assert_eq!(c.delay_of(TechnoKind::M, 9), [1, 2]);
        assert_eq!(c.delay_of(TechnoKind::S, 1200), [7, 7]);
        assert_eq!(c.delay_of(TechnoKind::H, 1), [5, 5]);
    }
}
