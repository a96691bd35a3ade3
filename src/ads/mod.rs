//! ADS over TCP: the AMS/TCP codec, the CNC's tasks as a real TwinCAT 3 CNC has them (COM
//! 553, GEO 551, SDA 552, the PLC's HLI 851), a server that serves them to real clients
//! (pyads, the `ads` crate, Node ads-client, TwinSharp), and a client for `ncchannel stream`.
//!
//! The object table reaches the channels only through [`backend::CncBackend`], one door:
//! `call(channel, Op) → Reply`, the channel's own vocabulary (`crate::machine`). The runtime
//! implements it beside the machine (`crate::machine::remote::ChannelBackend`); the tests
//! drive real channels through it too, so there is no stand-in channel to drift from the
//! real one.

pub mod backend;
pub mod client;
pub mod com;
pub(crate) mod description;
pub mod frame;
pub(crate) mod geo;
pub(crate) mod hli;
pub mod objects;
pub mod payload;
pub(crate) mod plc_types;
pub mod result;
pub mod route_service;
pub mod routes;
pub(crate) mod sda;
pub mod server;
mod slots;
pub(crate) mod sum;
pub(crate) mod symbols;
pub(crate) mod system;
#[cfg(test)]
pub(crate) mod testing;

pub use crate::vocab::ams::{AmsNetId, RouteEntry};
pub use backend::{CncBackend, DeviceError};
pub use frame::AmsAddr;
pub use result::AdsResult;
pub use server::{spawn, ServerConfig, ServerHandle};
pub use slots::{EVICT_QUIET, FIRST_REQUEST_GRACE};
