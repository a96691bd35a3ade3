//! What a run tells the outside: cycle statistics, the JSON Lines event log and the report.

pub mod event;
pub mod plot;
pub mod progress;
pub mod summary;
