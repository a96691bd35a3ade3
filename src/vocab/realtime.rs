//! The real-time mode's settings, read by runtime.toml (`params`) and applied by the runtime
//! (`runtime::realtime`): the words both name.

use serde::Deserialize;

/// The real-time scheduling policy of the runtime thread (sched(7)).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Policy {
    /// SCHED_FIFO: runs until it blocks or a higher priority wakes (what cyclictest uses).
    #[default]
    Fifo,
    /// SCHED_RR: SCHED_FIFO with a time slice among threads of the same priority.
    Rr,
}

impl Policy {
    pub fn name(self) -> &'static str {
        match self {
            Policy::Fifo => "SCHED_FIFO",
            Policy::Rr => "SCHED_RR",
        }
    }

    /// The name cyclictest's `--policy` takes.
    pub fn cyclictest_name(self) -> &'static str {
        match self {
            Policy::Fifo => "fifo",
            Policy::Rr => "rr",
        }
    }
}

/// Lowest and highest real-time priority of SCHED_FIFO and SCHED_RR on Linux (sched(7)).
pub const PRIORITIES: std::ops::RangeInclusive<u8> = 1..=99;

/// The real-time mode: runtime.toml's `[realtime]`, overridden by the command line's
/// `--rt-…` options. The default is off: normal scheduling, no pinning, no locked memory.
#[derive(Debug, Clone, Default, PartialEq, Eq, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RealtimeConfig {
    /// SCHED_FIFO (default) or SCHED_RR, applied when `priority` is given.
    pub policy: Policy,
    /// Real-time priority 1 ... 99; absent = normal scheduling (SCHED_OTHER).
    pub priority: Option<u8>,
    /// The CPU the runtime thread runs on; every other thread is kept off it.
    pub cpu: Option<usize>,
    /// Lock all memory (`mlockall`, current and future) with the stack and a heap reserve
    /// faulted in, so no page fault lands in a tick.
    pub lock_memory: bool,
    /// A part the system refuses stops the command (exit 5) instead of a warning.
    pub required: bool,
}

impl RealtimeConfig {
    /// Whether any part of the mode is asked for.
    pub fn is_on(&self) -> bool {
        self.priority.is_some() || self.cpu.is_some() || self.lock_memory
    }

    /// The key and reason of a bad setting (`priority` out of 1 ... 99).
    pub fn check(&self) -> Result<(), (&'static str, String)> {
        match self.priority {
            Some(p) if !PRIORITIES.contains(&p) => Err((
                "priority",
                format!(
                    "{p} is not in {} ... {}",
                    PRIORITIES.start(),
                    PRIORITIES.end()
                ),
            )),
            _ => Ok(()),
        }
    }

    /// What the mode asks for, in words: `SCHED_FIFO 80, CPU 1, memory locked`.
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if let Some(p) = self.priority {
            parts.push(format!("{} {p}", self.policy.name()));
        }
        if let Some(c) = self.cpu {
            parts.push(format!("CPU {c}"));
        }
        if self.lock_memory {
            parts.push("memory locked".to_string());
        }
        if parts.is_empty() {
            "off".to_string()
        } else {
            parts.join(", ")
        }
    }
}
