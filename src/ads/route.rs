//! The route allow-list's entries: which clients the ADS server serves. A value type of its
//! own, so the configuration (runtime.toml `[ads] allowed_clients`) names routes without
//! depending on the server.

use std::net::IpAddr;
use std::str::FromStr;

use super::frame::AmsNetId;

/// One entry of the route allow-list: a client NetId or a peer IP address.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(try_from = "String")]
pub enum RouteEntry {
    NetId(AmsNetId),
    Ip(IpAddr),
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
