//! ncchannel: an emulated CNC channel of a TwinCAT 3 CNC / ISG kernel.
//!
//! Data flows one way through a tick: requests → stream → decoder → planner →
//! interpolator → events. Each room below owns one machine part; see the
//! README's architecture section for who may talk to whom.

pub mod cli;
pub mod diag;
pub mod dnc;
pub mod feeder;
pub mod lang;
pub mod params;
pub mod report;
pub mod runtime;
pub mod source;
