//! The ADS endpoint's vocabulary: the AMS NetId, the route allow-list's entries and the
//! server's default limits. Here, below both, so the configuration (runtime.toml `[ads]`)
//! names and defaults them with the ADS server's own parser and numbers without depending on
//! the server (Beckhoff's ADS specification: the AMS NetId is six bytes written `a.b.c.d.e.f`).

use std::fmt;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::str::FromStr;
use std::time::Duration;

/// Default upper bound for the AMS/TCP length field (runtime config `ads.max_frame_bytes`).
pub const DEFAULT_MAX_FRAME_BYTES: usize = 65_536;

/// Default bind address: loopback only, the standard ADS/TCP port.
pub(crate) const DEFAULT_BIND: SocketAddr = SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), 48898);
/// Default bound on simultaneous connections.
pub const DEFAULT_MAX_CONNECTIONS: usize = 64;
/// Default bound on notification handles per connection.
pub(crate) const DEFAULT_MAX_NOTIFICATIONS: usize = 256;
/// Default bound on notification handles over the whole server.
pub(crate) const DEFAULT_MAX_NOTIFICATIONS_TOTAL: usize = 1024;
/// Default budget of notification samples per second of one connection: ten 1 ms handles
/// (each handle costs one sample per cycle time). What one client asks beyond it is refused
/// (0x716) to that client only.
pub const DEFAULT_NOTIFICATION_SAMPLES_PER_S_PER_CONNECTION: u64 = 10_000;
/// Default budget of notification samples per second over the whole server: four connections
/// at their whole budget, so one client never holds more than a quarter of it (ten HMIs that
/// each hold an ADS-state and a symbol-version handle at 1 ms, 2 000/s each, fit beside a
/// tool with ten 1 ms handles). runtime.toml `ads.notification_samples_per_s` and
/// `ads.notification_samples_per_s_per_connection` set both.
pub const DEFAULT_NOTIFICATION_SAMPLES_PER_S: u64 =
    4 * DEFAULT_NOTIFICATION_SAMPLES_PER_S_PER_CONNECTION;
/// Default idle timeout (`ads::server::ServerConfig::idle_timeout`).
pub(crate) const DEFAULT_IDLE_TIMEOUT: Duration = Duration::from_secs(60);
/// Default time a request waits for the runtime before it is answered 0x708 "busy, not
/// applied" (runtime.toml `ads.reply_timeout_ms`). A tick answers within one period (1 ms);
/// 500 ms outlasts any tick the runtime's budgets allow by far, yet is a quarter of the
/// shortest default request timeout of the common clients (Node `ads-client` 2 s; Beckhoff
/// AdsLib, pyads and TwinCAT.Ads 5 s), so a stalled runtime is reported, never left silent.
pub const DEFAULT_REPLY_TIMEOUT: Duration = Duration::from_millis(500);
/// Default AMS NetId of the server (runtime.toml `ads.net_id`): not `127.0.0.1.1.1`, which the
/// Rust `ads` crate (0.4, `Client::device`) rewrites to the client's own NetId, and not the
/// `<IPv4>.1.1` a client on loopback derives for itself (the `ads` crate's `Source::Auto`,
/// pyads, and this server's answer to a router port request), which must differ from the
/// target's.
pub const DEFAULT_NET_ID: AmsNetId = AmsNetId([127, 0, 0, 2, 1, 1]);

/// A six-byte AMS network id, written `a.b.c.d.e.f`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, PartialOrd, Ord, serde::Deserialize)]
#[serde(try_from = "String")]
pub struct AmsNetId(pub [u8; 6]);

impl TryFrom<String> for AmsNetId {
    type Error = NetIdParseError;
    fn try_from(s: String) -> Result<Self, Self::Error> {
        s.parse()
    }
}

impl AmsNetId {
    /// The local NetId clients use when they talk to "this machine".
    pub const LOCAL: AmsNetId = AmsNetId([127, 0, 0, 1, 1, 1]);
}

impl fmt::Display for AmsNetId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [a, b, c, d, e, g] = self.0;
        write!(f, "{a}.{b}.{c}.{d}.{e}.{g}")
    }
}

/// Why a NetId string did not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("invalid AMS NetId {text:?}: expected six numbers 0-255 separated by dots (a.b.c.d.e.f)")]
pub struct NetIdParseError {
    pub text: String,
}

impl FromStr for AmsNetId {
    type Err = NetIdParseError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = || NetIdParseError {
            text: s.to_string(),
        };
        let mut out = [0u8; 6];
        let mut parts = s.split('.');
        for byte in out.iter_mut() {
            let part = parts.next().ok_or_else(err)?;
            if part.is_empty() || part.len() > 3 || !part.bytes().all(|b| b.is_ascii_digit()) {
                return Err(err());
            }
            *byte = part.parse().map_err(|_| err())?;
        }
        if parts.next().is_some() {
            return Err(err());
        }
        Ok(AmsNetId(out))
    }
}

/// One entry of the route allow-list: a client NetId or a peer IP address.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(try_from = "String")]
pub enum RouteEntry {
    NetId(AmsNetId),
    Ip(IpAddr),
}

impl fmt::Display for RouteEntry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RouteEntry::NetId(id) => write!(f, "{id}"),
            RouteEntry::Ip(ip) => write!(f, "{ip}"),
        }
    }
}

impl TryFrom<String> for RouteEntry {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl FromStr for RouteEntry {
    type Err = String;

    /// `a.b.c.d.e.f` is a NetId; anything `IpAddr` parses is an address.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if let Ok(id) = s.parse::<AmsNetId>() {
            return Ok(RouteEntry::NetId(id));
        }
        s.parse::<IpAddr>()
            .map(RouteEntry::Ip)
            .map_err(|_| format!("route {s:?} is neither an AMS NetId nor an IP address"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn net_id_round_trips_and_rejects_garbage() {
        let id: AmsNetId = "192.168.0.10.1.1".parse().unwrap();
        assert_eq!(id.0, [192, 168, 0, 10, 1, 1]);
        assert_eq!(id.to_string(), "192.168.0.10.1.1");
        for bad in [
            "1.2.3.4.5",
            "1.2.3.4.5.6.7",
            "1.2.3.4.5.256",
            "1..3.4.5.6",
            "a.b.c.d.e.f",
            "",
            "1.2.3.4.5.+6",
        ] {
            assert!(bad.parse::<AmsNetId>().is_err(), "{bad:?} parsed");
        }
    }
}
