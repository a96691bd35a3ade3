//! The web view's HTTP/1.1 server: accepts connections (at most [`MAX_CONNECTIONS`], one
//! thread each, as the ADS server does), reads one request head with `httparse`, and answers
//! it: the embedded page, the event stream (at most [`MAX_PAGE_CONNECTIONS`] at once) or a
//! control request. Every response closes its connection; there is no keep-alive to bound.

use std::io::{self, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

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
    #[error(transparent)]
    Io(#[from] io::Error),
}

/// One request as the routes need it.
struct Request {
    method: String,
    path: String,
    has_control_header: bool,
    body: String,
}

struct Shared {
    backend: Backend,
    controls: ControlAccess,
    pages: Arc<Pages>,
    stopping: AtomicBool,
    connections: AtomicUsize,
    streams: AtomicUsize,
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

    /// Pages whose event stream is open now.
    pub fn pages_connected(&self) -> usize {
        self.shared.pages.connected()
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
        pages: Arc::clone(&feed.pages),
        stopping: AtomicBool::new(false),
        connections: AtomicUsize::new(0),
        streams: AtomicUsize::new(0),
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
        reserve(counter, limit).then_some(Slot(counter))
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
            let _ = stream.shutdown(Shutdown::Both);
            continue;
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

fn serve_connection(mut socket: TcpStream, shared: &Shared) -> Result<(), RequestError> {
    socket.set_read_timeout(Some(READ_TIMEOUT))?;
    socket.set_write_timeout(Some(WRITE_TIMEOUT))?;
    let req = match read_request(&mut socket) {
        Ok(r) => r,
        Err(e @ (RequestError::TooLarge | RequestError::Malformed(_))) => {
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
    route(socket, &req, shared)
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

/// Read one request head and its body (both within [`MAX_REQUEST_BYTES`]).
fn read_request(socket: &mut TcpStream) -> Result<Request, RequestError> {
    let mut buf = vec![0u8; MAX_REQUEST_BYTES];
    let mut filled = 0;
    loop {
        let n = socket.read(&mut buf[filled..])?;
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
            let method = parsed.method.unwrap_or_default().to_string();
            let path = parsed.path.unwrap_or_default();
            let path = path.split_once('?').map_or(path, |(p, _)| p).to_string();
            let end = head.checked_add(length).filter(|&e| e <= buf.len());
            let end = end.ok_or(RequestError::TooLarge)?;
            while filled < end {
                let n = socket.read(&mut buf[filled..end])?;
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
                body,
            });
        }
        if filled == buf.len() {
            return Err(RequestError::TooLarge);
        }
    }
}

fn content_length(headers: &[httparse::Header<'_>]) -> Result<usize, RequestError> {
    match headers
        .iter()
        .find(|h| h.name.eq_ignore_ascii_case("content-length"))
    {
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
