//! The machine's worst tick and what it was doing: each tick's time split into its phases
//! (the PLCs and built-in clients, each channel's step, the notification watches, the event
//! log), and, for the longest tick so far, those phases with the slowest channel's state and
//! block. `bench` reports it (README "The cycle"): a tick over the period names its culprit.

use std::fmt;
use std::time::{Duration, Instant};

use crate::channel::{Channel, State};

/// One tick's phases, measured as the machine steps (a clock read between phases).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TickPhases {
    /// The simulated PLCs and the built-in stream clients.
    pub plcs_and_feeders: Duration,
    /// Each channel's step, in channel order.
    pub channels: Vec<Duration>,
    /// The notification watches evaluated after the channels.
    pub watches: Duration,
    /// The channels' events handed to the event log.
    pub events: Duration,
}

impl TickPhases {
    pub(super) fn new(channels: usize) -> Self {
        TickPhases {
            channels: vec![Duration::ZERO; channels],
            ..TickPhases::default()
        }
    }

    pub fn total(&self) -> Duration {
        self.plcs_and_feeders + self.channels.iter().sum::<Duration>() + self.watches + self.events
    }

    /// The slowest channel: its index and time.
    fn slowest(&self) -> Option<(usize, Duration)> {
        self.channels
            .iter()
            .copied()
            .enumerate()
            .max_by_key(|&(_, d)| d)
    }
}

/// Whether the machine splits its ticks into phases and keeps the worst one. A split costs a
/// clock read per channel and phase, a fifth of a virtual-time tick's work, so only `bench`,
/// which reports the worst tick, turns it on ([`super::Machine::keep_worst_tick`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum PhaseTiming {
    #[default]
    Off,
    On,
}

/// A running split of one tick into phases: each [`PhaseClock::lap`] is the time since the
/// last (zero when the timing is off: no clock is read).
#[derive(Debug)]
pub(super) struct PhaseClock(Option<Instant>);

impl PhaseClock {
    pub(super) fn start(timing: PhaseTiming) -> Self {
        PhaseClock((timing == PhaseTiming::On).then(Instant::now))
    }

    pub(super) fn lap(&mut self) -> Duration {
        let Some(last) = &mut self.0 else {
            return Duration::ZERO;
        };
        let now = Instant::now();
        let d = now.saturating_duration_since(*last);
        *last = now;
        d
    }
}

/// What the slowest channel of the worst tick was at when the tick ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChannelAt {
    /// 1-based channel number.
    pub channel: usize,
    pub state: State,
    /// The main program, if one runs.
    pub program: Option<String>,
    /// The block in execution: its program, ISG block counter, `N` number and byte offset.
    pub block: Option<(String, u64, Option<u32>, u64)>,
    /// Blocks executed so far.
    pub blocks: u64,
}

/// The longest tick of the run so far.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WorstTick {
    /// The tick's number.
    pub tick: u64,
    pub phases: TickPhases,
    /// The phases' sum, kept to compare each tick with.
    total: Duration,
    pub slowest: Option<ChannelAt>,
}

impl WorstTick {
    /// Keep `phases` of tick `tick` when it is longer than `worst`; the slowest channel's
    /// state is read then only (a status costs microseconds; a new maximum is rare).
    pub(super) fn consider(
        worst: &mut Option<WorstTick>,
        tick: u64,
        phases: &TickPhases,
        channels: &[Channel],
    ) {
        let total = phases.total();
        if worst.as_ref().is_some_and(|w| w.total >= total) {
            return;
        }
        let slowest = phases.slowest().and_then(|(i, _)| {
            let s = channels.get(i)?.status();
            Some(ChannelAt {
                channel: i + 1,
                state: s.state,
                program: s.program,
                block: s
                    .active_block
                    .map(|b| (b.prog.to_string(), b.counter, b.n, b.offset)),
                blocks: s.blocks,
            })
        });
        *worst = Some(WorstTick {
            tick,
            phases: phases.clone(),
            total,
            slowest,
        });
    }
}

fn us(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

impl fmt::Display for WorstTick {
    /// `tick 1234: 1834.2 µs; channel 2 1790.0 µs (Active, program main.nc, block 17 N40 of
    /// sub.nc at byte 5678, 16 blocks executed); PLCs and clients 3.1 µs, notifications 20.3
    /// µs, events 0.4 µs`
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = &self.phases;
        write!(f, "tick {}: {:.1} µs", self.tick, us(self.total))?;
        if let (Some((i, d)), Some(c)) = (p.slowest(), &self.slowest) {
            write!(f, "; channel {} {:.1} µs ({:?}", i + 1, us(d), c.state)?;
            if let Some(prog) = &c.program {
                write!(f, ", program {prog}")?;
            }
            if let Some((prog, counter, n, offset)) = &c.block {
                write!(f, ", block {counter}")?;
                if let Some(n) = n {
                    write!(f, " N{n}")?;
                }
                write!(f, " of {prog} at byte {offset}")?;
            }
            write!(f, ", {} blocks executed)", c.blocks)?;
        }
        write!(
            f,
            "; PLCs and clients {:.1} µs, notifications {:.1} µs, events {:.1} µs",
            us(p.plcs_and_feeders),
            us(p.watches),
            us(p.events)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_longer_tick_replaces_the_worst_and_the_slowest_channel_is_named() {
        let mut worst = None;
        let mut p = TickPhases::new(2);
        p.channels = vec![Duration::from_micros(10), Duration::from_micros(900)];
        p.watches = Duration::from_micros(5);
        WorstTick::consider(&mut worst, 7, &p, &[]);
        let shorter = TickPhases::new(2);
        WorstTick::consider(&mut worst, 8, &shorter, &[]);
        let w = worst.clone().unwrap();
        assert_eq!((w.tick, w.phases.total()), (7, Duration::from_micros(915)));
        assert_eq!(w.phases.slowest(), Some((1, Duration::from_micros(900))));
        let text = w.to_string();
        assert!(text.starts_with("tick 7: 915.0 µs;"), "{text}");
        assert!(text.contains("notifications 5.0 µs"), "{text}");
    }
}
