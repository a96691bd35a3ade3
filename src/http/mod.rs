//! The live web view of `serve --http`: one embedded page, fed by Server-Sent Events from the
//! channels' status, with operator controls that go through the same door as ADS.
//!
//! Parts, one per file: [`server`] accepts page connections (at most
//! [`MAX_PAGE_CONNECTIONS`]) and routes requests; [`feed`] polls every channel through
//! [`CncBackend`] at [`FEED_PERIOD`] on a thread of its own and hands each update to the
//! connected pages; [`snapshot`] is what one update says; [`path`] keeps each channel's path
//! since its program started and cuts the stream's text into lines; [`preview`] runs a whole
//! program on a private copy of the channels; [`sse`] writes the updates to one page;
//! [`controls`] turns an operator's POST into [`crate::machine::Op`]s; [`page`] holds the
//! embedded page. Nothing here runs on the runtime's thread: a poll is an ordinary
//! request the tick serves, as an ADS read is, and a page that reads too slowly is dropped.

pub mod controls;
pub mod feed;
pub mod page;
pub mod path;
pub mod preview;
pub mod server;
pub mod snapshot;
pub mod sse;

use std::net::SocketAddr;
use std::time::Duration;

pub use server::{spawn, HttpHandle};

use crate::machine::remote::CncBackend;

/// Pages connected to the event stream at once; more are answered 503. Each costs one
/// thread and one bounded queue.
pub const MAX_PAGE_CONNECTIONS: usize = 8;
/// Connections at once (pages, event streams, control requests); more are closed at once.
pub const MAX_CONNECTIONS: usize = 32;
/// How often the feed polls the channels and sends an update: 20 Hz, smooth enough for a
/// DRO and a backplot, and one status request per channel per 50 ms for the runtime.
pub const FEED_PERIOD: Duration = Duration::from_millis(50);
/// Updates queued for one page; a page this far behind is dropped (it reconnects and
/// starts from the present), never buffered without bound.
pub const PAGE_QUEUE_UPDATES: usize = 16;
/// A write to a page that takes longer than this (the browser stopped reading) ends it.
pub const WRITE_TIMEOUT: Duration = Duration::from_secs(5);
/// A request head (and its body) that has not arrived whole within this is dropped: one
/// deadline for the whole request, not for each read, so a client trickling a byte at a time
/// holds a connection slot no longer than this.
pub const READ_TIMEOUT: Duration = Duration::from_secs(5);
/// Largest request head and body, bytes: the page sends nothing bigger than a program name.
pub const MAX_REQUEST_BYTES: usize = 8 * 1024;

/// Whether the page's operator controls may command the channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ControlAccess {
    /// Read-only view: every control request is refused with 403.
    Refused,
    /// `--http-controls`: start, hold, resume, reset, override, run from line, MDI and jog go
    /// through the door.
    Allowed,
}

/// The web view's settings.
#[derive(Debug, Clone)]
pub struct HttpConfig {
    pub bind: SocketAddr,
    /// A non-loopback `bind` is refused unless this is set (`serve --allow-non-loopback`).
    pub allow_non_loopback: bool,
    pub controls: ControlAccess,
    /// Further `Host` names (with or without `:port`) the view answers, for a reverse proxy
    /// (`serve --http-allow-host`); the bound address, `localhost`, `127.0.0.1` and `[::1]`
    /// with the bound port are always answered, any other `Host` gets 421 (DNS rebinding).
    pub allow_hosts: Vec<String>,
}

/// The backend the view reads and commands, shared by the feed and the control requests.
pub(crate) type Backend = std::sync::Arc<dyn CncBackend>;
