//! What a run tells the outside: cycle statistics, the JSON Lines event log and the report.

pub mod event;
pub(crate) mod event_writer;
pub(crate) mod plot;
pub(crate) mod progress;
pub mod summary;
