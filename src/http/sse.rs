//! One page's event stream: the Server-Sent Events response (WHATWG HTML, "Server-sent
//! events"), written from the page's queue until the feed drops the page, the feed stops or
//! the browser goes away.

use std::io::{self, Write};
use std::net::TcpStream;

use crossbeam_channel::Receiver;

use super::feed::Event;

/// The browser reconnects this long after a dropped stream, ms (the `retry` field).
const RECONNECT_MS: u32 = 1000;

/// Write the response head, then every event from `queue` as it comes. Returns when the
/// queue is closed (the page was dropped or the server stops) or a write fails or times out
/// (the socket's write timeout is set by the server).
pub fn stream(mut socket: TcpStream, queue: &Receiver<Event>) -> io::Result<()> {
    write!(
        socket,
        "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
         Connection: close\r\nX-Content-Type-Options: nosniff\r\n\r\nretry: {RECONNECT_MS}\n\n"
    )?;
    socket.flush()?;
    while let Ok(e) = queue.recv() {
        socket.write_all(e.as_bytes())?;
    }
    Ok(())
}
