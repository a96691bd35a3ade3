//! How a receiver is asked to stop: the first request lets the transfers in progress finish
//! within a grace period, the second cuts them at once (SIGINT/SIGTERM once, then twice).

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

/// How urgently a stop was asked for; each request goes one step further.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum StopLevel {
    /// No stop asked for.
    Run,
    /// Take no new transfer; the ones in progress get the grace period.
    Graceful,
    /// Cut the transfers in progress now (their open programs are dropped).
    Now,
}

/// The stop requests, shared between whoever asks (a signal thread) and the listener.
#[derive(Debug, Clone, Default)]
pub struct StopRequest(Arc<AtomicU8>);

impl StopRequest {
    pub fn new() -> Self {
        Self::default()
    }

    /// One more request: `Run` → `Graceful` → `Now` (and `Now` stays); returns the new level.
    pub fn escalate(&self) -> StopLevel {
        let before = self
            .0
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, |l| {
                Some((l + 1).min(2))
            })
            .unwrap_or(2);
        level((before + 1).min(2))
    }

    pub fn level(&self) -> StopLevel {
        level(self.0.load(Ordering::Acquire))
    }
}

fn level(v: u8) -> StopLevel {
    match v {
        0 => StopLevel::Run,
        1 => StopLevel::Graceful,
        _ => StopLevel::Now,
    }
}
