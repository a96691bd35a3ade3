//! ncchannel: an emulated CNC channel of a TwinCAT 3 CNC / ISG kernel.
//!
//! Data flows one way through a tick: requests → stream → decoder → planner →
//! interpolator → events. Each room below owns one machine part; `vocab` is the floor of
//! words they share. See the README's architecture section for who may import whom.

pub mod ads;
pub mod bounded;
pub mod channel;
pub mod cli;
pub mod decoder;
pub mod diag;
pub mod dnc;
pub mod feeder;
pub mod geometry;
pub mod lang;
pub mod machine;
pub mod motion;
pub mod params;
pub mod queue;
pub mod report;
pub mod runtime;
pub mod setup;
pub mod soak;
pub mod source;
pub mod vocab;
