//! The tick: the runtime's unit of time, carried by every event, and the clock it runs on. A module of its own so the
//! event log and the runtime both use it without depending on each other.

use std::time::Duration;

/// The tick being run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tick {
    /// Tick number, from 0.
    pub index: u64,
    /// The cycle time.
    pub period: Duration,
    /// Channel time at this tick: `index × period`, in either clock.
    pub time: Duration,
    /// How time passes for this tick: what a wait for the program loader means (virtual
    /// time stops the clock, real time ticks on).
    pub clock: Clock,
}

/// How time passes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Clock {
    /// Ticks run back to back; channel time advances one period per tick. Deterministic and
    /// faster than real time, for soak tests and the demo.
    Virtual,
    /// Tick `k` starts at `start + k × period`, waited for with spin_sleep.
    RealTime,
}

impl Tick {
    /// Tick 0, before the first step: where set-up commands (a program start, a trace) are
    /// applied.
    pub fn first(period: Duration, clock: Clock) -> Tick {
        Tick {
            index: 0,
            period,
            time: Duration::ZERO,
            clock,
        }
    }

    /// Channel time in seconds, as the events carry it.
    pub fn seconds(&self) -> f64 {
        self.time.as_secs_f64()
    }
}
