//! The web view's HTTP/1.1 server: accepts connections (at most [`MAX_CONNECTIONS`], one
//! thread each, as the ADS server does), reads one request head with `httparse`, and answers
//! it: the embedded page, the event stream (at most [`MAX_PAGE_CONNECTIONS`] at once) or a
//! control request. Every response closes its connection; there is no keep-alive to bound.

use std::io::{self, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use super::controls::{self, CONTROL_HEADER};
use super::feed::{Feed, Pages};
use super::{
    page, sse, Backend, ControlAccess, HttpConfig, MAX_CONNECTIONS, MAX_PAGE_CONNECTIONS,
    MAX_REQUEST_BYTES, READ_TIMEOUT, WRITE_TIMEOUT,
};
use crate::vocab::stats::LiveCycleStats;

/// Why a request could not be read.
#[derive(Debug, thiserror::Error)]
pub enum RequestError {
    #[error("request larger than {MAX_REQUEST_BYTES} bytes")]
    TooLarge,
    #[error("malformed request: {0}")]
    Malformed(#[from] httparse::Error),
    #[error("connection closed before the request was complete")]
    Incomplete,
    #[error("request not complete within the request deadline")]
    TimedOut,
    #[error("more than one Content-Length header")]
    DuplicateLength,
    #[error(transparent)]
    Io(#[from] io::Error),
}

/// One request as the routes need it.
struct Request {
    method: String,
    path: String,
    has_control_header: bool,
    /// The `Host` header's value, if any.
    host: Option<String>,
    /// The `Origin` header's value, if any.
    origin: Option<String>,
    body: String,
}

struct Shared {
    backend: Backend,
    controls: ControlAccess,
    /// Every `Host` value answered (lower case).
    hosts: Vec<String>,
    /// Sources (peer IP and kind of refusal) already logged, so each is logged once.
    refused_logged: std::sync::Mutex<Vec<(std::net::IpAddr, u16)>>,
    pages: Arc<Pages>,
    stopping: AtomicBool,
    connections: AtomicUsize,
    streams: AtomicUsize,
    /// Connections still reading their request head, oldest first, with their number: when
    /// every connection slot is taken, the oldest of these is closed for the newcomer, so
    /// clients trickling heads cannot lock pages out (slowloris).
    heads: std::sync::Mutex<std::collections::VecDeque<(u64, TcpStream)>>,
    next_id: std::sync::atomic::AtomicU64,
    /// Computes whole-program previews (`GET /preview/<channel>/<program>`), one at a time.
    previewer: std::sync::Mutex<Option<super::preview::Previewer>>,
    previewing: AtomicBool,
}

/// The running web view.
pub struct HttpHandle {
    local_addr: SocketAddr,
    shared: Arc<Shared>,
    feed: Feed,
    accept: Option<JoinHandle<()>>,
}

impl HttpHandle {
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Answer `GET /preview/<channel>/<program>` with `previewer` (`serve` sets it up from
    /// its lists; without one the preview is 404).
    pub fn set_previewer(&self, previewer: super::preview::Previewer) {
        if let Ok(mut p) = self.shared.previewer.lock() {
            *p = Some(previewer);
        }
    }

    /// Show the soak's counters and invariants on the page from the next update on.
    pub fn publish_soak(&self, soak: serde_json::Value) {
        self.shared.pages.publish_soak(soak);
    }

    /// Pages whose event stream is open now.
    pub fn pages_connected(&self) -> usize {
        self.shared.pages.connected()
    }

    /// Connections open now (pages, streams, requests still being read).
    pub fn connections_open(&self) -> usize {
        self.shared.connections.load(Ordering::SeqCst)
    }

    /// Stop accepting, stop the feed and end every page's stream.
    pub fn shutdown(mut self) {
        self.stop();
    }

    fn stop(&mut self) {
        self.shared.stopping.store(true, Ordering::SeqCst);
        self.feed.stop();
        // Wake the accept loop blocked in accept().
        let _ = TcpStream::connect(self.local_addr);
        if let Some(t) = self.accept.take() {
            let _ = t.join();
        }
    }
}

impl Drop for HttpHandle {
    fn drop(&mut self) {
        self.stop();
    }
}

/// Bind `config.bind` and serve the view of `backend`; `live` adds the runtime's lateness
/// and overruns to the cycle statistics.
pub fn spawn(
    config: &HttpConfig,
    backend: Backend,
    live: Option<Arc<LiveCycleStats>>,
) -> io::Result<HttpHandle> {
    if !config.bind.ip().is_loopback() && !config.allow_non_loopback {
        return Err(io::Error::new(
            io::ErrorKind::PermissionDenied,
            format!(
                "refusing to serve the web view on non-loopback address {} without --allow-non-loopback",
                config.bind
            ),
        ));
    }
    let listener = TcpListener::bind(config.bind)?;
    let local_addr = listener.local_addr()?;
    let feed = Feed::start(Arc::clone(&backend), live)?;
    let shared = Arc::new(Shared {
        backend,
        controls: config.controls,
        hosts: allowed_hosts(local_addr, &config.allow_hosts),
        refused_logged: std::sync::Mutex::new(Vec::new()),
        pages: Arc::clone(&feed.pages),
        stopping: AtomicBool::new(false),
        connections: AtomicUsize::new(0),
        streams: AtomicUsize::new(0),
        heads: std::sync::Mutex::new(std::collections::VecDeque::new()),
        next_id: std::sync::atomic::AtomicU64::new(0),
        previewer: std::sync::Mutex::new(None),
        previewing: AtomicBool::new(false),
    });
    let accept_shared = Arc::clone(&shared);
    let accept = std::thread::Builder::new()
        .name("http-accept".into())
        .spawn(move || accept_loop(&listener, &accept_shared))?;
    Ok(HttpHandle {
        local_addr,
        shared,
        feed,
        accept: Some(accept),
    })
}

/// Decrements a counter when a connection or stream ends, however it ends.
struct Slot<'a>(&'a AtomicUsize);

impl<'a> Slot<'a> {
    /// Take one of `limit` slots, or `None` when all are taken.
    fn take(counter: &'a AtomicUsize, limit: usize) -> Option<Slot<'a>> {
        // `then`, not `then_some`: a Slot built and dropped on refusal would give back a slot never taken.
        reserve(counter, limit).then(|| Slot(counter))
    }
}

/// Count one more of at most `limit`; false when `limit` are counted already.
fn reserve(counter: &AtomicUsize, limit: usize) -> bool {
    counter
        .fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| {
            (n < limit).then_some(n + 1)
        })
        .is_ok()
}

impl Drop for Slot<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::SeqCst);
    }
}

fn accept_loop(listener: &TcpListener, shared: &Arc<Shared>) {
    for stream in listener.incoming() {
        if shared.stopping.load(Ordering::SeqCst) {
            return;
        }
        let Ok(stream) = stream else { continue };
        if !reserve(&shared.connections, MAX_CONNECTIONS) {
            if !evict_oldest_head(shared) {
                let _ = stream.shutdown(Shutdown::Both);
                continue;
            }
            // The evicted connection's thread ends at once and gives its slot back.
            shared.connections.fetch_add(1, Ordering::SeqCst);
        }
        let conn_shared = Arc::clone(shared);
        let spawned = std::thread::Builder::new()
            .name("http-conn".into())
            .spawn(move || {
                // The slot reserved above, released however the connection ends.
                let _slot = Slot(&conn_shared.connections);
                if let Err(e) = serve_connection(stream, &conn_shared) {
                    log::debug!("web view: {e}");
                }
            });
        if spawned.is_err() {
            shared.connections.fetch_sub(1, Ordering::SeqCst);
        }
    }
}

/// Close the connection that has waited longest for its request head; false when none is
/// waiting (every slot serves a page or a request).
fn evict_oldest_head(shared: &Shared) -> bool {
    let Ok(mut heads) = shared.heads.lock() else {
        return false;
    };
    match heads.pop_front() {
        Some((_, s)) => {
            let _ = s.shutdown(Shutdown::Both);
            true
        }
        None => false,
    }
}

fn serve_connection(mut socket: TcpStream, shared: &Shared) -> Result<(), RequestError> {
    socket.set_write_timeout(Some(WRITE_TIMEOUT))?;
    let id = shared.next_id.fetch_add(1, Ordering::SeqCst);
    if let (Ok(clone), Ok(mut heads)) = (socket.try_clone(), shared.heads.lock()) {
        heads.push_back((id, clone));
    }
    let read = read_request(&mut socket);
    if let Ok(mut heads) = shared.heads.lock() {
        heads.retain(|(i, _)| *i != id);
    }
    let req = match read {
        Ok(r) => r,
        Err(
            e @ (RequestError::TooLarge
            | RequestError::Malformed(_)
            | RequestError::DuplicateLength),
        ) => {
            respond(
                &mut socket,
                400,
                "text/plain; charset=utf-8",
                &e.to_string(),
            )?;
            return Err(e);
        }
        Err(e) => return Err(e),
    };
    let text = "text/plain; charset=utf-8";
    let host_ok = req.host.as_deref().is_some_and(|h| answers_host(shared, h));
    if !host_ok {
        refused_once(&socket, shared, 421, req.host.as_deref().unwrap_or(""));
        return Ok(respond(
            &mut socket,
            421,
            text,
            "unknown Host (see --http-allow-host)",
        )?);
    }
    // A state-changing request from a page must come from this view's own origin.
    if req.method != "GET" {
        if let Some(origin) = req.origin.as_deref() {
            let own = ["http://", "https://"].iter().any(|scheme| {
                origin
                    .strip_prefix(scheme)
                    .is_some_and(|h| answers_host(shared, h))
            });
            if !own {
                refused_once(&socket, shared, 403, origin);
                return Ok(respond(&mut socket, 403, text, "foreign Origin")?);
            }
        }
    }
    route(socket, &req, shared)
}

/// Whether `host` (a `Host` header, or an `Origin` without its scheme) names this view.
fn answers_host(shared: &Shared, host: &str) -> bool {
    shared.hosts.iter().any(|a| a.eq_ignore_ascii_case(host))
}

/// Every `Host` value the view answers: the bound address, `localhost`, `127.0.0.1` and
/// `[::1]`, each with the bound port, and `extra` (as given, and with the port when it has none).
fn allowed_hosts(local: SocketAddr, extra: &[String]) -> Vec<String> {
    let port = local.port();
    let mut hosts = vec![
        local.to_string(),
        format!("localhost:{port}"),
        format!("127.0.0.1:{port}"),
        format!("[::1]:{port}"),
    ];
    for h in extra {
        hosts.push(h.to_ascii_lowercase());
        if !h.contains(':') || h.ends_with(']') {
            hosts.push(format!("{}:{port}", h.to_ascii_lowercase()));
        }
    }
    hosts
}

/// Log a refusal (421 wrong Host, 403 wrong Origin) once per peer address and kind; the
/// list is bounded, so a flood of peers cannot grow it.
fn refused_once(socket: &TcpStream, shared: &Shared, status: u16, value: &str) {
    const MAX_LOGGED_SOURCES: usize = 256;
    let Ok(peer) = socket.peer_addr() else { return };
    let Ok(mut seen) = shared.refused_logged.lock() else {
        return;
    };
    if seen.contains(&(peer.ip(), status)) || seen.len() >= MAX_LOGGED_SOURCES {
        return;
    }
    seen.push((peer.ip(), status));
    let what = if status == 421 { "Host" } else { "Origin" };
    let value: String = value.chars().take(80).collect();
    log::warn!(
        "web view: refused {what} {value:?} from {} with {status} (DNS rebinding or a foreign page; logged once per source)",
        peer.ip()
    );
}

fn route(mut socket: TcpStream, req: &Request, shared: &Shared) -> Result<(), RequestError> {
    let text = "text/plain; charset=utf-8";
    match (req.method.as_str(), req.path.as_str()) {
        ("GET", "/events") => {
            let Some(_slot) = Slot::take(&shared.streams, MAX_PAGE_CONNECTIONS) else {
                let msg = format!("{MAX_PAGE_CONNECTIONS} pages are connected already");
                return Ok(respond(&mut socket, 503, text, &msg)?);
            };
            let queue = shared.pages.subscribe();
            Ok(sse::stream(socket, &queue)?)
        }
        ("POST", p) if p.starts_with("/control/") => {
            let rest = &p["/control/".len()..];
            let a = controls::handle(
                &shared.backend,
                shared.controls,
                req.has_control_header,
                rest,
                &req.body,
            );
            Ok(respond(&mut socket, a.status, text, &a.text)?)
        }
        ("GET", "/snapshot.json") => match shared.pages.snapshot() {
            Some(json) => Ok(respond(
                &mut socket,
                200,
                "application/json; charset=utf-8",
                &json,
            )?),
            None => Ok(respond(&mut socket, 503, text, "no update yet")?),
        },
        ("GET", p) if p.starts_with("/preview/") => {
            let (status, body) = preview(shared, &p["/preview/".len()..]);
            let kind = if status == 200 {
                "application/json; charset=utf-8"
            } else {
                text
            };
            Ok(respond(&mut socket, status, kind, &body)?)
        }
        ("GET", "/controls") => {
            let on = shared.controls == ControlAccess::Allowed;
            Ok(respond(
                &mut socket,
                200,
                text,
                if on { "on" } else { "off" },
            )?)
        }
        ("GET", p) => match page::find(p) {
            Some(a) => Ok(respond(&mut socket, 200, a.content_type, a.body)?),
            None => Ok(respond(&mut socket, 404, text, "not found")?),
        },
        _ => Ok(respond(&mut socket, 405, text, "method not allowed")?),
    }
}

/// A whole-program preview: `rest` is `<channel>/<program>`; one at a time (each runs the
/// program on a private copy of the channels), others are answered 503.
fn preview(shared: &Shared, rest: &str) -> (u16, String) {
    let Some((ch, program)) = rest.split_once('/') else {
        return (404, "use /preview/<channel>/<program>".into());
    };
    let Ok(ch) = ch.parse::<u16>() else {
        return (404, format!("no channel '{ch}'"));
    };
    let program = percent_decoded(program);
    let Some(previewer) = shared.previewer.lock().ok().and_then(|p| p.clone()) else {
        return (404, "no previews in this view".into());
    };
    if shared.previewing.swap(true, Ordering::SeqCst) {
        return (503, "a preview is being computed: ask again".into());
    }
    let answer = previewer(ch, &program);
    shared.previewing.store(false, Ordering::SeqCst);
    match answer.map(|p| serde_json::to_string(&p)) {
        Ok(Ok(json)) => (200, json),
        Ok(Err(e)) => (500, e.to_string()),
        Err(reason) => (409, reason),
    }
}

/// `%XX` escapes of a path segment decoded (a program name with a space); invalid ones kept.
fn percent_decoded(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = b
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match (b[i], hex) {
            (b'%', Some(v)) => {
                out.push(v);
                i += 3;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Read one request head and its body (both within [`MAX_REQUEST_BYTES`]).
/// The whole request must arrive within [`READ_TIMEOUT`] of the connection's start: each
/// read waits only for what is left of that one deadline.
fn read_request(socket: &mut TcpStream) -> Result<Request, RequestError> {
    let deadline = Instant::now() + READ_TIMEOUT;
    let mut buf = vec![0u8; MAX_REQUEST_BYTES];
    let mut filled = 0;
    loop {
        let n = read_before(socket, &mut buf[filled..], deadline)?;
        if n == 0 {
            return Err(RequestError::Incomplete);
        }
        filled += n;
        let mut headers = [httparse::EMPTY_HEADER; 32];
        let mut parsed = httparse::Request::new(&mut headers);
        if let httparse::Status::Complete(head) = parsed.parse(&buf[..filled])? {
            let length = content_length(parsed.headers)?;
            let has_control_header = parsed
                .headers
                .iter()
                .any(|h| h.name.eq_ignore_ascii_case(CONTROL_HEADER));
            let header = |name: &str| {
                parsed
                    .headers
                    .iter()
                    .find(|h| h.name.eq_ignore_ascii_case(name))
                    .map(|h| String::from_utf8_lossy(h.value).trim().to_string())
            };
            let host = header("host");
            let origin = header("origin");
            let method = parsed.method.unwrap_or_default().to_string();
            let path = parsed.path.unwrap_or_default();
            let path = path.split_once('?').map_or(path, |(p, _)| p).to_string();
            let end = head.checked_add(length).filter(|&e| e <= buf.len());
            let end = end.ok_or(RequestError::TooLarge)?;
            while filled < end {
                let n = read_before(socket, &mut buf[filled..end], deadline)?;
                if n == 0 {
                    return Err(RequestError::Incomplete);
                }
                filled += n;
            }
            let body = String::from_utf8_lossy(&buf[head..end]).into_owned();
            return Ok(Request {
                method,
                path,
                has_control_header,
                host,
                origin,
                body,
            });
        }
        if filled == buf.len() {
            return Err(RequestError::TooLarge);
        }
    }
}

/// One read that waits no later than `deadline`.
fn read_before(
    socket: &mut TcpStream,
    buf: &mut [u8],
    deadline: Instant,
) -> Result<usize, RequestError> {
    let left = deadline.saturating_duration_since(Instant::now());
    if left.is_zero() {
        return Err(RequestError::TimedOut);
    }
    socket.set_read_timeout(Some(left))?;
    match socket.read(buf) {
        Ok(n) => Ok(n),
        Err(e)
            if matches!(
                e.kind(),
                io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
            ) =>
        {
            Err(RequestError::TimedOut)
        }
        Err(e) => Err(e.into()),
    }
}

/// The body's length; two `Content-Length` headers (even equal ones) are refused, as a
/// proxy in front could have read the body by the other one (RFC 9112 §6.3).
fn content_length(headers: &[httparse::Header<'_>]) -> Result<usize, RequestError> {
    let mut lengths = headers
        .iter()
        .filter(|h| h.name.eq_ignore_ascii_case("content-length"));
    let first = lengths.next();
    if lengths.next().is_some() {
        return Err(RequestError::DuplicateLength);
    }
    match first {
        None => Ok(0),
        Some(h) => std::str::from_utf8(h.value)
            .ok()
            .and_then(|v| v.trim().parse().ok())
            .ok_or(RequestError::Malformed(httparse::Error::HeaderValue)),
    }
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        409 => "Conflict",
        421 => "Misdirected Request",
        503 => "Service Unavailable",
        _ => "Internal Server Error",
    }
}

/// A whole response; the page may load nothing from elsewhere (Content-Security-Policy).
fn respond(socket: &mut TcpStream, status: u16, content_type: &str, body: &str) -> io::Result<()> {
    write!(
        socket,
        "HTTP/1.1 {status} {}\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n\
         Cache-Control: no-store\r\nConnection: close\r\nX-Content-Type-Options: nosniff\r\n\
         Content-Security-Policy: default-src 'self'; img-src 'self' data:\r\n\r\n{body}",
        reason(status),
        body.len()
    )?;
    socket.flush()
}
