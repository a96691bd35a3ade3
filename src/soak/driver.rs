//! The soak's one driver core, shared by the in-process soak ([`SoakCycle`], its own client)
//! and `serve --soak` (`soak::external`, external ADS clients): the fault plan of a channel,
//! its counters, and the checks after each tick. Everything it does to a channel is an
//! [`Op`] through the channel's one door ([`Door`]); it only reads the channel (state,
//! position, errors) through `&self` accessors.
//!
//! One tick per channel: faults due → restart after a reset, error or program end → the
//! client writes (or a forced rejection refuses it) → the channel steps → its executed stream
//! blocks are checked against what it owes, its position against the soft limits, its new
//! errors against the expected ones.

use std::collections::{BTreeMap, VecDeque};
use std::convert::Infallible;
use std::sync::Arc;
use std::time::Duration;

use serde::Serialize;

use super::feed::{FeedCounters, Owed, SoakFeeder};
use super::invariants::{check_blocks, Checksum, Tally, TechnoCheck, Verdict};
use super::rng::SplitMix64;
use super::scenario::Faults;
use crate::channel::AxisLimits;
use crate::channel::{Channel, State};
use crate::machine::{Machine, Offer, Op, Reply};
use crate::runtime::{Clock, Cycle, Flow, Tick};

/// The one way the soak commands a channel, and reads it.
pub trait Door {
    /// Apply one operation in this tick, as a client's request would be.
    fn apply(&mut self, tick: &Tick, op: Op) -> Reply;
    /// A stream write of a packet the caller keeps offering until it is taken
    /// ([`Machine::write_stream`]).
    fn write_stream(&mut self, tick: &Tick, packet: &Arc<[u8]>) -> Reply;
    /// The channel, read-only (state, position, errors for the checks).
    fn channel(&self) -> &Channel;
}

/// One channel of a [`Machine`] as a door: ops go through [`Machine::apply`].
pub(crate) struct MachineDoor<'a> {
    machine: &'a mut Machine,
    number: u32,
    index: usize,
}

impl<'a> MachineDoor<'a> {
    /// The door of channel `number` (1-based), if the machine has it.
    pub fn new(machine: &'a mut Machine, number: u32) -> Option<Self> {
        let index = (number as usize).checked_sub(1)?;
        machine.channels().get(index)?;
        Some(MachineDoor {
            machine,
            number,
            index,
        })
    }
}

impl Door for MachineDoor<'_> {
    fn apply(&mut self, tick: &Tick, op: Op) -> Reply {
        self.machine.apply(tick, self.number, op)
    }
    fn write_stream(&mut self, tick: &Tick, packet: &Arc<[u8]>) -> Reply {
        self.machine.write_stream(tick, self.number, packet)
    }
    fn channel(&self) -> &Channel {
        // `new` checked the index, and a machine's channels never change.
        &self.machine.channels()[self.index]
    }
}

/// The tick of the next fault: `now` plus a draw from the range, or never.
fn draw(rng: &mut SplitMix64, now: u64, r: Option<[u64; 2]>) -> Option<u64> {
    r.map(|[a, b]| now.saturating_add(rng.range(a, b)))
}

/// Fault plan of one channel: the next tick (or block count) each fault is due. The random
/// numbers come from the caller, in a fixed order, so a seed gives the same faults.
#[derive(Debug, Default)]
struct FaultPlan {
    reset_at_block: Option<u64>,
    reset_at_tick: Option<u64>,
    hold_at: Option<u64>,
    hold_until: Option<u64>,
    override_at: Option<u64>,
    reject_at: Option<u64>,
    reject_until: Option<u64>,
}

impl FaultPlan {
    fn plan(&mut self, rng: &mut SplitMix64, f: &Faults, blocks: u64, now: u64) {
        self.reset_at_block = draw(rng, blocks, f.reset_every_blocks);
        self.reset_at_tick = draw(rng, now, f.reset_every_ticks);
        self.hold_at = draw(rng, now, f.hold_every_ticks);
        self.override_at = draw(rng, now, f.override_every_ticks);
        self.reject_at = draw(rng, now, f.reject_every_ticks);
    }

    fn reset_due(&self, blocks: u64, now: u64) -> bool {
        self.reset_at_block.is_some_and(|b| blocks >= b)
            || self.reset_at_tick.is_some_and(|at| now >= at)
    }

    fn rejecting(&self, now: u64) -> bool {
        self.reject_until.is_some_and(|u| now < u)
    }
}

/// Counters of one soaked channel, as the report shows them.
#[derive(Debug, Clone, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct SoakCounters {
    pub number: u32,
    /// The program restarted after each reset (empty: none).
    pub program: String,
    /// Stream blocks executed (and checked).
    pub blocks: u64,
    /// Resets injected by the fault plan.
    pub resets: u64,
    /// Resets after a channel error.
    pub(crate) error_resets: u64,
    /// Program restarts after the program ended (a streamed file's M30, a client's reset).
    pub restarts: u64,
    pub holds: u64,
    pub overrides: u64,
    pub forced_rejections: u64,
    /// Stream writes the channel accepted, and their bytes and lines (now owed).
    pub writes_ok: u64,
    pub bytes: u64,
    pub lines_accepted: u64,
    /// Accepted lines an injected (or error) reset dropped before they ran (external
    /// clients; each reset is also announced on stderr by `serve --soak`).
    pub lines_dropped: u64,
    /// Stream writes the channel refused (a full buffer: 11012).
    pub writes_rejected: u64,
    /// Writes a forced rejection refused without touching the channel.
    pub(crate) writes_skipped: u64,
    /// Pauses the built-in client made (none for external clients).
    pub pauses: u64,
    pub interrupts: u64,
    pub warnings: u64,
    /// Channel errors by number.
    pub errors: BTreeMap<u32, u64>,
    /// FNV-1a over (offset, N) of every executed block, hex: equal for equal runs.
    pub checksum: String,
    /// The technology functions and the simulated PLC, for a channel with one
    /// (`[channel.plc]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plc: Option<PlcCounters>,
}

/// A soaked channel's technology functions and what its simulated PLC did.
#[derive(Debug, Clone, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct PlcCounters {
    /// What the check counted from the channel's observations.
    pub functions: super::invariants::TechnoFigures,
    /// Output and not finished when the run ended.
    pub open_at_end: u64,
    /// Channel time from output to acknowledgement, summed, seconds (the channel's figure).
    pub waited_s: f64,
    /// Acknowledgements the PLC made late (`late_every`).
    pub late: u64,
    /// Functions the PLC left unanswered (`stop_after`).
    pub unanswered: u64,
}

/// The invariant tallies over all channels.
#[derive(Debug, Clone, Default)]
pub struct Tallies {
    pub order: Tally,
    pub errors: Tally,
    pub limits: Tally,
    /// Technology functions output once, finished once (acknowledged or dropped by a reset).
    pub techno: Tally,
    /// No block starts before the functions it waits for are acknowledged.
    pub techno_motion: Tally,
    /// A simulated PLC runs: the technology verdicts are reported (they are checked always;
    /// without a PLC they are reported when violated, so the shipped reports keep their shape).
    pub techno_reported: bool,
}

impl Tallies {
    /// The verdicts of a run: order, errors, limits, and memory (`growth`: resident set
    /// after warm-up, KiB, allowed up to `slack_kib`).
    pub(crate) fn verdicts(
        &self,
        blocks: u64,
        expected_errors: &[u32],
        growth: Option<i64>,
        slack_kib: u64,
    ) -> Vec<Verdict> {
        let mut memory = Tally::default();
        if let Some(g) = growth {
            if g > slack_kib as i64 {
                memory.violate(|| {
                    format!("resident set grew by {g} KiB after warm-up (allowed {slack_kib} KiB)")
                });
            }
        }
        let mut v = vec![
            self.order.verdict(
                "every accepted line executed exactly once, in order, between resets",
                Some(format!("{blocks} blocks checked")),
            ),
            self.errors.verdict(
                "no channel error but the expected ones",
                Some(format!("expected: {expected_errors:?}")),
            ),
            self.limits
                .verdict("positions within the axis soft limits", None),
            memory.verdict(
                "memory steady",
                growth.map(|g| format!("growth {g} KiB ≤ {slack_kib} KiB")),
            ),
        ];
        if self.techno_reported || self.techno.violations + self.techno_motion.violations > 0 {
            v.push(self.techno.verdict(
                "every technology function output once, then acknowledged once or dropped by a reset",
                None,
            ));
            v.push(self.techno_motion.verdict(
                "no block starts before the functions it waits for (MVS_SVS) are acknowledged",
                None,
            ));
        }
        v
    }
}

/// What the soak keeps of one channel: its fault plan, counters and checker state.
pub struct SoakChannel {
    plan: FaultPlan,
    /// Configured axes: index, soft limits (mm).
    limits: Vec<(usize, f64, f64)>,
    /// Start the program again at the next tick.
    restart_due: bool,
    /// Ticks the channel stays READY after an injected reset before the program restarts
    /// (0: in the reset's own tick, as the built-in client's soak does).
    ready_hold_ticks: u64,
    /// The tick at which a held READY ends and the program restarts.
    restart_at: Option<u64>,
    errors_seen: usize,
    /// Check that numbered lines run with rising N (external clients: a numbered line is a
    /// client's line once, so an N not above the last is a line run again, even when the
    /// client wrote it twice and the offsets differ).
    numbers_rise: bool,
    /// The last N executed this epoch.
    last_n: Option<u32>,
    sum: Checksum,
    /// The technology check, for a channel whose observations are on (`Op::ObserveTechno`).
    techno: Option<TechnoCheck>,
    pub counters: SoakCounters,
}

impl SoakChannel {
    /// A channel that restarts `program` (if any) and checks positions against `axes`.
    pub fn new(number: u32, program: Option<String>, axes: &[AxisLimits]) -> Self {
        SoakChannel {
            plan: FaultPlan::default(),
            limits: axes.iter().map(|a| (a.index, a.min_mm, a.max_mm)).collect(),
            restart_due: true,
            ready_hold_ticks: 0,
            restart_at: None,
            errors_seen: 0,
            numbers_rise: false,
            last_n: None,
            sum: Checksum::default(),
            techno: None,
            counters: SoakCounters {
                number,
                program: program.unwrap_or_default(),
                ..Default::default()
            },
        }
    }

    /// Also check the technology functions (the channel's observations must be on).
    pub(crate) fn with_techno_check(mut self) -> Self {
        self.techno = Some(TechnoCheck::default());
        self
    }

    /// The end of the run: the check's counts against the channel's own counters, and the
    /// balance output = acknowledged + dropped + still open.
    pub(crate) fn end_checks(&self, c: &Channel, tallies: &mut Tallies) {
        let Some(tc) = &self.techno else { return };
        let (f, own, number) = (tc.figures, c.report().techno, self.counters.number);
        if f.output != f.acknowledged + f.dropped + tc.open() as u64 {
            tallies.techno.violate(|| {
                format!(
                    "channel {number}: {} output ≠ {} acknowledged + {} dropped + {} open",
                    f.output,
                    f.acknowledged,
                    f.dropped,
                    tc.open()
                )
            });
        }
        if (own.output, own.acknowledged, own.dropped_by_reset)
            != (f.output, f.acknowledged, f.dropped + f.dropped_unoutput)
        {
            tallies.techno.violate(|| {
                format!(
                    "channel {number}: the channel counted {}/{}/{} output/acknowledged/dropped, its observations {}/{}/{}",
                    own.output, own.acknowledged, own.dropped_by_reset,
                    f.output, f.acknowledged, f.dropped + f.dropped_unoutput
                )
            });
        }
    }

    /// Also check that numbered lines run with rising N (for external clients).
    pub(crate) fn with_rising_numbers(mut self) -> Self {
        self.numbers_rise = true;
        self
    }

    /// Keep the channel READY for `ticks` after each injected reset before restarting the
    /// program, so a client watching mode and state sees the reset (external clients).
    pub(crate) fn set_ready_hold(&mut self, ticks: u64) {
        self.ready_hold_ticks = ticks;
    }

    /// An injected reset's READY is being held: the program restarts at the returned tick.
    pub(crate) fn ready_held_until(&self) -> Option<u64> {
        self.restart_at
    }

    /// Draw the first faults (at the first tick).
    pub(crate) fn plan(&mut self, rng: &mut SplitMix64, f: &Faults, now: u64) {
        self.plan.plan(rng, f, self.counters.blocks, now);
    }

    /// A forced rejection is running: the client's writes are refused unseen by the channel.
    pub(crate) fn rejecting(&self, now: u64) -> bool {
        self.plan.rejecting(now)
    }

    /// A new stream epoch: the rising-N check starts over (what is owed is the caller's).
    pub(crate) fn new_epoch(&mut self) {
        self.last_n = None;
    }

    /// Start the program again; `new_epoch` drops what the client owes.
    fn restart(&mut self, tick: &Tick, door: &mut impl Door, new_epoch: &mut dyn FnMut(u64)) {
        new_epoch(tick.index);
        self.new_epoch();
        if !self.counters.program.is_empty() {
            // A failed start raises its channel error, which the error check then sees.
            let _ = door.apply(tick, Op::Start(self.counters.program.clone()));
        }
    }

    fn reset(
        &mut self,
        rng: &mut SplitMix64,
        f: &Faults,
        tick: &Tick,
        door: &mut impl Door,
        new_epoch: &mut dyn FnMut(u64),
    ) {
        door.apply(tick, Op::Reset);
        let p = &mut self.plan;
        p.hold_until = None;
        p.reset_at_block = draw(rng, self.counters.blocks, f.reset_every_blocks);
        p.reset_at_tick = draw(rng, tick.index, f.reset_every_ticks);
        if self.ready_hold_ticks == 0 {
            self.restart(tick, door, new_epoch);
        } else {
            // The reset ends the epoch now: lines accepted while READY is held belong to the
            // next one, which the restart reads from the stream buffer's start.
            new_epoch(tick.index);
            self.new_epoch();
            self.restart_at = Some(tick.index.saturating_add(self.ready_hold_ticks));
        }
    }

    /// The held READY after an injected reset is over: start the program, keeping what the
    /// clients wrote meanwhile (a client that started it itself gets a refusal, ignored).
    fn restart_held(&mut self, tick: &Tick, door: &mut impl Door) {
        self.restart_at = None;
        if !self.counters.program.is_empty() && door.channel().state() == State::Ready {
            let _ = door.apply(tick, Op::Start(self.counters.program.clone()));
        }
    }

    /// Faults and restarts due at this tick, through the door.
    pub fn faults(
        &mut self,
        rng: &mut SplitMix64,
        f: &Faults,
        tick: &Tick,
        door: &mut impl Door,
        new_epoch: &mut dyn FnMut(u64),
    ) {
        let t = tick.index;
        let state = door.channel().state();
        if self.plan.reset_due(self.counters.blocks, t) {
            self.counters.resets += 1;
            self.reset(rng, f, tick, door, new_epoch);
        } else if state == State::Error {
            self.counters.error_resets += 1;
            self.reset(rng, f, tick, door, new_epoch);
        } else if let Some(at) = self.restart_at {
            if t >= at {
                self.restart_held(tick, door);
            }
        } else if self.restart_due || (state == State::Ready && !self.counters.program.is_empty()) {
            // A channel without a program to restart stays READY and counts no restarts.
            if !self.restart_due {
                self.counters.restarts += 1;
            }
            self.restart_due = false;
            self.restart(tick, door, new_epoch);
        }
        let p = &mut self.plan;
        if p.hold_until.is_some_and(|u| t >= u) {
            p.hold_until = None;
            door.apply(tick, Op::Resume);
        } else if p.hold_at.is_some_and(|h| t >= h) {
            p.hold_at = draw(rng, t, f.hold_every_ticks);
            if door.channel().state() == State::Active {
                door.apply(tick, Op::Hold);
                p.hold_until = Some(t + rng.range(f.hold_ticks[0], f.hold_ticks[1]));
                self.counters.holds += 1;
            }
        }
        if p.override_at.is_some_and(|o| t >= o) {
            p.override_at = draw(rng, t, f.override_every_ticks);
            let [lo, hi] = f.override_pct;
            let pct = (rng.range_f64(lo, hi) * 10.0).round() / 10.0;
            if door.apply(tick, Op::SetOverride(pct.clamp(0.0, 200.0))) == Reply::Command(Ok(())) {
                self.counters.overrides += 1;
            }
        }
        if p.reject_at.is_some_and(|r| t >= r) {
            p.reject_at = draw(rng, t, f.reject_every_ticks);
            p.reject_until = Some(t + rng.range(f.reject_ticks[0], f.reject_ticks[1]));
            self.counters.forced_rejections += 1;
        }
    }

    /// After the tick: the executed stream blocks against what is `owed`, the position
    /// against the soft limits, new errors against the expected ones. Returns the blocks
    /// checked.
    pub fn check(
        &mut self,
        tick: &Tick,
        door: &mut impl Door,
        owed: &mut VecDeque<Owed>,
        tallies: &mut Tallies,
        expected_errors: &[u32],
    ) -> u64 {
        let (t, number) = (tick.index, self.counters.number);
        let (executed_pending, techno_pending) = door.channel().drains_pending();
        let executed = match executed_pending.then(|| door.apply(tick, Op::DrainExecuted)) {
            Some(Reply::Executed(e)) => e,
            _ => Vec::new(),
        };
        if self.numbers_rise {
            for n in executed.iter().filter_map(|b| b.n) {
                if let Some(last) = self.last_n.filter(|&last| n <= last) {
                    tallies.order.violate(|| {
                        format!("channel {number}: N{n} executed after N{last} (a line run twice or out of order)")
                    });
                }
                self.last_n = Some(n);
            }
        }
        if let Some(tc) = self.techno.as_mut().filter(|_| techno_pending) {
            if let Reply::TechnoSeen { seen, lost } = door.apply(tick, Op::DrainTechno) {
                for s in seen {
                    tc.see(number, s, &mut tallies.techno, &mut tallies.techno_motion);
                }
                if lost > 0 {
                    tallies.techno.violate(|| {
                        format!("channel {number}, tick {t}: {lost} technology observations lost")
                    });
                }
            }
        }
        let n = check_blocks(
            number,
            owed,
            executed.into_iter(),
            &mut tallies.order,
            &mut self.sum,
        );
        self.counters.blocks += n;
        let c = door.channel();
        let p = c.position();
        for &(i, lo, hi) in &self.limits {
            if !(lo - 1e-9..=hi + 1e-9).contains(&p[i]) {
                let (v, axis) = (p[i], crate::vocab::axis::AXIS_LETTERS[i] as char);
                tallies.limits.violate(|| {
                    format!("channel {number}, tick {t}: {axis} = {v:.4} mm outside [{lo}, {hi}]")
                });
            }
        }
        let errors = c.errors();
        if errors.len() > self.errors_seen {
            for e in &errors[self.errors_seen..] {
                let (code, msg) = (e.code, &e.msg);
                *self.counters.errors.entry(code).or_default() += 1;
                if !expected_errors.contains(&code) {
                    tallies
                        .errors
                        .violate(|| format!("channel {number}, tick {t}: error {code}: {msg}"));
                }
            }
            self.errors_seen = errors.len();
        }
        n
    }

    /// The counters for the report, with the channel's own figures and the checksum.
    pub fn report(&self, c: &Channel) -> SoakCounters {
        let r = c.report();
        let st = r.stats;
        SoakCounters {
            plc: self.techno.as_ref().map(|t| PlcCounters {
                functions: t.figures,
                open_at_end: t.open() as u64,
                waited_s: r.techno.waited.as_secs_f64(),
                ..PlcCounters::default()
            }),
            interrupts: st.interrupts,
            warnings: st.warnings,
            checksum: format!("{:016x}", self.sum.0),
            ..self.counters.clone()
        }
    }
}

/// One channel soaked by its own built-in client: the channel itself lives in the machine.
pub struct Slot {
    /// 1-based channel number in the machine.
    number: u32,
    pub feeder: SoakFeeder,
    pub core: SoakChannel,
    rng: SplitMix64,
    /// The packet on offer until the channel takes it.
    offer: Offer,
}

impl Slot {
    /// The soak's client of channel `number` of `machine`; `None` when the machine has no
    /// such channel.
    pub fn new(
        machine: &mut Machine,
        number: u32,
        program: String,
        feeder: SoakFeeder,
        axes: &[AxisLimits],
        rng: SplitMix64,
    ) -> Option<Self> {
        // Turning observation on emits nothing, so the tick does not matter.
        let tick0 = Tick::first(Duration::ZERO, Clock::Virtual);
        let mut door = MachineDoor::new(machine, number)?;
        door.apply(&tick0, Op::ObserveStreamBlocks(true));
        door.apply(&tick0, Op::ObserveTechno(true));
        Some(Slot {
            number,
            feeder,
            core: SoakChannel::new(number, Some(program), axes).with_techno_check(),
            rng,
            offer: Offer::default(),
        })
    }

    /// The counters for the report, the client's writes and the channel's own figures
    /// included.
    fn report(&self, machine: &Machine) -> SoakCounters {
        let f = self.feeder.counters();
        let own = (self.number as usize)
            .checked_sub(1)
            .and_then(|i| machine.channels().get(i))
            .map_or_else(|| self.core.counters.clone(), |c| self.core.report(c));
        let plc = machine
            .plcs()
            .iter()
            .find(|p| p.channel() == self.number)
            .map(|p| {
                let st = p.stats();
                PlcCounters {
                    late: st.late,
                    unanswered: st.unanswered,
                    ..own.plc.clone().unwrap_or_default()
                }
            });
        SoakCounters {
            plc,
            writes_ok: f.writes_ok,
            writes_rejected: f.writes_rejected,
            writes_skipped: f.writes_skipped,
            bytes: f.bytes,
            lines_accepted: f.lines,
            pauses: f.pauses,
            ..own
        }
    }
}

/// The in-process soak as a runtime [`Cycle`]: the shipped [`Machine`] with a built-in
/// client and a fault plan per soaked channel around it, as `serve --soak` wraps it for
/// external clients. The machine's tick is the one `run` and `serve` tick.
pub struct SoakCycle {
    machine: Machine,
    slots: Vec<Slot>,
    faults: Faults,
    expected_errors: Vec<u32>,
    /// Stop when this many stream blocks ran, all channels together.
    target_blocks: Option<u64>,
    pub(crate) total_blocks: u64,
    pub tallies: Tallies,
    planned: bool,
}

impl SoakCycle {
    pub fn new(
        machine: Machine,
        slots: Vec<Slot>,
        faults: Faults,
        expected_errors: Vec<u32>,
        target_blocks: Option<u64>,
    ) -> Self {
        let tallies = Tallies {
            techno_reported: !machine.plcs().is_empty(),
            ..Tallies::default()
        };
        SoakCycle {
            machine,
            slots,
            faults,
            expected_errors,
            target_blocks,
            total_blocks: 0,
            tallies,
            planned: false,
        }
    }

    /// Each soaked channel's counters, in the order of the scenario.
    pub fn reports(&self) -> Vec<SoakCounters> {
        self.slots.iter().map(|s| s.report(&self.machine)).collect()
    }

    /// The end-of-run checks of every soaked channel (the technology balance).
    pub(crate) fn end_checks(&mut self) {
        for s in &self.slots {
            if let Some(c) = (s.number as usize)
                .checked_sub(1)
                .and_then(|i| self.machine.channels().get(i))
            {
                s.core.end_checks(c, &mut self.tallies);
            }
        }
    }

    /// The built-in clients' write counters, in the order of the scenario.
    pub fn feed_counters(&self) -> impl Iterator<Item = &FeedCounters> {
        self.slots.iter().map(|s| s.feeder.counters())
    }
}

impl SoakCycle {
    /// The machine the soak ticks (the bench reads its worst tick).
    pub(crate) fn machine(&self) -> &Machine {
        &self.machine
    }

    /// The machine the soak ticks (the bench registers notification watches on it).
    pub(crate) fn machine_mut(&mut self) -> &mut Machine {
        &mut self.machine
    }
}

impl Cycle for SoakCycle {
    /// The soak takes no requests from other threads.
    type Request = Infallible;
    const TAKES_REQUESTS: bool = false;

    fn serve(&mut self, req: Infallible, _tick: &Tick) {
        match req {}
    }

    /// One tick, per soaked channel: faults due, then the client's write; the machine's tick;
    /// then per channel the checks. Channels do not share state, so each sees the same
    /// sequence as when they took turns.
    fn step(&mut self, tick: &Tick) -> Flow {
        let t = tick.index;
        if !self.planned {
            self.planned = true;
            for s in &mut self.slots {
                s.core.plan(&mut s.rng, &self.faults, t);
            }
        }
        for slot in &mut self.slots {
            let Some(mut door) = MachineDoor::new(&mut self.machine, slot.number) else {
                continue;
            };
            let (feeder, offer) = (&mut slot.feeder, &mut slot.offer);
            slot.core
                .faults(&mut slot.rng, &self.faults, tick, &mut door, &mut |t| {
                    offer.withdraw();
                    feeder.new_epoch(t);
                });
            if slot.core.rejecting(t) {
                slot.feeder.skip(t);
            } else if let Some(packet) = slot.feeder.poll(t) {
                let reply = door.write_stream(tick, slot.offer.packet(packet));
                slot.feeder.result(t, slot.offer.answered(&reply));
            }
        }
        // The machine decides nothing here (it never stops by itself): the soak stops at
        // its block target.
        let _ = self.machine.step(tick);
        for slot in &mut self.slots {
            let Some(mut door) = MachineDoor::new(&mut self.machine, slot.number) else {
                continue;
            };
            self.total_blocks += slot.core.check(
                tick,
                &mut door,
                slot.feeder.owed_mut(),
                &mut self.tallies,
                &self.expected_errors,
            );
        }
        match self.target_blocks {
            Some(b) if self.total_blocks >= b => Flow::Stop,
            _ => Flow::Continue,
        }
    }

    fn take_clock_stopped(&mut self) -> Duration {
        self.machine.take_clock_stopped()
    }

    fn record_work(&mut self, work: Duration) {
        self.machine.record_work(work);
    }
}
