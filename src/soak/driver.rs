//! The soak cycle: every channel of the scenario with its own client, ticked in one runtime
//! cycle, with faults injected at random ticks and the invariants checked after each tick.
//!
//! One tick per channel: faults due → restart after a reset, error or program end → the
//! client writes (or a forced rejection skips it) → the channel steps → its executed stream
//! blocks are checked against what it owes, its position against the soft limits, its new
//! errors against the expected ones.

use std::collections::BTreeMap;
use std::convert::Infallible;

use super::feed::SoakFeeder;
use super::invariants::{check_blocks, Checksum, Tally};
use super::rng::SplitMix64;
use super::scenario::Faults;
use crate::channel::{Channel, State};
use crate::motion::AxisLimits;
use crate::runtime::{Cycle, Flow, Tick};

/// Fault schedule of one channel: the next tick (or block count) each fault is due.
#[derive(Debug)]
struct Schedule {
    rng: SplitMix64,
    reset_at_block: Option<u64>,
    reset_at_tick: Option<u64>,
    hold_at: Option<u64>,
    hold_until: Option<u64>,
    override_at: Option<u64>,
    reject_at: Option<u64>,
    reject_until: Option<u64>,
}

/// The tick of the next fault: `now` plus a draw from the range, or never.
pub(crate) fn draw(rng: &mut SplitMix64, now: u64, r: Option<[u64; 2]>) -> Option<u64> {
    r.map(|[a, b]| now.saturating_add(rng.range(a, b)))
}

/// Counters of one channel's soak.
#[derive(Debug, Clone, Default)]
pub struct SlotCounters {
    /// Stream blocks executed (and checked).
    pub blocks: u64,
    /// Resets injected by the fault schedule.
    pub resets: u64,
    /// Resets after a channel error.
    pub error_resets: u64,
    /// Program restarts after the program ended (a streamed file's M30).
    pub restarts: u64,
    pub holds: u64,
    pub overrides: u64,
    pub forced_rejections: u64,
    /// Channel errors by number.
    pub errors: BTreeMap<u32, u64>,
    pub checksum: Checksum,
}

/// One soaked channel.
pub struct Slot {
    pub channel: Channel,
    pub program: String,
    pub feeder: SoakFeeder,
    /// Configured axes: index, soft limits (mm).
    limits: Vec<(usize, f64, f64)>,
    schedule: Schedule,
    errors_seen: usize,
    pub counters: SlotCounters,
    /// Start the program again at the next tick.
    restart_due: bool,
}

impl Slot {
    pub fn new(
        mut channel: Channel,
        program: String,
        feeder: SoakFeeder,
        axes: &[AxisLimits],
        rng: SplitMix64,
    ) -> Self {
        channel.observe_stream_blocks(true);
        Slot {
            channel,
            program,
            feeder,
            limits: axes.iter().map(|a| (a.index, a.min_mm, a.max_mm)).collect(),
            schedule: Schedule {
                rng,
                reset_at_block: None,
                reset_at_tick: None,
                hold_at: None,
                hold_until: None,
                override_at: None,
                reject_at: None,
                reject_until: None,
            },
            errors_seen: 0,
            counters: SlotCounters::default(),
            restart_due: true,
        }
    }

    fn plan(&mut self, f: &Faults, now: u64) {
        let s = &mut self.schedule;
        s.reset_at_block = draw(&mut s.rng, self.counters.blocks, f.reset_every_blocks);
        s.reset_at_tick = draw(&mut s.rng, now, f.reset_every_ticks);
        s.hold_at = draw(&mut s.rng, now, f.hold_every_ticks);
        s.override_at = draw(&mut s.rng, now, f.override_every_ticks);
        s.reject_at = draw(&mut s.rng, now, f.reject_every_ticks);
    }

    fn restart(&mut self, tick: &Tick) {
        self.feeder.new_epoch(tick.index);
        // A failed start raises its channel error, which the error check then sees.
        let _ = self.channel.start(tick, &self.program);
    }

    fn reset(&mut self, tick: &Tick, f: &Faults) {
        self.channel.reset(tick);
        let s = &mut self.schedule;
        s.hold_until = None;
        s.reset_at_block = draw(&mut s.rng, self.counters.blocks, f.reset_every_blocks);
        s.reset_at_tick = draw(&mut s.rng, tick.index, f.reset_every_ticks);
        self.restart(tick);
    }

    /// Faults and restarts due at this tick.
    fn faults(&mut self, tick: &Tick, f: &Faults) {
        let t = tick.index;
        let s = &self.schedule;
        let reset_due = s.reset_at_block.is_some_and(|b| self.counters.blocks >= b)
            || s.reset_at_tick.is_some_and(|at| t >= at);
        if reset_due {
            self.counters.resets += 1;
            self.reset(tick, f);
        } else if self.channel.state() == State::Error {
            self.counters.error_resets += 1;
            self.reset(tick, f);
        } else if self.restart_due || self.channel.state() == State::Ready {
            if !self.restart_due {
                self.counters.restarts += 1;
            }
            self.restart_due = false;
            self.restart(tick);
        }
        let s = &mut self.schedule;
        if s.hold_until.is_some_and(|u| t >= u) {
            s.hold_until = None;
            self.channel.resume(tick);
        } else if s.hold_at.is_some_and(|h| t >= h) {
            s.hold_at = draw(&mut s.rng, t, f.hold_every_ticks);
            if self.channel.state() == State::Active {
                self.channel.hold(tick);
                s.hold_until = Some(t + s.rng.range(f.hold_ticks[0], f.hold_ticks[1]));
                self.counters.holds += 1;
            }
        }
        if s.override_at.is_some_and(|o| t >= o) {
            s.override_at = draw(&mut s.rng, t, f.override_every_ticks);
            let [lo, hi] = f.override_pct;
            let pct = (s.rng.range_f64(lo, hi) * 10.0).round() / 10.0;
            if self.channel.set_override(pct.clamp(0.0, 200.0)).is_ok() {
                self.counters.overrides += 1;
            }
        }
        if s.reject_at.is_some_and(|r| t >= r) {
            s.reject_at = draw(&mut s.rng, t, f.reject_every_ticks);
            s.reject_until = Some(t + s.rng.range(f.reject_ticks[0], f.reject_ticks[1]));
            self.counters.forced_rejections += 1;
        }
    }
}

/// The invariant tallies over all channels.
#[derive(Debug, Clone, Default)]
pub struct Tallies {
    pub order: Tally,
    pub errors: Tally,
    pub limits: Tally,
}

/// The soak as a runtime [`Cycle`].
pub struct SoakCycle {
    pub slots: Vec<Slot>,
    faults: Faults,
    expected_errors: Vec<u32>,
    /// Stop when this many stream blocks ran, all channels together.
    target_blocks: Option<u64>,
    pub total_blocks: u64,
    pub tallies: Tallies,
    planned: bool,
}

impl SoakCycle {
    pub fn new(
        slots: Vec<Slot>,
        faults: Faults,
        expected_errors: Vec<u32>,
        target_blocks: Option<u64>,
    ) -> Self {
        SoakCycle {
            slots,
            faults,
            expected_errors,
            target_blocks,
            total_blocks: 0,
            tallies: Tallies::default(),
            planned: false,
        }
    }
}

impl Cycle for SoakCycle {
    /// The soak takes no requests from other threads.
    type Request = Infallible;

    fn serve(&mut self, req: Infallible, _tick: &Tick) {
        match req {}
    }

    fn step(&mut self, tick: &Tick) -> Flow {
        let t = tick.index;
        if !self.planned {
            self.planned = true;
            for s in &mut self.slots {
                s.plan(&self.faults, t);
            }
        }
        for slot in &mut self.slots {
            slot.faults(tick, &self.faults);
            let rejecting = slot.schedule.reject_until.is_some_and(|u| t < u);
            if rejecting {
                slot.feeder.skip(t);
            } else if let Some(packet) = slot.feeder.poll(t) {
                let ok = slot.channel.write_stream(tick, packet).is_ok();
                slot.feeder.result(t, ok);
            }
            slot.channel.step(tick);
            let number = slot.channel.number();
            let n = check_blocks(
                number,
                slot.feeder.owed_mut(),
                slot.channel.drain_executed(),
                &mut self.tallies.order,
                &mut slot.counters.checksum,
            );
            slot.counters.blocks += n;
            self.total_blocks += n;
            let p = slot.channel.position();
            for &(i, lo, hi) in &slot.limits {
                if !(lo - 1e-9..=hi + 1e-9).contains(&p[i]) {
                    let (v, axis) = (p[i], crate::vocab::axis::AXIS_LETTERS[i] as char);
                    self.tallies.limits.violate(|| {
                        format!(
                            "channel {number}, tick {t}: {axis} = {v:.4} mm outside [{lo}, {hi}]"
                        )
                    });
                }
            }
            let errors = slot.channel.errors();
            if errors.len() > slot.errors_seen {
                for e in &errors[slot.errors_seen..] {
                    let (code, msg) = (e.code, &e.msg);
                    *slot.counters.errors.entry(code).or_default() += 1;
                    if !self.expected_errors.contains(&code) {
                        self.tallies
                            .errors
                            .violate(|| format!("channel {number}, tick {t}: error {code}: {msg}"));
                    }
                }
                slot.errors_seen = errors.len();
            }
        }
        match self.target_blocks {
            Some(b) if self.total_blocks >= b => Flow::Stop,
            _ => Flow::Continue,
        }
    }
}
