//! SIGINT and SIGTERM as an orderly stop for the commands that run until stopped (`serve`,
//! `run --realtime`, `soak --realtime`, `receive --listen`): the first signal sets a flag the
//! command polls at its next tick or accept; a second one exits at once with
//! [`exit::SECOND_SIGNAL`], the pattern signal-hook documents for
//! `flag::register_conditional_shutdown`.

use std::io;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::flag;

use super::exit;

/// The flag SIGINT and SIGTERM set, and which of them came last.
#[derive(Debug, Clone)]
pub(crate) struct StopSignal {
    stop: Arc<AtomicBool>,
    /// The number of the signal that came (0: none yet).
    which: Arc<AtomicUsize>,
}

impl StopSignal {
    /// Register the handlers. Called once per process by the command that runs until stopped.
    pub fn install() -> io::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let which = Arc::new(AtomicUsize::new(0));
        for sig in [SIGINT, SIGTERM] {
            // Registered first, so it sees the flag as the previous signal left it: set means
            // this is the second signal.
            flag::register_conditional_shutdown(
                sig,
                i32::from(exit::SECOND_SIGNAL),
                Arc::clone(&stop),
            )?;
            flag::register_usize(sig, Arc::clone(&which), sig as usize)?;
            flag::register(sig, Arc::clone(&stop))?;
        }
        Ok(StopSignal { stop, which })
    }

    /// Whether a signal asked for a stop.
    pub fn raised(&self) -> bool {
        self.stop.load(Ordering::Acquire)
    }

    /// The signal that asked for the stop, by name and with the exit code a shell gives a
    /// process it ended (128 + its number): `("SIGINT", 130)`, `("SIGTERM", 143)`.
    pub fn which(&self) -> Option<(&'static str, u8)> {
        match self.which.load(Ordering::Acquire) {
            n if n == SIGINT as usize => Some(("SIGINT", 128 + SIGINT as u8)),
            n if n == SIGTERM as usize => Some(("SIGTERM", 128 + SIGTERM as u8)),
            _ => self.raised().then_some(("a signal", exit::SECOND_SIGNAL)),
        }
    }

    /// The flag itself, for [`crate::runtime::Runtime::stop_on`].
    pub(crate) fn flag(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.stop)
    }
}
