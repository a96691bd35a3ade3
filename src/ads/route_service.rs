//! The ADS route service on UDP 48899 (Beckhoff's discovery/route protocol): identify (NetId,
//! host name, TwinCAT version, OS) and add-route, which feeds the server's route table.
//!
//! Wire format, as the public clients send and parse it (birkenfeld/ads-rs `src/udp.rs`,
//! stlehmann/pyads `pyads_ex.py` `adsAddRouteToPLC`/`adsGetNetIdForPLC`): a 24-byte header —
//! magic 0x71146603, invoke id, service (1 identify, 6 add route; | 0x8000_0000 in the
//! reply), the sender's AMS address (NetId + port), the item count (all u32/u16 LE) — then
//! that many items `tag u16, length u16, bytes`. Strings carry their NUL.

use std::io;
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

use super::frame::AmsAddr;
use super::routes::RouteTable;
use crate::vocab::ams::{AmsNetId, RouteEntry};

/// The route service's UDP port (`ads::UDP_PORT` in the `ads` crate, `PORT_REMOTE_UDP` in pyads).
pub const ROUTE_SERVICE_PORT: u16 = 48899;
const MAGIC: u32 = 0x7114_6603;
const HEADER_LEN: usize = 24;
const SERVICE_IDENTIFY: u32 = 1;
const SERVICE_ADD_ROUTE: u32 = 6;
const RESPONSE: u32 = 0x8000_0000;
const TAG_STATUS: u16 = 1;
const TAG_TC_VERSION: u16 = 3;
const TAG_OS_VERSION: u16 = 4;
const TAG_COMPUTER_NAME: u16 = 5;
const TAG_NET_ID: u16 = 7;
/// Largest datagram read; a longer one is cut there (and then is malformed).
const MAX_DATAGRAM: usize = 2048;
/// ADS error "invalid parameter value(s)" (0x70B), the status of an add-route without a NetId.
const STATUS_INVALID: u32 = 0x70B;
/// ADS error "no memory" (0x70A), the status of an add-route the full route table refuses.
const STATUS_TABLE_FULL: u32 = 0x70A;

/// A datagram that is not a request of the route service; it is dropped unanswered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DatagramError {
    #[error("shorter than the 24-byte header ({0} bytes)")]
    Short(usize),
    #[error("magic 0x{0:08X} is not the route service's")]
    Magic(u32),
    #[error("item {0} runs past the end of the datagram")]
    Item(u32),
}

/// One request: its header and its items, borrowed from the datagram.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Datagram<'a> {
    pub invoke_id: u32,
    pub service: u32,
    pub source: AmsAddr,
    items: &'a [u8],
    count: u32,
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes([*b.get(at)?, *b.get(at + 1)?]))
}

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

/// Parse a datagram; every item is checked to lie inside it.
pub fn parse(bytes: &[u8]) -> Result<Datagram<'_>, DatagramError> {
    let short = DatagramError::Short(bytes.len());
    let head = bytes.get(..HEADER_LEN).ok_or(short)?;
    let magic = u32_at(head, 0).ok_or(short)?;
    if magic != MAGIC {
        return Err(DatagramError::Magic(magic));
    }
    let mut id = [0u8; 6];
    id.copy_from_slice(&head[12..18]);
    let d = Datagram {
        invoke_id: u32_at(head, 4).ok_or(short)?,
        service: u32_at(head, 8).ok_or(short)?,
        source: AmsAddr {
            net_id: AmsNetId(id),
            port: u16_at(head, 18).ok_or(short)?,
        },
        items: &bytes[HEADER_LEN..],
        count: u32_at(head, 20).ok_or(short)?,
    };
    // Walk the items once: the count is the client's, the bytes bound the walk.
    let mut rest = d.items;
    for i in 0..d.count {
        let len = u16_at(rest, 2).ok_or(DatagramError::Item(i))? as usize;
        rest = rest.get(4 + len..).ok_or(DatagramError::Item(i))?;
    }
    Ok(d)
}

impl<'a> Datagram<'a> {
    /// The first item with `tag`, its bytes.
    pub fn item(&self, tag: u16) -> Option<&'a [u8]> {
        let mut rest = self.items;
        for _ in 0..self.count {
            let t = u16_at(rest, 0)?;
            let len = u16_at(rest, 2)? as usize;
            let value = rest.get(4..4 + len)?;
            if t == tag {
                return Some(value);
            }
            rest = &rest[4 + len..];
        }
        None
    }

    /// A string item without its NUL (and anything after it); `None` when not UTF-8.
    pub fn text(&self, tag: u16) -> Option<&'a str> {
        let b = self.item(tag)?;
        let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
        std::str::from_utf8(&b[..end]).ok()
    }
}

/// What identify answers: this device.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    pub net_id: AmsNetId,
    pub host_name: String,
}

/// The TwinCAT version the system service answers in ReadDeviceInfo (`system::device_info`).
fn tc_version() -> [u8; 4] {
    let (major, minor, build, _) =
        super::system::device_info(super::system::PORT).unwrap_or((0, 0, 0, ""));
    let b = build.to_le_bytes();
    [major, minor, b[0], b[1]]
}

/// The OS item: an OSVERSIONINFO as Windows writes it (size, major, minor, build, platform,
/// then the service-pack text in UTF-16). This host's OS name goes in the text, platform 0
/// (none of the Windows platform ids), version numbers 0: nothing else is known portably.
fn os_version() -> Vec<u8> {
    let text: Vec<u16> = std::env::consts::OS.encode_utf16().chain([0]).collect();
    let mut out = Vec::with_capacity(20 + 2 * text.len());
    let size = (20 + 2 * text.len()) as u32;
    for v in [size, 0, 0, 0, 0] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for c in text {
        out.extend_from_slice(&c.to_le_bytes());
    }
    out
}

/// A reply under construction: the header with the item count patched as items go in.
struct Reply(Vec<u8>);

impl Reply {
    fn new(req: &Datagram<'_>, me: AmsAddr) -> Self {
        let mut b = Vec::with_capacity(256);
        b.extend_from_slice(&MAGIC.to_le_bytes());
        b.extend_from_slice(&req.invoke_id.to_le_bytes());
        b.extend_from_slice(&(req.service | RESPONSE).to_le_bytes());
        b.extend_from_slice(&me.net_id.0);
        b.extend_from_slice(&me.port.to_le_bytes());
        b.extend_from_slice(&0u32.to_le_bytes());
        Reply(b)
    }

    fn item(mut self, tag: u16, value: &[u8]) -> Self {
        let len = u16::try_from(value.len()).unwrap_or(u16::MAX);
        self.0.extend_from_slice(&tag.to_le_bytes());
        self.0.extend_from_slice(&len.to_le_bytes());
        self.0.extend_from_slice(&value[..usize::from(len)]);
        let count = u32_at(&self.0, 20).unwrap_or(0) + 1;
        self.0[20..24].copy_from_slice(&count.to_le_bytes());
        self
    }
}

/// What a request did, for the log.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Outcome {
    Identified,
    RouteAdded(Vec<RouteEntry>),
    RouteRefused(u32),
    /// A service this server does not offer: not answered, as TwinCAT ignores it.
    Ignored(u32),
}

/// The reply to one datagram (`None`: not answered) and what it did. Add-route takes the
/// NetId item, and the computer-name item when it is an IP address, into `routes`; the user
/// name and password are not checked (the emulator has no user accounts).
pub fn answer(
    bytes: &[u8],
    me: &Identity,
    routes: &RouteTable,
) -> Result<(Option<Vec<u8>>, Outcome), DatagramError> {
    let req = parse(bytes)?;
    let addr = AmsAddr {
        net_id: me.net_id,
        port: super::system::PORT,
    };
    match req.service {
        SERVICE_IDENTIFY => {
            let mut name = me.host_name.clone().into_bytes();
            name.push(0);
            let reply = Reply::new(&req, addr)
                .item(TAG_COMPUTER_NAME, &name)
                .item(TAG_TC_VERSION, &tc_version())
                .item(TAG_OS_VERSION, &os_version());
            Ok((Some(reply.0), Outcome::Identified))
        }
        SERVICE_ADD_ROUTE => {
            let (status, outcome) = add_route(&req, routes);
            let reply = Reply::new(&req, addr).item(TAG_STATUS, &status.to_le_bytes());
            Ok((Some(reply.0), outcome))
        }
        other => Ok((None, Outcome::Ignored(other))),
    }
}

fn add_route(req: &Datagram<'_>, routes: &RouteTable) -> (u32, Outcome) {
    let Some(id) = req
        .item(TAG_NET_ID)
        .and_then(|b| <[u8; 6]>::try_from(b).ok())
    else {
        return (STATUS_INVALID, Outcome::RouteRefused(STATUS_INVALID));
    };
    let mut added = vec![RouteEntry::NetId(AmsNetId(id))];
    if let Some(ip) = req.text(TAG_COMPUTER_NAME).and_then(|t| t.parse().ok()) {
        added.push(RouteEntry::Ip(ip));
    }
    for e in &added {
        if routes.add(*e).is_err() {
            return (STATUS_TABLE_FULL, Outcome::RouteRefused(STATUS_TABLE_FULL));
        }
    }
    (0, Outcome::RouteAdded(added))
}

/// This host's name (Linux `/proc/sys/kernel/hostname`), else `ncchannel`; at most 64 bytes.
pub fn host_name() -> String {
    let name = std::fs::read("/proc/sys/kernel/hostname")
        .ok()
        .map(|b| {
            String::from_utf8_lossy(&b[..b.len().min(64)])
                .trim()
                .to_string()
        })
        .filter(|n| !n.is_empty());
    name.unwrap_or_else(|| "ncchannel".to_string())
}

/// The running service: `stop()` (or drop) ends its thread.
pub struct RouteService {
    local_addr: SocketAddr,
    stopping: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl RouteService {
    /// Bind `bind` (the caller has checked it is loopback, or allowed) and answer there.
    /// `log` gets one line per route added or refused and per malformed datagram source
    /// (the caller rate-limits it).
    pub fn spawn(
        bind: SocketAddr,
        me: Identity,
        routes: Arc<RouteTable>,
        log: impl Fn(String) + Send + 'static,
    ) -> io::Result<RouteService> {
        let socket = UdpSocket::bind(bind)?;
        let local_addr = socket.local_addr()?;
        // Wake often enough to notice the stop.
        socket.set_read_timeout(Some(Duration::from_millis(200)))?;
        let stopping = Arc::new(AtomicBool::new(false));
        let stop = Arc::clone(&stopping);
        let thread = std::thread::Builder::new()
            .name("ads-route-udp".into())
            .spawn(move || serve(&socket, &me, &routes, &stop, &log))?;
        Ok(RouteService {
            local_addr,
            stopping,
            thread: Some(thread),
        })
    }

    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    pub fn stop(&mut self) {
        self.stopping.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for RouteService {
    fn drop(&mut self) {
        self.stop();
    }
}

fn serve(
    socket: &UdpSocket,
    me: &Identity,
    routes: &RouteTable,
    stopping: &AtomicBool,
    log: &dyn Fn(String),
) {
    let mut buf = [0u8; MAX_DATAGRAM];
    while !stopping.load(Ordering::SeqCst) {
        let (n, from) = match socket.recv_from(&mut buf) {
            Ok(r) => r,
            Err(_) => continue,
        };
        match answer(&buf[..n], me, routes) {
            Ok((reply, outcome)) => {
                if let Some(r) = reply {
                    let _ = socket.send_to(&r, from);
                }
                match outcome {
                    Outcome::RouteAdded(e) => {
                        let e: Vec<String> = e.iter().map(ToString::to_string).collect();
                        log(format!("{from}: route added: {}", e.join(", ")))
                    }
                    Outcome::RouteRefused(s) => {
                        log(format!("{from}: add-route refused, status 0x{s:X}"))
                    }
                    Outcome::Ignored(s) => log(format!(
                        "{from}: route service 0x{s:X} not offered: datagram ignored"
                    )),
                    Outcome::Identified => {}
                }
            }
            Err(e) => log(format!("{from}: UDP datagram dropped: {e}")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(service: u32, items: &[(u16, &[u8])]) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend_from_slice(&MAGIC.to_le_bytes());
        b.extend_from_slice(&7u32.to_le_bytes());
        b.extend_from_slice(&service.to_le_bytes());
        b.extend_from_slice(&[10, 1, 2, 3, 1, 1, 0x10, 0x27]);
        b.extend_from_slice(&(items.len() as u32).to_le_bytes());
        for (t, v) in items {
            b.extend_from_slice(&t.to_le_bytes());
            b.extend_from_slice(&(v.len() as u16).to_le_bytes());
            b.extend_from_slice(v);
        }
        b
    }

    fn me() -> Identity {
        Identity {
            net_id: AmsNetId([127, 0, 0, 2, 1, 1]),
            host_name: "box".into(),
        }
    }

    #[test]
    fn identify_names_the_device_and_echoes_the_invoke_id() {
        let routes = RouteTable::new(&[]);
        let (reply, _) = answer(&request(1, &[]), &me(), &routes).unwrap();
        let reply = reply.unwrap();
        let d = parse(&reply).unwrap();
        assert_eq!(d.invoke_id, 7);
        assert_eq!(d.service, 0x8000_0001);
        assert_eq!(d.source.net_id, me().net_id);
        assert_eq!(d.text(TAG_COMPUTER_NAME), Some("box"));
        assert_eq!(d.item(TAG_TC_VERSION), Some(&[3, 1, 0xB8, 0x0F][..]));
        assert!(d.item(TAG_OS_VERSION).is_some_and(|o| o.len() >= 22));
    }

    /// pyads reads the status at bytes 26..29 of a reply of at most 32 bytes.
    #[test]
    fn add_route_feeds_the_table_in_a_32_byte_reply() {
        let routes = RouteTable::new(&["10.9.9.9".parse().unwrap()]);
        let req = request(
            6,
            &[
                (12, b"route\0"),
                (7, &[10, 1, 2, 3, 1, 1]),
                (13, b"Administrator\0"),
                (2, b"1\0"),
                (5, b"10.1.2.3\0"),
            ],
        );
        let (reply, outcome) = answer(&req, &me(), &routes).unwrap();
        let reply = reply.unwrap();
        assert_eq!(reply.len(), 32);
        assert_eq!(&reply[26..29], b"\x04\x00\x00");
        assert_eq!(reply[11], 0x80);
        assert!(matches!(outcome, Outcome::RouteAdded(_)));
        assert!(routes.routes_net_id(AmsNetId([10, 1, 2, 3, 1, 1])));
        assert!(routes.routes_ip("10.1.2.3".parse().unwrap()));
        let (reply, _) = answer(&request(6, &[(7, b"short")]), &me(), &routes).unwrap();
        assert_eq!(
            parse(&reply.unwrap()).unwrap().item(TAG_STATUS),
            Some(&0x70Bu32.to_le_bytes()[..])
        );
    }

    #[test]
    fn malformed_datagrams_are_errors_never_panics() {
        assert_eq!(parse(&[0; 3]), Err(DatagramError::Short(3)));
        assert!(matches!(parse(&[0; 24]), Err(DatagramError::Magic(0))));
        let mut lying = request(6, &[(7, &[1, 2, 3, 4, 5, 6])]);
        lying[20] = 200; // 200 items claimed, one present
        assert_eq!(parse(&lying), Err(DatagramError::Item(1)));
        let mut cut = request(6, &[(7, &[1, 2, 3, 4, 5, 6])]);
        cut.truncate(cut.len() - 1);
        assert_eq!(parse(&cut), Err(DatagramError::Item(0)));
        let mut huge = request(6, &[]);
        huge[20..24].copy_from_slice(&u32::MAX.to_le_bytes());
        assert_eq!(parse(&huge), Err(DatagramError::Item(0)));
        // Every prefix of a valid request parses or errs; none panics.
        let ok = request(6, &[(7, &[1, 2, 3, 4, 5, 6]), (5, b"h\0")]);
        for cut in 0..ok.len() {
            let _ = answer(&ok[..cut], &me(), &RouteTable::new(&[]));
        }
        assert_eq!(
            answer(&request(3, &[]), &me(), &RouteTable::new(&[])).unwrap(),
            (None, Outcome::Ignored(3))
        );
    }
}
