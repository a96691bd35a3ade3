//! The emulated controller as the runtime ticks it: its channels, the built-in stream feeders,
//! and the requests other threads (ADS connections, tests) send it.
//!
//! One tick: serve requests → feeders write → each channel decodes, executes, reports →
//! events leave for the log. Nothing here blocks or does I/O.

pub mod live;
pub mod plc;
pub mod remote;
pub mod rng;
pub mod watch;
pub mod worst;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use crossbeam_channel::Sender;

pub use crate::channel::door::{CycleTimes, HmiOp, Op, Reply, Status, TraceOp};
use crate::channel::{Channel, Finish, State};
pub use crate::channel::{SearchTarget, StreamWriteError};
use crate::feeder::Feeder;
use crate::report::event::EventLog;
use crate::runtime::{Cycle, Flow, Tick};
use plc::SimulatedPlc;

/// A request with its own way back: answered in the tick that serves it.
#[derive(Debug)]
pub struct Request {
    /// 1-based channel number.
    pub channel: u32,
    pub op: Op,
    pub reply: Sender<Reply>,
    /// Who decides this request's fate: the runtime (it applies it) or the waiting caller (it
    /// gave up and answers "not applied"). Whoever takes the claim first wins; the other side
    /// then knows, so a request is never both applied and answered as not applied
    /// (docs/exactly-once.md).
    pub(crate) claim: Claim,
}

impl Request {
    /// A request and the caller's half of its claim.
    pub fn new(channel: u32, op: Op, reply: Sender<Reply>) -> (Self, Claim) {
        let claim = Claim::default();
        let caller = claim.clone();
        (
            Request {
                channel,
                op,
                reply,
                claim,
            },
            caller,
        )
    }
}

/// A one-shot flag shared by a request and the thread waiting for its reply.
#[derive(Debug, Clone, Default)]
pub struct Claim(Arc<AtomicBool>);

impl Claim {
    /// Take the claim; true when this side got it (the other side had not taken it yet).
    pub fn take(&self) -> bool {
        !self.0.swap(true, Ordering::AcqRel)
    }
}

/// The packet a built-in client keeps offering until the channel takes it, shared with each
/// write attempt: a client offers the same packet again after a refusal, so a refused packet
/// (a full buffer refuses most attempts) is not copied again.
#[derive(Debug, Default)]
pub(crate) struct Offer(Option<Arc<[u8]>>);

impl Offer {
    /// The packet to write: `packet`, copied at its first attempt only. It is lent to the
    /// write ([`Machine::write_stream`], [`Channel::write_packet`]), not cloned into an
    /// [`Op`]: a refused attempt then costs no reference count.
    pub(crate) fn packet(&mut self, packet: &[u8]) -> &Arc<[u8]> {
        self.0.get_or_insert_with(|| Arc::from(packet))
    }

    /// The channel's answer to the write: true when it took the packet (the next offer is a
    /// new packet).
    pub(crate) fn answered(&mut self, reply: &Reply) -> bool {
        let accepted = matches!(reply, Reply::Stream(Ok(())));
        if accepted {
            self.0 = None;
        }
        accepted
    }

    /// The client starts over (a reset): nothing is on offer.
    pub(crate) fn withdraw(&mut self) {
        self.0 = None;
    }
}

/// A built-in client streaming a file into one channel.
pub struct Attached {
    pub channel: u32,
    pub feeder: Feeder,
    offer: Offer,
}

/// When `run` is over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopWhen {
    /// Never by itself (`serve`).
    Never,
    /// When every channel that ran a program has finished it (`run`, `soak`).
    ProgramsFinished,
}

pub struct Machine {
    channels: Vec<Channel>,
    feeders: Vec<Attached>,
    /// Simulated PLCs, at most one per channel (`machine::plc`).
    plcs: Vec<SimulatedPlc>,
    log: EventLog,
    stop_when: StopWhen,
    /// Per channel: how its last program finished.
    finishes: Vec<Option<Finish>>,
    cycle_times: CycleTimes,
    /// Wall time the channels' ticks waited for the program loader with the clock stopped,
    /// not yet taken by the runtime ([`Cycle::take_clock_stopped`]).
    clock_stopped: Duration,
    /// Notification watches evaluated after every tick (`watch`).
    watches: watch::Watches,
    /// The phases of the tick in progress, and the longest tick so far (`worst`), when
    /// `timing` is on.
    timing: worst::PhaseTiming,
    phases: worst::TickPhases,
    worst: Option<worst::WorstTick>,
    /// Per channel: the live view's record (off until the view drains it).
    live: Vec<live::ChannelRecord>,
}

impl Machine {
    /// Evaluate `w` after every tick from now on; false when [`watch::MAX_WATCHES`] are
    /// active.
    pub fn watch(&mut self, w: watch::Watch) -> bool {
        self.watches.add(&watch::WatchSlot::new(w))
    }

    pub fn new(channels: Vec<Channel>, log: EventLog, stop_when: StopWhen) -> Self {
        let n = channels.len();
        Machine {
            channels,
            feeders: Vec::new(),
            plcs: Vec::new(),
            log,
            stop_when,
            finishes: vec![None; n],
            cycle_times: CycleTimes::default(),
            clock_stopped: Duration::ZERO,
            watches: watch::Watches::default(),
            timing: worst::PhaseTiming::Off,
            phases: worst::TickPhases::new(n),
            worst: None,
            live: std::iter::repeat_with(live::ChannelRecord::default)
                .take(n)
                .collect(),
        }
    }

    /// Record every channel's path and stream text for the live view from now on
    /// (`serve --http`, before the first tick: a page that connects late sees everything).
    pub fn record_live(&mut self) {
        for (c, r) in self.channels.iter().zip(&mut self.live) {
            r.turn_on(c);
        }
    }

    pub fn set_stop_when(&mut self, w: StopWhen) {
        self.stop_when = w;
    }

    pub fn attach_feeder(&mut self, channel: u32, feeder: Feeder) {
        self.feeders.push(Attached {
            channel,
            feeder,
            offer: Offer::default(),
        });
    }

    /// Play a PLC for its channel (one per channel: a second replaces the first).
    pub fn attach_plc(&mut self, plc: SimulatedPlc) {
        self.plcs.retain(|p| p.channel() != plc.channel());
        self.plcs.push(plc);
    }

    pub fn plcs(&self) -> &[SimulatedPlc] {
        &self.plcs
    }

    pub fn feeders(&self) -> &[Attached] {
        &self.feeders
    }

    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// The channel by number; commands reach it only through [`Machine::apply`].
    fn channel_mut(&mut self, number: u32) -> Option<&mut Channel> {
        self.channels.get_mut((number as usize).checked_sub(1)?)
    }

    /// Split every tick into its phases from now on and keep the longest one
    /// ([`Machine::worst_tick`]).
    pub fn keep_worst_tick(&mut self) {
        self.timing = worst::PhaseTiming::On;
    }

    /// The longest tick since [`Machine::keep_worst_tick`], split into its phases, with what
    /// its slowest channel did.
    pub fn worst_tick(&self) -> Option<&worst::WorstTick> {
        self.worst.as_ref()
    }

    pub fn finishes(&self) -> &[Option<Finish>] {
        &self.finishes
    }

    /// Hand the remaining events to the log and wait for it to write them.
    pub fn finish_log(&mut self) -> std::io::Result<u64> {
        for c in &mut self.channels {
            c.close_event_stretches();
            c.events_mut().flush_to(&mut self.log);
        }
        std::mem::replace(&mut self.log, EventLog::disabled()).finish()
    }

    /// Events from every channel, in channel order within a tick.
    fn publish(&mut self) {
        if !self.log.enabled() {
            return;
        }
        for c in &mut self.channels {
            c.events_mut().flush_to(&mut self.log);
        }
    }

    /// Route one request to its channel (the runtime serves requests through this). The
    /// cycle-time statistics are the machine's, so their reset and the times in a status are
    /// filled in here.
    pub fn apply(&mut self, tick: &Tick, channel: u32, op: Op) -> Reply {
        // `matches!`, not `==`: comparing builds an `Op` to compare with and drops it, on
        // every request of every tick.
        if matches!(op, Op::Hmi(HmiOp::ResetCycleTimes)) {
            self.cycle_times = CycleTimes::default();
            return Reply::Done;
        }
        if let Op::Watch(slot) = &op {
            if self.channel_mut(channel).is_none() {
                return Reply::NoChannel;
            }
            return if self.watches.add(slot) {
                Reply::Done
            } else {
                Reply::Value(None)
            };
        }
        let Some((c, record)) = channel_and_record(&mut self.channels, &mut self.live, channel)
        else {
            return Reply::NoChannel;
        };
        if matches!(op, Op::DrainLive) {
            return Reply::Live(Box::new(record.drain(c)));
        }
        match op {
            Op::WriteStream(p) => write_packet(tick, c, record, &p),
            op => match c.apply(tick, op) {
                Reply::Status(mut s) => {
                    s.cycle_times = self.cycle_times;
                    Reply::Status(s)
                }
                r => r,
            },
        }
    }

    /// A stream write of a packet the caller keeps (a built-in client offering it again
    /// after a refusal): [`Machine::apply`] of [`Op::WriteStream`] without giving it away.
    pub fn write_stream(&mut self, tick: &Tick, channel: u32, packet: &Arc<[u8]>) -> Reply {
        match channel_and_record(&mut self.channels, &mut self.live, channel) {
            Some((c, record)) => write_packet(tick, c, record, packet),
            None => Reply::NoChannel,
        }
    }
}

/// Channel `number` (1-based) and its live record, when the machine has it.
fn channel_and_record<'a>(
    channels: &'a mut [Channel],
    live: &'a mut [live::ChannelRecord],
    number: u32,
) -> Option<(&'a mut Channel, &'a mut live::ChannelRecord)> {
    let i = (number as usize).wrapping_sub(1);
    Some((channels.get_mut(i)?, live.get_mut(i)?))
}

/// A stream write through the channel's door, and into the live record when taken.
fn write_packet(
    tick: &Tick,
    c: &mut Channel,
    record: &mut live::ChannelRecord,
    packet: &Arc<[u8]>,
) -> Reply {
    let reply = c.write_packet(tick, packet);
    // `matches!`, not `==`: no reply built to compare with, on every attempt.
    if matches!(reply, Reply::Stream(Ok(()))) {
        record.stream_written(packet, c);
    }
    reply
}

impl Cycle for Machine {
    type Request = Request;

    fn serve(&mut self, req: Request, tick: &Tick) {
        // The caller gave up waiting and already answered "not applied": leave it so.
        if !req.claim.take() {
            return;
        }
        let reply = self.apply(tick, req.channel, req.op);
        // A client that went away no longer needs its answer.
        let _ = req.reply.send(reply);
    }

    fn step(&mut self, tick: &Tick) -> Flow {
        let mut clock = worst::PhaseClock::start(self.timing);
        // The PLCs answer before the channels step, as the requests of the tick are served.
        for p in &mut self.plcs {
            if let Some(c) = self
                .channels
                .get_mut((p.channel() as usize).wrapping_sub(1))
            {
                p.tick(tick, c);
            }
        }
        for a in &mut self.feeders {
            let Some((c, record)) =
                channel_and_record(&mut self.channels, &mut self.live, a.channel)
            else {
                continue;
            };
            if let Some(packet) = a.feeder.poll(tick.index) {
                // Through the door like any client's write; a write the channel cannot take
                // (ERROR, no streaming program) is a refusal the feeder retries.
                let reply = write_packet(tick, c, record, a.offer.packet(packet));
                a.feeder.result(a.offer.answered(&reply));
            }
        }
        for ((i, c), record) in self.channels.iter_mut().enumerate().zip(&mut self.live) {
            let stopped = c.step(tick);
            self.clock_stopped += stopped;
            record.tick(tick, c);
            if let Some(f) = c.take_finish() {
                self.finishes[i] = Some(f);
            }
            // Virtual time: a wait for the loader is not the channel's work (runtime.rs).
            if let Some(d) = self.phases.channels.get_mut(i) {
                *d = clock.lap().saturating_sub(stopped);
            }
        }
        if !self.watches.is_empty() {
            let mut watches = std::mem::take(&mut self.watches);
            watches.evaluate(tick, self.channels.len(), |ch, op| self.apply(tick, ch, op));
            self.watches = watches;
        }
        self.phases.watches = clock.lap();
        self.publish();
        self.phases.events = clock.lap();
        if self.timing == worst::PhaseTiming::On {
            worst::WorstTick::consider(&mut self.worst, tick.index, &self.phases, &self.channels);
        }
        match self.stop_when {
            StopWhen::Never => Flow::Continue,
            StopWhen::ProgramsFinished => {
                let running = self
                    .channels
                    .iter()
                    .any(|c| matches!(c.state(), State::Active | State::Hold));
                let any_finished = self.finishes.iter().any(Option::is_some);
                if !running && any_finished {
                    Flow::Stop
                } else {
                    Flow::Continue
                }
            }
        }
    }

    fn take_clock_stopped(&mut self) -> Duration {
        std::mem::take(&mut self.clock_stopped)
    }

    fn record_work(&mut self, work: Duration) {
        self.cycle_times.record(work);
    }
}

#[cfg(test)]
mod tests {
    use super::{Machine, StopWhen};
    use crate::report::event::EventLog;
    use crate::runtime::{Clock, Cycle, Tick};
    use std::time::Duration;

    /// The phases are timed only once asked for: a soak or a run reads no clock for them.
    #[test]
    fn the_worst_tick_is_kept_only_after_keep_worst_tick() {
        let mut m = Machine::new(Vec::new(), EventLog::disabled(), StopWhen::Never);
        let tick = Tick::first(Duration::from_millis(1), Clock::Virtual);
        m.step(&tick);
        assert!(m.worst_tick().is_none());
        m.keep_worst_tick();
        m.step(&tick);
        assert_eq!(m.worst_tick().map(|w| w.tick), Some(tick.index));
    }
}
