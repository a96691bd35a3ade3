//! The tick: the runtime's unit of time, carried by every event. A module of its own so the
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
}

impl Tick {
    /// Channel time in seconds, as the events carry it.
    pub fn seconds(&self) -> f64 {
        self.time.as_secs_f64()
    }
}
