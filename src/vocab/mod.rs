//! The ground floor: the words every layer shares — time, modes and states, axes, `#FLUSH`,
//! cache operations, the ADS endpoint's ids and defaults, cycle statistics, the real-time mode's settings, the variables'
//! memory budget. It imports nothing
//! from the crate but itself; every other room may import it.

pub mod ams;
pub mod axis;
pub mod event;
pub mod flush;
pub mod mode;
pub mod realtime;
pub mod stats;
pub mod techno;
pub(crate) mod tick;
pub mod vars;
