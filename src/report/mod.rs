//! What a run tells the outside: cycle statistics, the JSON Lines event log, the report and
//! the pictures.

pub mod event;
pub(crate) mod lateness;
pub mod picture;
pub(crate) mod plot;
pub(crate) mod progress;
pub mod summary;
