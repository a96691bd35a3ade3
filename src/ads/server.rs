//! The ADS/TCP server: accepts connections, frames requests, answers them through the object
//! table, and pushes DeviceNotification frames.
//!
//! One thread per connection answering its requests in order (at most `max_connections`,
//! default 64; beyond that the connection quiet for longest gives its slot up, or the
//! newcomer is closed: `slots.rs`) and reading them while it has nothing to answer, one
//! helper thread per connection that reads the requests behind an answer that takes long,
//! stamping each with its arrival ([`Inbox`]), one writer thread per connection draining its
//! bounded send queue, plus one notification
//! thread per connection that has notification handles on what is not evaluated in the
//! cycle (every object of the COM, GEO, SDA and HLI tables is, `machine::watch`; the
//! description table, the uploads and the system service are read whole). Channel calls may
//! block for up to a runtime tick; that only holds up the connection that asked. The limits
//! that keep a hostile or careless client from hurting the others or the cycle are explained
//! in docs/ads-limits.md. Compatibility rules are in docs/ads-wire.md; each is marked `rule n` below.

use std::collections::{HashMap, VecDeque};
use std::io::{self, Read, Write};
use std::net::{IpAddr, Ipv4Addr, Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU16, AtomicU32, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use super::backend::CncBackend;
use super::frame::{
    self, AmsAddr, AmsHeader, CommandId, Frame, AMS_ERR_MACHINE_NOT_FOUND, AMS_ERR_PORT_NOT_FOUND,
    FLAGS_REQUEST,
};
use super::objects::Devices;
use super::payload::{self, response, NotificationRequest, Request};
use super::result::AdsResult;
use super::route_service::{self, Identity, RouteService, ROUTE_SERVICE_PORT};
use super::routes::RouteTable;
use super::slots::{Admission, Progress, Slots, EVICT_QUIET, FIRST_REQUEST_GRACE};
use super::sum;
use crate::machine::watch::{Delivery, Watch};
use crate::vocab::ams::{
    AmsNetId, RouteEntry, DEFAULT_BIND, DEFAULT_IDLE_TIMEOUT, DEFAULT_MAX_CONNECTIONS,
    DEFAULT_MAX_FRAME_BYTES, DEFAULT_MAX_NOTIFICATIONS, DEFAULT_MAX_NOTIFICATIONS_TOTAL,
    DEFAULT_NET_ID, DEFAULT_NOTIFICATION_SAMPLES_PER_S,
    DEFAULT_NOTIFICATION_SAMPLES_PER_S_PER_CONNECTION,
};

/// Default bound on the bytes waiting in one connection's send queue.
pub(crate) const DEFAULT_MAX_SEND_QUEUE_BYTES: usize = 1 << 20;
/// A write to a client that takes longer than this (its receive window stays shut) ends
/// the connection.
pub(crate) const WRITE_TIMEOUT: Duration = Duration::from_secs(5);
/// Distinct source NetIds a connection logs a line about, for each kind of refused frame;
/// beyond that one summary line at most.
const MAX_LOGGED_UNROUTED: usize = 16;
/// Notification cycle times are clamped to this range.
pub(crate) const MIN_NOTIFICATION_CYCLE: Duration = Duration::from_millis(1);
pub(crate) const MAX_NOTIFICATION_CYCLE: Duration = Duration::from_secs(10);

/// Server settings (the runtime config's `[ads]` table maps onto this).
#[derive(Debug, Clone)]
pub struct ServerConfig {
    /// Where to listen. Default 127.0.0.1:48898.
    pub bind: SocketAddr,
    /// A non-loopback `bind` is refused unless this is set (and then logs a warning): the
    /// server moves machine axes on request and has no authentication.
    pub allow_non_loopback: bool,
    /// This device's NetId. `Some`: frames addressed to another NetId than this one or its
    /// loopback alias 127.0.0.1.1.1 get AMS error 7 (logged once per source and connection).
    /// `None`: any target NetId is accepted (a single-device emulator).
    pub net_id: Option<AmsNetId>,
    /// Also answer the ADS route service (UDP, identify and add-route) on the bind address:
    /// port 48899, or a free port when `bind`'s port is 0.
    pub route_service: bool,
    /// Upper bound of the AMS/TCP length field; longer frames close the connection.
    pub max_frame_bytes: usize,
    /// Simultaneous connections; more are closed at once.
    pub max_connections: usize,
    /// Notification handles per connection; more are answered 0x716.
    pub max_notifications: usize,
    /// Notification handles over all connections; more are answered 0x716.
    pub max_notifications_total: usize,
    /// Notification samples per second over all connections (each handle costs one sample
    /// per cycle time); a handle that would exceed it is answered 0x716.
    pub notification_samples_per_s: u64,
    /// Notification samples per second of one connection; a handle that would exceed it is
    /// answered 0x716 to that connection only.
    pub notification_samples_per_s_per_connection: u64,
    /// A connection that has not completed a frame for this long is closed when it is in the
    /// middle of a frame (a slow or stalled sender) or holds no notification handles (an
    /// idle client holding a slot). A client with notifications may stay silent for ever.
    pub idle_timeout: Duration,
    /// Bytes of responses and notifications waiting for one client; a client that lets
    /// more pile up (it does not read) is disconnected, with a log line.
    pub max_send_queue_bytes: usize,
    /// Route allow-list; empty = allow all. A client is served when its peer IP or the
    /// source NetId of its frame is listed; others are dropped silently (after a log line),
    /// as a router without a route drops them. Routes added through the route service join
    /// it at run time (`routes.rs`).
    pub allow: Vec<RouteEntry>,
}

impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            bind: DEFAULT_BIND,
            allow_non_loopback: false,
            net_id: None,
            route_service: false,
            max_frame_bytes: DEFAULT_MAX_FRAME_BYTES,
            max_connections: DEFAULT_MAX_CONNECTIONS,
            max_notifications: DEFAULT_MAX_NOTIFICATIONS,
            max_notifications_total: DEFAULT_MAX_NOTIFICATIONS_TOTAL,
            notification_samples_per_s: DEFAULT_NOTIFICATION_SAMPLES_PER_S,
            notification_samples_per_s_per_connection:
                DEFAULT_NOTIFICATION_SAMPLES_PER_S_PER_CONNECTION,
            idle_timeout: DEFAULT_IDLE_TIMEOUT,
            max_send_queue_bytes: DEFAULT_MAX_SEND_QUEUE_BYTES,
            allow: Vec::new(),
        }
    }
}

/// A running server; `shutdown()` (or drop) stops it and closes every connection.
pub struct ServerHandle {
    local_addr: SocketAddr,
    shared: Arc<Shared>,
    accept: Option<JoinHandle<()>>,
    route_service: Option<RouteService>,
}

impl ServerHandle {
    /// The address actually bound (useful with port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Where the route service answers (UDP), when it runs.
    pub fn route_service_addr(&self) -> Option<SocketAddr> {
        self.route_service.as_ref().map(RouteService::local_addr)
    }

    /// The route table: the configured allow-list and the routes added since.
    pub fn routes(&self) -> Vec<RouteEntry> {
        self.shared.routes.entries()
    }

    /// Number of connections currently served.
    pub fn connections(&self) -> usize {
        self.shared.active.load(Ordering::SeqCst)
    }

    /// Stop accepting, close all connections, and wait for the accept thread.
    pub fn shutdown(mut self) {
        self.stop();
    }

    fn stop(&mut self) {
        if self.shared.stopping.swap(true, Ordering::SeqCst) {
            return;
        }
        if let Some(mut r) = self.route_service.take() {
            r.stop();
        }
        // Wake the blocking accept() with a connection of our own.
        let wake = match self.local_addr.ip() {
            ip if ip.is_unspecified() => {
                SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), self.local_addr.port())
            }
            _ => self.local_addr,
        };
        let _ = TcpStream::connect_timeout(&wake, Duration::from_millis(500));
        self.shared.slots.close_all();
        if let Some(h) = self.accept.take() {
            let _ = h.join();
        }
    }
}

impl Drop for ServerHandle {
    fn drop(&mut self) {
        self.stop();
    }
}

/// State shared by the accept thread and the connections.
struct Shared {
    config: ServerConfig,
    /// The tasks behind the AMS ports (one TCP port for all, as a TwinCAT router).
    devices: Devices,
    stopping: AtomicBool,
    active: AtomicUsize,
    /// Every open connection: closed on shutdown, the quietest evicted when full.
    slots: Slots,
    /// Next AMS port handed out by the router "port connect" command.
    next_router_port: AtomicU16,
    /// Who may talk to the server: the allow-list and the routes added at run time.
    routes: Arc<RouteTable>,
    /// Notification handles and sample rate in use over all connections.
    budget: Mutex<NotifyBudget>,
    /// Log lines that a client can provoke at will, at most one a second each.
    refused_log: RateLimitedLog,
    router_log: RateLimitedLog,
    /// Frames for another device's NetId.
    target_log: RateLimitedLog,
    evicted_log: RateLimitedLog,
    /// The line each connection may write when it ends (why), all together at
    /// most [`CONN_LINES_PER_S`] a second: a thousand connections ending at once cost a
    /// few lines and a count, not a thousand lines.
    conn_log: RateLimitedLog,
}

/// Lines a second of [`Shared::conn_log`].
const CONN_LINES_PER_S: u64 = 10;

/// What the notification handles of all connections cost together.
#[derive(Debug, Default)]
struct NotifyBudget {
    handles: usize,
    /// Samples per second, in millihertz (a 1 ms handle costs 1 000 000).
    rate_mhz: u64,
}

/// The sample rate of one handle in millihertz.
fn rate_mhz(cycle: Duration) -> u64 {
    let ns = cycle.as_nanos().max(1);
    u64::try_from(1_000_000_000_000u128 / ns).unwrap_or(u64::MAX)
}

impl Shared {
    /// Take one handle of `cycle` from the server's budget, or say it is spent.
    fn reserve(&self, cycle: Duration) -> bool {
        let mut b = lock(&self.budget);
        let rate = rate_mhz(cycle);
        let limit = self.config.notification_samples_per_s.saturating_mul(1000);
        if b.handles >= self.config.max_notifications_total
            || b.rate_mhz.saturating_add(rate) > limit
        {
            return false;
        }
        b.handles += 1;
        b.rate_mhz += rate;
        true
    }

    /// Give back what removed handles took.
    fn release<'a>(&self, removed: impl IntoIterator<Item = &'a Notification>) {
        let mut b = lock(&self.budget);
        for n in removed {
            b.handles = b.handles.saturating_sub(1);
            b.rate_mhz = b.rate_mhz.saturating_sub(rate_mhz(n.cycle));
        }
    }
}

/// A log line a client can trigger as often as it sends: written at most `per_second` times
/// a second, with the count of the lines left out since.
struct RateLimitedLog {
    per_second: u64,
    state: Mutex<RateState>,
}

#[derive(Default)]
struct RateState {
    /// Start of the current one-second window and lines written in it.
    window: Option<Instant>,
    written: u64,
    /// Lines left out since the last one written.
    skipped: u64,
}

impl RateLimitedLog {
    const WINDOW: Duration = Duration::from_secs(1);

    fn new(per_second: u64) -> Self {
        RateLimitedLog {
            per_second,
            state: Mutex::new(RateState::default()),
        }
    }

    fn log(&self, msg: impl std::fmt::Display) {
        let mut st = lock(&self.state);
        let now = Instant::now();
        if st
            .window
            .is_none_or(|t| now.duration_since(t) >= Self::WINDOW)
        {
            st.window = Some(now);
            st.written = 0;
        }
        if st.written >= self.per_second {
            st.skipped += 1;
            return;
        }
        st.written += 1;
        let skipped = std::mem::take(&mut st.skipped);
        drop(st);
        if skipped > 0 {
            log(format_args!(
                "{msg} (and {skipped} more like it not logged)"
            ));
        } else {
            log(msg);
        }
    }
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// One line of the server's log (the `log` facade; `ncchannel` writes it to stderr).
fn log(msg: impl std::fmt::Display) {
    log::warn!("{msg}");
}

/// Bind and start serving `backend`.
pub fn spawn(config: ServerConfig, backend: Arc<dyn CncBackend>) -> io::Result<ServerHandle> {
    if !config.bind.ip().is_loopback() {
        if !config.allow_non_loopback {
            return Err(io::Error::new(
                io::ErrorKind::PermissionDenied,
                format!(
                    "refusing to bind ADS to non-loopback address {} without the explicit opt-in",
                    config.bind
                ),
            ));
        }
        log(format_args!(
            "listening on non-loopback {}: any host that reaches it can command the channel",
            config.bind
        ));
    }
    let listener = TcpListener::bind(config.bind)?;
    let local_addr = listener.local_addr()?;
    let max_connections = config.max_connections;
    let routes = Arc::new(RouteTable::new(&config.allow));
    let route_log = Arc::new(RateLimitedLog::new(1));
    // Without its UDP port (another router or server holds it) the server still serves
    // TCP: the route service is a convenience, and the listening line then names none.
    let route_service = if config.route_service {
        spawn_route_service(&config, local_addr, Arc::clone(&routes), route_log)
            .map_err(|e| log(format_args!("{e}: not started")))
            .ok()
    } else {
        None
    };
    let shared = Arc::new(Shared {
        config,
        routes,
        target_log: RateLimitedLog::new(1),
        devices: Devices::new(backend),
        stopping: AtomicBool::new(false),
        active: AtomicUsize::new(0),
        slots: Slots::new(max_connections),
        next_router_port: AtomicU16::new(32768),
        budget: Mutex::new(NotifyBudget::default()),
        refused_log: RateLimitedLog::new(1),
        router_log: RateLimitedLog::new(1),
        evicted_log: RateLimitedLog::new(1),
        conn_log: RateLimitedLog::new(CONN_LINES_PER_S),
    });
    let accept_shared = Arc::clone(&shared);
    let accept = std::thread::Builder::new()
        .name("ads-accept".into())
        .spawn(move || accept_loop(listener, accept_shared))?;
    Ok(ServerHandle {
        local_addr,
        shared,
        accept: Some(accept),
        route_service,
    })
}

/// The route service on the TCP server's address (already checked: loopback, or allowed),
/// port 48899, or a free one when the TCP port was picked (port 0: tests, several servers).
fn spawn_route_service(
    config: &ServerConfig,
    tcp: SocketAddr,
    routes: Arc<RouteTable>,
    log: Arc<RateLimitedLog>,
) -> io::Result<RouteService> {
    let port = if config.bind.port() == 0 {
        0
    } else {
        ROUTE_SERVICE_PORT
    };
    let me = Identity {
        net_id: config.net_id.unwrap_or(DEFAULT_NET_ID),
        host_name: route_service::host_name(),
    };
    let bind = SocketAddr::new(tcp.ip(), port);
    RouteService::spawn(bind, me, routes, move |line| log.log(line))
        .map_err(|e| io::Error::new(e.kind(), format!("route service on UDP {bind}: {e}")))
}

fn accept_loop(listener: TcpListener, shared: Arc<Shared>) {
    for stream in listener.incoming() {
        if shared.stopping.load(Ordering::SeqCst) {
            return;
        }
        let stream = match stream {
            Ok(s) => s,
            Err(e) => {
                log(format_args!("accept failed: {e}"));
                std::thread::sleep(Duration::from_millis(10));
                continue;
            }
        };
        let peer = match stream.peer_addr() {
            Ok(p) => p,
            Err(_) => continue,
        };
        let ip_listed = shared.routes.routes_ip(peer.ip());
        if !ip_listed && !shared.routes.has_net_id_routes() {
            shared
                .refused_log
                .log(format_args!("no route for {peer}: connection closed"));
            let _ = stream.shutdown(Shutdown::Both);
            continue;
        }
        let Some((id, progress)) = admit(&shared, &stream, peer) else {
            let _ = stream.shutdown(Shutdown::Both);
            continue;
        };
        shared.active.fetch_add(1, Ordering::SeqCst);
        let conn_shared = Arc::clone(&shared);
        let spawned = std::thread::Builder::new()
            .name(format!("ads-conn-{id}"))
            .spawn(move || {
                let conn = Conn {
                    peer,
                    ip_routed: ip_listed,
                    progress,
                };
                let ended = serve_connection(stream, &conn, &conn_shared);
                // The server's own stop and an eviction (logged when it happened) are no
                // fault of the client's.
                let quiet = conn_shared.stopping.load(Ordering::SeqCst)
                    || conn_shared.slots.was_evicted(id);
                if let (Err(e), false) = (ended, quiet) {
                    conn_shared.conn_log.log(format_args!("{peer}: {e}"));
                }
                conn_shared.slots.leave(id);
                conn_shared.active.fetch_sub(1, Ordering::SeqCst);
            });
        if spawned.is_err() {
            shared.slots.leave(id);
            shared.active.fetch_sub(1, Ordering::SeqCst);
        }
    }
}

/// A slot for a new connection from `peer`, or `None` (logged) when the table is full of
/// connections that made progress lately.
fn admit(shared: &Shared, stream: &TcpStream, peer: SocketAddr) -> Option<(u64, Arc<Progress>)> {
    let clone = stream.try_clone().ok()?;
    match shared.slots.admit(clone, peer) {
        Admission::Admitted(id, progress) => Some((id, progress)),
        Admission::Evicted {
            id,
            progress,
            victim,
            why,
        } => {
            shared.evicted_log.log(format_args!(
                "connection limit {} reached: {victim} ({why}) closed to serve {peer}",
                shared.config.max_connections,
            ));
            Some((id, progress))
        }
        Admission::Full => {
            shared.refused_log.log(format_args!(
                "{peer}: connection limit {} reached (every connection made a request within {} s or connected within {} ms): connection closed",
                shared.config.max_connections,
                EVICT_QUIET.as_secs(),
                FIRST_REQUEST_GRACE.as_millis()
            ));
            None
        }
        Admission::PeerFull(held) => {
            shared.refused_log.log(format_args!(
                "{peer}: its address already holds {held} of the {} connections (a quarter per remote address): connection closed",
                shared.config.max_connections,
            ));
            None
        }
    }
}

/// Who a connection serves.
struct Conn {
    peer: SocketAddr,
    /// The peer's IP is routed (or every client is): frames need no routed source NetId.
    ip_routed: bool,
    progress: Arc<Progress>,
}

/// The writing half of a connection, shared by the request loop and the notifier: a queue
/// bounded in bytes, drained by the connection's writer thread. Nothing that answers a
/// request or samples a notification ever waits for the client to read.
struct Outbox {
    state: Mutex<OutboxState>,
    ready: Condvar,
    limit_bytes: usize,
}

#[derive(Default)]
struct OutboxState {
    frames: VecDeque<Vec<u8>>,
    /// Bytes in `frames`.
    bytes: usize,
    /// Why the connection must end, once it must.
    closed: Option<Closed>,
}

/// Why a connection's sending side gave up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Closed {
    /// The request loop ended; the writer finishes what is queued.
    Done,
    /// More than the queue's limit waited: the client does not read.
    Overflow,
    /// A write failed or timed out.
    WriteFailed,
}

type Writer = Arc<Outbox>;

impl Outbox {
    fn new(limit_bytes: usize) -> Self {
        Outbox {
            state: Mutex::new(OutboxState::default()),
            ready: Condvar::new(),
            limit_bytes,
        }
    }

    fn closed(&self) -> Option<Closed> {
        lock(&self.state).closed
    }

    fn close(&self, why: Closed) {
        lock(&self.state).closed.get_or_insert(why);
        self.ready.notify_all();
    }

    /// Drain the queue into `stream` until the connection ends.
    fn write_loop(&self, mut stream: TcpStream) {
        loop {
            let frame = {
                let mut st = lock(&self.state);
                loop {
                    if st.closed.is_some_and(|c| c != Closed::Done) {
                        return;
                    }
                    if let Some(f) = st.frames.pop_front() {
                        st.bytes -= f.len();
                        break f;
                    }
                    if st.closed.is_some() {
                        return;
                    }
                    st = self.ready.wait(st).unwrap_or_else(|p| p.into_inner());
                }
            };
            if stream.write_all(&frame).is_err() {
                self.close(Closed::WriteFailed);
                let _ = stream.shutdown(Shutdown::Both);
                return;
            }
        }
    }
}

/// Queue one frame for the client; an error when the connection is over (the queue
/// overflowed now or earlier, or a write failed).
fn send(writer: &Writer, bytes: &[u8]) -> io::Result<()> {
    let mut st = lock(&writer.state);
    if let Some(c) = st.closed {
        return Err(closed_error(c, writer.limit_bytes));
    }
    if st.bytes + bytes.len() > writer.limit_bytes {
        st.closed = Some(Closed::Overflow);
        writer.ready.notify_all();
        return Err(closed_error(Closed::Overflow, writer.limit_bytes));
    }
    st.bytes += bytes.len();
    st.frames.push_back(bytes.to_vec());
    writer.ready.notify_all();
    Ok(())
}

fn closed_error(c: Closed, limit: usize) -> io::Error {
    io::Error::other(match c {
        Closed::Overflow => format!(
            "more than {limit} bytes of responses and notifications unread: the client does not read; connection dropped"
        ),
        Closed::WriteFailed => format!(
            "a write took over {} s or failed (the client does not read?): connection dropped",
            WRITE_TIMEOUT.as_secs()
        ),
        Closed::Done => "connection closed".to_string(),
    })
}

/// One notification handle.
struct Notification {
    /// Where samples go (the requester) and where they come from (the device it addressed).
    client: AmsAddr,
    device: AmsAddr,
    req: NotificationRequest,
    cycle: Duration,
    on_change: bool,
    next_due: Instant,
    last: Option<Vec<u8>>,
    /// False until the AddDeviceNotification response is written: no sample goes out before
    /// the client knows the handle.
    armed: bool,
    /// Evaluated in the cycle (`machine::watch`) rather than polled by the notifier thread.
    watch: Option<Arc<CycleWatch>>,
}

/// The server's half of a notification evaluated in the cycle: the flag that ends it and
/// when its first sample may go out.
struct CycleWatch {
    alive: Arc<AtomicBool>,
    /// Set once the AddDeviceNotification response is queued ([`arm_notifications`]).
    first_sample_at: Mutex<Option<Instant>>,
}

impl Drop for Notification {
    /// A handle removed from its connection's table (deleted, port closed, connection
    /// ended) ends its watch: the next tick drops it.
    fn drop(&mut self) {
        if let Some(w) = &self.watch {
            w.alive.store(false, Ordering::Relaxed);
        }
    }
}

/// Per-connection notification table, polled by the notifier thread.
struct Notifications {
    table: Mutex<HashMap<u32, Notification>>,
    next_handle: AtomicU32,
    closed: AtomicBool,
    notifier: Mutex<Option<JoinHandle<()>>>,
}

/// Why a connection ended with a log line.
#[derive(Debug, thiserror::Error)]
enum ConnError {
    #[error("{0}: connection closed")]
    Frame(#[from] frame::FrameError),
    #[error("{0}")]
    Io(#[from] io::Error),
    #[error("{0}: connection closed")]
    Idle(String),
    /// The reader has ended and every frame it read is answered.
    #[error("connection closed")]
    Ended,
}

fn serve_connection(stream: TcpStream, conn: &Conn, shared: &Arc<Shared>) -> Result<(), ConnError> {
    stream.set_nodelay(true)?;
    stream.set_write_timeout(Some(WRITE_TIMEOUT))?;
    // Poll often enough to notice an idle timeout or an overflowed send queue.
    let poll = shared
        .config
        .idle_timeout
        .clamp(Duration::from_millis(50), Duration::from_millis(500));
    stream.set_read_timeout(Some(poll))?;
    let writer: Writer = Arc::new(Outbox::new(shared.config.max_send_queue_bytes));
    let write_half = stream.try_clone()?;
    let write_thread = {
        let w = Arc::clone(&writer);
        std::thread::Builder::new()
            .name("ads-write".into())
            .spawn(move || w.write_loop(write_half))?
    };
    let notifs = Arc::new(Notifications {
        table: Mutex::new(HashMap::new()),
        next_handle: AtomicU32::new(1),
        closed: AtomicBool::new(false),
        notifier: Mutex::new(None),
    });
    let result = request_loop(stream.try_clone()?, conn, shared, &writer, &notifs);
    notifs.closed.store(true, Ordering::SeqCst);
    let notifier = lock(&notifs.notifier).take();
    if let Some(h) = notifier {
        let _ = h.join();
    }
    let ended: Vec<Notification> = lock(&notifs.table).drain().map(|(_, n)| n).collect();
    shared.release(&ended);
    writer.close(Closed::Done);
    let _ = write_thread.join();
    let _ = stream.shutdown(Shutdown::Both);
    result
}

/// Frames read from one connection and not yet answered, each stamped with the instant the
/// read that completed it returned, and the socket's read side, which whoever holds it reads.
/// The answering thread reads the socket itself whenever it has nothing to answer, so a
/// client that waits for each answer costs no hand-over between threads. A helper thread
/// takes the reading over only while one answer has taken longer than [`HELP_AFTER`] (a
/// runtime call waiting on a stalled tick): requests pipelined behind it are read and stamped
/// then, so each one's reply deadline counts from its own arrival (at most [`HELP_AFTER`]
/// late), not from the answer to the one before it (a client with 50 requests in flight
/// through a runtime stall hears "busy" for each within `reply_timeout` of sending it).
/// Bounded in bytes like the [`Outbox`]: past the limit the helper stops reading and TCP
/// holds the client back.
struct Inbox {
    state: Mutex<InboxState>,
    ready: Condvar,
    read: Mutex<ReadSide>,
    limit_bytes: usize,
}

/// How long an answer may take before the helper thread reads the requests behind it.
const HELP_AFTER: Duration = Duration::from_millis(5);

#[derive(Default)]
struct InboxState {
    frames: VecDeque<(Instant, Frame, usize)>,
    /// Bytes of the frames in `frames`.
    bytes: usize,
    /// When the answering thread took the frame it is answering; `None` while it waits for
    /// one or reads.
    serving_since: Option<Instant>,
    /// The helper holds (or is about to take) the read side.
    helper_reading: bool,
    /// The helper waits without a deadline (nothing was being answered): the answering
    /// thread wakes it when it takes a frame, so it can time that answer.
    helper_parked: bool,
    /// The reading is done, and why (`Ok` for the client's or the server's clean close);
    /// taken by the answering thread once every frame is answered.
    ended: Option<Result<(), ConnError>>,
    /// No more reads: the reading ended or the answering side is gone.
    closed: bool,
}

/// The socket's read side and what it has read of a frame not yet complete.
struct ReadSide {
    stream: TcpStream,
    buf: Vec<u8>,
    last_frame: Instant,
    read_at: Instant,
}

/// What one connection's reading needs of the rest of the server.
#[derive(Clone, Copy)]
struct ReadCtx<'a> {
    shared: &'a Shared,
    writer: &'a Writer,
    notifs: &'a Notifications,
}

impl Inbox {
    fn new(stream: TcpStream, limit_bytes: usize) -> Self {
        let now = Instant::now();
        Inbox {
            state: Mutex::new(InboxState::default()),
            ready: Condvar::new(),
            read: Mutex::new(ReadSide {
                stream,
                buf: Vec::with_capacity(8192),
                last_frame: now,
                read_at: now,
            }),
            limit_bytes,
        }
    }

    fn state(&self) -> MutexGuard<'_, InboxState> {
        lock(&self.state)
    }

    fn wait<'g>(&self, g: MutexGuard<'g, InboxState>) -> MutexGuard<'g, InboxState> {
        self.ready.wait(g).unwrap_or_else(|p| p.into_inner())
    }

    /// The next frame and its arrival, read by this (the answering) thread when none is
    /// waiting and the helper is not reading; or why the reading ended once every frame is
    /// answered.
    fn next(&self, ctx: ReadCtx<'_>) -> Result<(Instant, Frame), ConnError> {
        loop {
            {
                let mut st = self.state();
                st.serving_since = None;
                loop {
                    if let Some((arrived, frame, len)) = st.frames.pop_front() {
                        st.bytes -= len;
                        st.serving_since = Some(Instant::now());
                        if st.helper_reading || st.helper_parked {
                            // It may wait for room, or time this answer.
                            st.helper_parked = false;
                            self.ready.notify_all();
                        }
                        return Ok((arrived, frame));
                    }
                    if let Some(end) = st.ended.take() {
                        // Ended for good: the next call says so again.
                        st.ended = Some(Ok(()));
                        return end.and(Err(ConnError::Ended));
                    }
                    if !st.helper_reading {
                        break;
                    }
                    st = self.wait(st);
                }
            }
            // The helper never holds the read side without `helper_reading`, so it is free.
            let mut rs = lock(&self.read);
            self.read_once(&mut rs, ctx, false);
        }
    }

    /// The helper thread: read while an answer has taken longer than [`HELP_AFTER`], until
    /// the reading ends.
    fn help(&self, ctx: ReadCtx<'_>) {
        loop {
            {
                let mut st = self.state();
                loop {
                    if st.closed {
                        return;
                    }
                    match st.serving_since.map(|t| t.elapsed()) {
                        Some(d) if d >= HELP_AFTER => break,
                        Some(d) => {
                            st = self
                                .ready
                                .wait_timeout(st, HELP_AFTER - d)
                                .unwrap_or_else(|p| p.into_inner())
                                .0
                        }
                        None => {
                            st.helper_parked = true;
                            st = self.wait(st);
                        }
                    }
                }
                st.helper_reading = true;
            }
            {
                let mut rs = lock(&self.read);
                self.read_once(&mut rs, ctx, true);
            }
            self.state().helper_reading = false;
            self.ready.notify_all();
        }
    }

    /// Read once (at most the socket's read timeout) and queue every frame completed; on
    /// the end of the reading, record why. `helper`: frames are queued for the answering
    /// thread (woken, and waited for while the inbox is full); else the caller is it.
    fn read_once(&self, rs: &mut ReadSide, ctx: ReadCtx<'_>, helper: bool) {
        if self.state().closed {
            return;
        }
        if let Err(why) = self.read_frames(rs, ctx, helper) {
            let mut st = self.state();
            st.closed = true;
            st.ended.get_or_insert(Err(why));
            drop(st);
            self.ready.notify_all();
        }
    }

    /// Cut every complete frame out of the buffer (rule 1) into the queue, then read one
    /// chunk; `Err` when the client closes, sends a malformed frame, stays idle, or the
    /// answering side is gone (`Ok` end). The decoder rejects a hostile length before we
    /// would ever wait for its bytes, so `buf` stays below max_frame_bytes + 6 + one chunk.
    fn read_frames(
        &self,
        rs: &mut ReadSide,
        ctx: ReadCtx<'_>,
        helper: bool,
    ) -> Result<(), ConnError> {
        let (shared, writer) = (ctx.shared, ctx.writer);
        let max = shared.config.max_frame_bytes;
        let used = self.push_frames(rs, max, helper)?;
        if used > 0 && !helper {
            // Frames to answer first: read more once they are answered.
            return Ok(());
        }
        if let Some(c) = writer.closed() {
            return Err(closed_error(c, writer.limit_bytes).into());
        }
        let mut chunk = [0u8; 8192];
        let n = match rs.stream.read(&mut chunk) {
            // The writer shut the socket (write stall): say why, not just "closed".
            Ok(0) => {
                return match writer.closed() {
                    Some(c) if c != Closed::Done => Err(closed_error(c, writer.limit_bytes).into()),
                    _ => Err(ConnError::Ended),
                }
            }
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => return Ok(()),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) =>
            {
                if !self.busy() {
                    check_idle(rs.last_frame, &rs.buf, shared, ctx.notifs)?;
                }
                return Ok(());
            }
            Err(_) if shared.stopping.load(Ordering::SeqCst) => return Err(ConnError::Ended),
            Err(e) => {
                return Err(match writer.closed() {
                    Some(c) if c != Closed::Done => closed_error(c, writer.limit_bytes),
                    _ => e,
                }
                .into())
            }
        };
        rs.read_at = Instant::now();
        rs.buf.extend_from_slice(&chunk[..n]);
        self.push_frames(rs, max, helper)?;
        Ok(())
    }

    /// Pushes every whole frame at the front of `rs.buf` and removes their bytes; the number
    /// of bytes they took. A malformed frame is the decoder's error, a refused push `Ended`.
    fn push_frames(&self, rs: &mut ReadSide, max: usize, helper: bool) -> Result<usize, ConnError> {
        let mut used = 0;
        while let Some((frame, n)) = frame::decode(&rs.buf[used..], max)? {
            used += n;
            rs.last_frame = Instant::now();
            if !self.push(rs.read_at, frame, n, helper) {
                return Err(ConnError::Ended);
            }
        }
        rs.buf.drain(..used);
        Ok(used)
    }

    /// Queue a frame of `len` bytes; the helper waits while the inbox is full (the answering
    /// thread only reads when it is empty). `false` once the answering side is gone.
    fn push(&self, arrived: Instant, frame: Frame, len: usize, helper: bool) -> bool {
        let mut st = self.state();
        while helper && !st.closed && !st.frames.is_empty() && st.bytes + len > self.limit_bytes {
            st = self.wait(st);
        }
        if st.closed {
            return false;
        }
        st.bytes += len;
        st.frames.push_back((arrived, frame, len));
        drop(st);
        if helper {
            self.ready.notify_all();
        }
        true
    }

    /// Frames wait or one is being answered: the client is not idle.
    fn busy(&self) -> bool {
        let st = self.state();
        st.serving_since.is_some() || !st.frames.is_empty()
    }

    /// The answering side is gone: the helper stops.
    fn close(&self) {
        self.state().closed = true;
        self.ready.notify_all();
    }
}

/// Bytes of frames one connection may have read ahead of its answers ([`Inbox`]).
const MAX_INBOX_BYTES: usize = 256 * 1024;

/// Answer the frames of the connection in order until it ends; a helper thread reads the
/// requests behind an answer that takes long ([`Inbox`]).
fn request_loop(
    stream: TcpStream,
    conn: &Conn,
    shared: &Arc<Shared>,
    writer: &Writer,
    notifs: &Arc<Notifications>,
) -> Result<(), ConnError> {
    let inbox = Arc::new(Inbox::new(
        stream.try_clone()?,
        MAX_INBOX_BYTES.max(shared.config.max_frame_bytes),
    ));
    let helper = {
        let (s, w, n, i) = (
            Arc::clone(shared),
            Arc::clone(writer),
            Arc::clone(notifs),
            Arc::clone(&inbox),
        );
        std::thread::Builder::new()
            .name("ads-read".into())
            .spawn(move || {
                i.help(ReadCtx {
                    shared: &s,
                    writer: &w,
                    notifs: &n,
                })
            })?
    };
    let ctx = ReadCtx {
        shared,
        writer,
        notifs,
    };
    let result = answer_loop(conn, shared, writer, notifs, &inbox, ctx);
    inbox.close();
    let _ = stream.shutdown(Shutdown::Read);
    let _ = helper.join();
    match result {
        Err(ConnError::Ended) => Ok(()),
        r => r,
    }
}

fn answer_loop(
    conn: &Conn,
    shared: &Arc<Shared>,
    writer: &Writer,
    notifs: &Arc<Notifications>,
    inbox: &Inbox,
    ctx: ReadCtx<'_>,
) -> Result<(), ConnError> {
    let (peer, ip_routed) = (conn.peer, conn.ip_routed);
    let mut logged_unrouted = LoggedNetIds::default();
    let mut logged_foreign = LoggedNetIds::default();
    loop {
        let (arrived, frame) = inbox.next(ctx)?;
        match frame {
            Frame::Ams { header, data } => {
                let routed = ip_routed || shared.routes.routes_net_id(header.source.net_id);
                if !routed {
                    note_unrouted(peer, &mut logged_unrouted, header.source.net_id);
                    continue;
                }
                if !serves_target(shared.config.net_id, header.target.net_id) {
                    note_foreign_target(shared, peer, &mut logged_foreign, &header);
                    let refusal = header.response(AMS_ERR_MACHINE_NOT_FOUND);
                    send(writer, &frame::encode(&refusal, &[]))?;
                    continue;
                }
                let late = shared.devices.overdue(arrived);
                if let Some(reply) = handle_request(&header, &data, late, shared, writer, notifs) {
                    send(writer, &reply)?;
                    conn.progress.mark();
                    if adds_notifications(&header, &data) {
                        arm_notifications(notifs);
                    }
                }
            }
            Frame::Router {
                command: PORT_CLOSE,
                body,
            } => {
                // The client's port is gone: its notifications end, and the connection
                // is closed, as the TwinCAT router does, so the client's disconnect()
                // (which waits for the close) returns at once.
                close_port(shared, notifs, &body);
                return Ok(());
            }
            Frame::Router { command, body } => {
                if let Some(reply) = handle_router(command, &body, peer, shared) {
                    send(writer, &reply)?;
                    conn.progress.mark();
                }
            }
        }
        if let Some(c) = writer.closed() {
            return Err(closed_error(c, writer.limit_bytes).into());
        }
    }
}

/// The source NetIds one connection has logged a line about, for one kind of refused frame:
/// at most [`MAX_LOGGED_UNROUTED`], so a client cycling through NetIds cannot fill the log.
#[derive(Default)]
struct LoggedNetIds(Vec<AmsNetId>);

/// What [`LoggedNetIds::note`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FirstSeen {
    /// Not logged before: log it.
    New,
    /// The first NetId past the bound: say that no more are logged.
    PastBound,
    /// Logged before, or past the bound already: nothing to log.
    Known,
}

impl LoggedNetIds {
    fn note(&mut self, id: AmsNetId) -> FirstSeen {
        if self.0.len() > MAX_LOGGED_UNROUTED || self.0.contains(&id) {
            return FirstSeen::Known;
        }
        let past = self.0.len() == MAX_LOGGED_UNROUTED;
        self.0.push(id);
        if past {
            FirstSeen::PastBound
        } else {
            FirstSeen::New
        }
    }
}

/// Log a frame dropped for want of a route, once per source NetId; past
/// `MAX_LOGGED_UNROUTED` NetIds say so once and log no more (a flood cannot fill the log).
fn note_unrouted(peer: SocketAddr, logged: &mut LoggedNetIds, id: AmsNetId) {
    match logged.note(id) {
        FirstSeen::New => log(format_args!(
            "{peer}: no route for source NetId {id}: frames dropped"
        )),
        FirstSeen::PastBound => log(format_args!(
            "{peer}: more than {MAX_LOGGED_UNROUTED} unrouted source NetIds: no more are logged"
        )),
        FirstSeen::Known => {}
    }
}

/// Whether a frame for `target` is this device's: its NetId or the loopback alias
/// 127.0.0.1.1.1, which a TwinCAT router serves as its own (`None`: every NetId is).
fn serves_target(device: Option<AmsNetId>, target: AmsNetId) -> bool {
    device.is_none_or(|id| target == id || target == AmsNetId::LOCAL)
}

/// Log a frame answered AMS error 7 for its target NetId, once per source NetId and
/// connection (bounded as the unrouted ones), through the server's rate-limited line.
fn note_foreign_target(
    shared: &Shared,
    peer: SocketAddr,
    logged: &mut LoggedNetIds,
    header: &AmsHeader,
) {
    let source = header.source.net_id;
    if logged.note(source) == FirstSeen::New {
        let own = shared.config.net_id.unwrap_or(DEFAULT_NET_ID);
        shared.target_log.log(format_args!(
            "{peer}: frames from {source} for AMS NetId {} answered AMS error 7: this device is {own} (or {})",
            header.target.net_id,
            AmsNetId::LOCAL
        ));
    }
}

/// After a read timed out: end the connection when no frame came for the idle timeout and
/// it is waiting on the client (a frame half sent, or no notifications to keep it alive).
fn check_idle(
    last_frame: Instant,
    buf: &[u8],
    shared: &Shared,
    notifs: &Notifications,
) -> Result<(), ConnError> {
    let idle = last_frame.elapsed();
    let waiting = !buf.is_empty() || lock(&notifs.table).is_empty();
    if idle >= shared.config.idle_timeout && waiting {
        let what = if buf.is_empty() {
            "idle"
        } else {
            "frame incomplete"
        };
        return Err(ConnError::Idle(format!(
            "{what} for {} s (idle timeout {} s)",
            idle.as_secs(),
            shared.config.idle_timeout.as_secs_f64()
        )));
    }
    Ok(())
}

/// AMS/TCP command 0x0001: a client closes its AMS port (body: the port, u16 LE).
const PORT_CLOSE: u16 = 0x0001;

/// Drop the notifications of the port a 0x0001 frame closes (all of them when the body does
/// not name a port).
fn close_port(shared: &Shared, notifs: &Notifications, body: &[u8]) {
    let port = match body {
        [a, b, ..] => Some(u16::from_le_bytes([*a, *b])),
        _ => None,
    };
    let removed: Vec<Notification> = lock(&notifs.table)
        .extract_if(|_, n| port.is_none_or(|p| n.client.port == p))
        .map(|(_, n)| n)
        .collect();
    shared.release(&removed);
}

/// How long after its AddDeviceNotification response a handle's first sample goes out.
/// Beckhoff's AdsLib (inside pyads) creates the handle's dispatcher in the calling thread only
/// once that thread has woken up with the response; a sample its receive thread meets before
/// then is dropped ("No dispatcher found for notification", `AmsConnection::ReceiveNotification`
/// in Beckhoff/ADS). Right behind the response, pyads lost its first sample about once in a
/// hundred on a busy machine. TwinCAT sends the first sample at the notification's next cycle,
/// not within microseconds either.
pub const FIRST_SAMPLE_DELAY: Duration = Duration::from_millis(20);

/// Let the notifications just added send their first sample [`FIRST_SAMPLE_DELAY`] from now.
/// Their response is already in the connection's send queue, so the sample also never
/// overtakes it on the wire.
fn arm_notifications(notifs: &Notifications) {
    let due = Instant::now() + FIRST_SAMPLE_DELAY;
    for n in lock(&notifs.table).values_mut().filter(|n| !n.armed) {
        n.armed = true;
        n.next_due = due;
        if let Some(w) = &n.watch {
            *lock(&w.first_sample_at) = Some(due);
        }
    }
    if let Some(h) = lock(&notifs.notifier).as_ref() {
        h.thread().unpark();
    }
}

/// AMS router commands. 0x1000 "port connect" (sent by clients that expect a local router:
/// ads-client's `connect()`, the `ads` crate's `Source::Request`) gets the router's loopback
/// NetId 127.0.0.1.1.1 and a fresh port: a NetId on the router, served as the device's own
/// (docs/design-choices.md says why not the device's configured NetId); everything else is
/// ignored.
fn handle_router(command: u16, _body: &[u8], peer: SocketAddr, shared: &Shared) -> Option<Vec<u8>> {
    if command != 0x1000 {
        shared.router_log.log(format_args!(
            "{peer}: AMS router command 0x{command:04X} ignored"
        ));
        return None;
    }
    let port = shared.next_router_port.fetch_add(1, Ordering::SeqCst);
    let mut out = vec![0x00, 0x10, 8, 0, 0, 0];
    out.extend_from_slice(&AmsNetId::LOCAL.0);
    out.extend_from_slice(&port.to_le_bytes());
    Some(out)
}

fn device_name() -> String {
    format!("ncchannel {}", env!("CARGO_PKG_VERSION"))
}

fn version_numbers() -> (u8, u8, u16) {
    let mut parts = env!("CARGO_PKG_VERSION")
        .split(['.', '-'])
        .map(|p| p.parse::<u16>().unwrap_or(0));
    let major = parts.next().unwrap_or(0).min(255) as u8;
    let minor = parts.next().unwrap_or(0).min(255) as u8;
    let build = parts.next().unwrap_or(0);
    (major, minor, build)
}

/// Answer one request frame; `None` when no answer is due (responses from the client, or
/// DeviceNotification frames sent to us).
fn handle_request(
    header: &AmsHeader,
    data: &[u8],
    late: bool,
    shared: &Arc<Shared>,
    writer: &Writer,
    notifs: &Arc<Notifications>,
) -> Option<Vec<u8>> {
    if header.state_flags & 0x0001 != 0 {
        return None; // a response; we never asked anything
    }
    if !shared.devices.serves_now(header.target.port) {
        // rule 5: router-level error in the header, empty payload.
        return Some(frame::encode(&header.response(AMS_ERR_PORT_NOT_FOUND), &[]));
    }
    let (devices, port) = (&shared.devices, header.target.port);
    let command = header.command.to_u16();
    let payload = match payload::decode_request(command, data) {
        None => {
            if header.command == CommandId::DeviceNotification {
                return None;
            }
            response::result_only(AdsResult::SERVICE_NOT_SUPPORTED)
        }
        Some(Err(e)) => error_payload(header.command, e.result()),
        // The runtime is stalled and this request's reply timeout, counted from its arrival,
        // has passed: "busy, not applied" now, without asking the runtime.
        Some(Ok(
            Request::Read { .. }
            | Request::Write { .. }
            | Request::ReadWrite { .. }
            | Request::AddNotification(_),
        )) if late => error_payload(header.command, AdsResult::BUSY),
        Some(Ok(req)) => match req {
            Request::ReadDeviceInfo => match Devices::device_info(port) {
                Some((major, minor, build, name)) => {
                    response::device_info(major, minor, build, name)
                }
                None => {
                    let (major, minor, build) = version_numbers();
                    response::device_info(major, minor, build, &device_name())
                }
            },
            Request::ReadState => {
                let (ads_state, device_state) = devices.read_state(port);
                response::state(ads_state, device_state)
            }
            Request::WriteControl { ads_state, .. } => {
                response::result_only(match devices.write_control(port, ads_state) {
                    Ok(()) => AdsResult::OK,
                    Err(r) => r,
                })
            }
            Request::Read {
                group,
                offset,
                length,
            } => match devices.read(port, group, offset, length) {
                Ok(bytes) => response::with_data(AdsResult::OK, &bytes),
                Err(r) => response::with_data(r, &[]),
            },
            Request::Write {
                group,
                offset,
                data,
            } => response::result_only(match devices.write(port, group, offset, &data) {
                Ok(()) => AdsResult::OK,
                Err(r) => r,
            }),
            Request::ReadWrite {
                group: group @ (sum::ADD_NOTIFICATIONS | sum::DELETE_NOTIFICATIONS),
                offset: count,
                read_length,
                data,
            } => {
                let sums = SumNotifications {
                    header,
                    shared,
                    writer,
                    notifs,
                };
                match sums.serve(group, count, read_length, &data) {
                    Ok(bytes) => response::with_data(AdsResult::OK, &bytes),
                    Err(r) => response::with_data(r, &[]),
                }
            }
            Request::ReadWrite {
                group,
                offset,
                read_length,
                data,
            } => match devices.read_write(port, group, offset, read_length, &data) {
                Ok(bytes) => response::with_data(AdsResult::OK, &bytes),
                Err(r) => response::with_data(r, &[]),
            },
            Request::AddNotification(req) => {
                let (result, handle) = add_notification(header, req, shared, writer, notifs);
                response::handle(result, handle)
            }
            Request::DelNotification { handle } => {
                response::result_only(delete_notification(shared, notifs, handle))
            }
        },
    };
    Some(frame::encode(&header.response(0), &payload))
}

/// A sum add/delete notification request and the connection whose table it changes.
struct SumNotifications<'a> {
    header: &'a AmsHeader,
    shared: &'a Arc<Shared>,
    writer: &'a Writer,
    notifs: &'a Arc<Notifications>,
}

impl SumNotifications<'_> {
    /// Serve sum `group` (0xF085 or 0xF086) with `count` entries in `data`.
    fn serve(
        &self,
        group: u32,
        count: u32,
        read_length: u32,
        data: &[u8],
    ) -> Result<Vec<u8>, AdsResult> {
        let (header, shared, writer, notifs) = (self.header, self.shared, self.writer, self.notifs);
        if group == sum::ADD_NOTIFICATIONS {
            let mut add = |req| add_notification(header, req, shared, writer, notifs);
            sum::add_notifications(count, read_length, data, &mut add)
        } else {
            let mut delete = |handle| delete_notification(shared, notifs, handle);
            sum::delete_notifications(count, read_length, data, &mut delete)
        }
    }
}

/// Remove notification `handle` of this connection and give its budget back.
fn delete_notification(shared: &Shared, notifs: &Notifications, handle: u32) -> AdsResult {
    let removed = lock(&notifs.table).remove(&handle);
    shared.release(removed.as_ref());
    if removed.is_some() {
        AdsResult::OK
    } else {
        AdsResult::INVALID_HANDLE
    }
}

/// Whether the request makes notification handles (AddDeviceNotification, or a sum add
/// notification ReadWrite): their first samples are planned once its response is queued.
fn adds_notifications(header: &AmsHeader, data: &[u8]) -> bool {
    header.command == CommandId::AddDeviceNotification
        || (header.command == CommandId::ReadWrite
            && data.get(..4) == Some(&sum::ADD_NOTIFICATIONS.to_le_bytes()[..]))
}

/// The error response shaped as the command's response (result alone, or result + zero).
fn error_payload(command: CommandId, result: AdsResult) -> Vec<u8> {
    match command {
        CommandId::Read | CommandId::ReadWrite => response::with_data(result, &[]),
        CommandId::AddDeviceNotification => response::handle(result, 0),
        _ => response::result_only(result),
    }
}

fn add_notification(
    header: &AmsHeader,
    req: NotificationRequest,
    shared: &Arc<Shared>,
    writer: &Writer,
    notifs: &Arc<Notifications>,
) -> (AdsResult, u32) {
    // The object must be readable with the requested length now.
    let port = header.target.port;
    if let Err(r) = shared.devices.read(port, req.group, req.offset, req.length) {
        return (r, 0);
    }
    let on_change = match req.mode {
        1 | 3 | 5 => false,
        2 | 4 | 6 => true,
        _ => return (AdsResult::INVALID_DATA, 0),
    };
    let cycle = Duration::from_nanos(u64::from(req.cycle_time_100ns) * 100)
        .clamp(MIN_NOTIFICATION_CYCLE, MAX_NOTIFICATION_CYCLE);
    let table = lock(&notifs.table);
    // 0x716 (no more handles) for the connection's limits (handles, samples a second) and the
    // whole server's budget: the one error a client already handles when a table is full.
    // The connection's rate is summed over its table (at most `max_notifications` handles).
    let conn_rate: u64 = table.values().map(|n| rate_mhz(n.cycle)).sum();
    let conn_limit = shared
        .config
        .notification_samples_per_s_per_connection
        .saturating_mul(1000);
    if table.len() >= shared.config.max_notifications
        || conn_rate.saturating_add(rate_mhz(cycle)) > conn_limit
        || !shared.reserve(cycle)
    {
        return (AdsResult::NO_MORE_HANDLES, 0);
    }
    let handle = notifs.next_handle.fetch_add(1, Ordering::SeqCst);
    // Only this connection's thread adds to its table, so nothing comes between the checks
    // above and the insert below while the watch is registered through the runtime.
    drop(table);
    let watch = watch_in_cycle(header, &req, cycle, on_change, handle, shared, writer);
    let in_cycle = watch.is_some();
    lock(&notifs.table).insert(
        handle,
        Notification {
            client: header.source,
            device: header.target,
            req,
            cycle,
            on_change,
            // Armed once the response is written (arm_notifications).
            next_due: Instant::now() + MAX_NOTIFICATION_CYCLE,
            last: None,
            armed: false,
            watch,
        },
    );
    let mut notifier = lock(&notifs.notifier);
    if notifier.is_none() && !in_cycle {
        let (s, w, n) = (Arc::clone(shared), Arc::clone(writer), Arc::clone(notifs));
        *notifier = std::thread::Builder::new()
            .name("ads-notify".into())
            .spawn(move || notify_loop(&s, &w, &n))
            .ok();
    }
    (AdsResult::OK, handle)
}

/// Register the notification `handle` to be evaluated in the cycle when its object allows
/// (`objects::Devices::watch`); `None` when it is sampled by the notifier thread instead.
fn watch_in_cycle(
    header: &AmsHeader,
    req: &NotificationRequest,
    cycle: Duration,
    on_change: bool,
    handle: u32,
    shared: &Shared,
    writer: &Writer,
) -> Option<Arc<CycleWatch>> {
    let state = Arc::new(CycleWatch {
        alive: Arc::new(AtomicBool::new(true)),
        first_sample_at: Mutex::new(None),
    });
    let (client, device) = (header.source, header.target);
    let (w, st) = (Arc::clone(writer), Arc::clone(&state));
    let deliver = move |bytes: &[u8]| {
        if !st.alive.load(Ordering::Relaxed) {
            return Delivery::Gone;
        }
        match *lock(&st.first_sample_at) {
            Some(t) if Instant::now() >= t => {}
            _ => return Delivery::NotYet,
        }
        match send(&w, &notification_frame(client, device, handle, bytes)) {
            Ok(()) => Delivery::Sent,
            Err(_) => Delivery::Gone,
        }
    };
    let alive = Arc::clone(&state.alive);
    let taken = shared
        .devices
        .watch(device.port, req.group, req.offset, req.length, |encode| {
            Watch {
                cycle,
                on_change,
                encode,
                deliver: Box::new(deliver),
                alive,
            }
        });
    if !taken {
        state.alive.store(false, Ordering::Relaxed);
        return None;
    }
    Some(state)
}

/// One DeviceNotification frame of one sample. Flags 0x0004: a notification is a request
/// the client does not answer.
fn notification_frame(client: AmsAddr, device: AmsAddr, handle: u32, bytes: &[u8]) -> Vec<u8> {
    let header = AmsHeader {
        target: client,
        source: device,
        command: CommandId::DeviceNotification,
        state_flags: FLAGS_REQUEST,
        error: 0,
        invoke_id: 0,
    };
    let payload = response::notification(filetime_now(), &[(handle, bytes)]);
    frame::encode(&header, &payload)
}

fn filetime_now() -> u64 {
    const UNIX_TO_1601_100NS: u64 = 116_444_736_000_000_000;
    let since = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default();
    UNIX_TO_1601_100NS + (since.as_nanos() / 100) as u64
}

/// Poll due handles and send a DeviceNotification for each sample that is due (cyclic) or
/// changed (on change). Flags 0x0004: a notification is a request the client does not answer.
fn notify_loop(shared: &Shared, writer: &Writer, notifs: &Notifications) {
    while !notifs.closed.load(Ordering::SeqCst) && !shared.stopping.load(Ordering::SeqCst) {
        let now = Instant::now();
        let mut frames = Vec::new();
        let mut next = now + Duration::from_millis(20);
        {
            let mut table = lock(&notifs.table);
            for (&handle, n) in table.iter_mut().filter(|(_, n)| n.watch.is_none()) {
                if n.armed && n.next_due <= now {
                    n.next_due = now + n.cycle;
                    let read =
                        shared
                            .devices
                            .read(n.device.port, n.req.group, n.req.offset, n.req.length);
                    if let Ok(bytes) = read {
                        if !n.on_change || n.last.as_deref() != Some(bytes.as_slice()) {
                            frames.push(notification_frame(n.client, n.device, handle, &bytes));
                            n.last = Some(bytes);
                        }
                    }
                }
                next = next.min(n.next_due);
            }
        }
        for f in frames {
            if send(writer, &f).is_err() {
                return;
            }
        }
        // Parked, not asleep: arm_notifications wakes it to plan a new handle's first sample.
        let wait = next.saturating_duration_since(Instant::now());
        std::thread::park_timeout(wait.max(Duration::from_micros(500)));
    }
}
