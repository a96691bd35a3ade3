//! SIGINT and SIGTERM as an orderly stop for the commands that run until stopped (`serve`,
//! `run --realtime`, `soak --realtime`, `receive --listen`): the first signal sets a flag the
//! command polls at its next tick or accept; a second one exits at once with
//! [`exit::SECOND_SIGNAL`], the pattern signal-hook documents for
//! `flag::register_conditional_shutdown`.

use std::io;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::flag;

use super::exit;

/// The flag SIGINT and SIGTERM set.
#[derive(Debug, Clone)]
pub(crate) struct StopSignal(Arc<AtomicBool>);

impl StopSignal {
    /// Register the handlers. Called once per process by the command that runs until stopped.
    pub fn install() -> io::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        for sig in [SIGINT, SIGTERM] {
            // Registered first, so it sees the flag as the previous signal left it: set means
            // this is the second signal.
            flag::register_conditional_shutdown(
                sig,
                i32::from(exit::SECOND_SIGNAL),
                Arc::clone(&stop),
            )?;
            flag::register(sig, Arc::clone(&stop))?;
        }
        Ok(StopSignal(stop))
    }

    /// Whether a signal asked for a stop.
    pub fn raised(&self) -> bool {
        self.0.load(Ordering::Acquire)
    }

    /// The flag itself, for [`crate::runtime::Runtime::stop_on`].
    pub(crate) fn flag(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.0)
    }
}
