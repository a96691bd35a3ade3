//! ADS over TCP: the AMS/TCP codec, the CNC object table on AMS port 553, a server that
//! serves it to real clients (pyads, the `ads` crate, TwinCAT tools), and a client for
//! `ncchannel stream`.
//!
//! The object table reaches the channels only through [`backend::CncBackend`]; the runtime
//! implements it, and [`memory::MemoryBackend`] is an in-memory stand-in for tests.

pub mod backend;
pub mod channel_backend;
pub mod client;
pub mod frame;
pub mod memory;
pub mod objects;
pub mod payload;
pub mod result;
pub mod server;

pub use backend::{CncBackend, DeviceError, StreamFill, StreamWriteOutcome};
pub use frame::{AmsAddr, AmsNetId};
pub use result::AdsResult;
pub use server::{spawn, RouteEntry, ServerConfig, ServerHandle};
