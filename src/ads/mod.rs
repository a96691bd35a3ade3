//! ADS over TCP: the AMS/TCP codec, the CNC's tasks as a real TwinCAT 3 CNC has them (COM
//! 553, GEO 551, SDA 552, the PLC's HLI 851), a server that serves them to real clients
//! (pyads, the `ads` crate, Node ads-client, TwinSharp), and a client for `ncchannel stream`.
//!
//! The object table reaches the channels only through [`backend::CncBackend`]; the runtime
//! implements it, and [`memory::MemoryBackend`] is an in-memory stand-in for tests.

pub mod backend;
pub mod channel_backend;
pub mod client;
pub mod com;
pub mod description;
pub mod frame;
pub mod geo;
pub mod hli;
pub mod memory;
pub mod objects;
pub mod payload;
pub mod result;
pub mod sda;
pub mod server;

pub use crate::vocab::ams::{AmsNetId, RouteEntry};
pub use backend::{CncBackend, DeviceError, StreamFill, StreamWriteOutcome};
pub use frame::AmsAddr;
pub use result::AdsResult;
pub use server::{spawn, ServerConfig, ServerHandle};
