//! The server's route table: the configured allow-list plus the routes clients add at run time
//! through the ADS route service (UDP 48899, `route_service.rs`), shared behind one lock.

use std::net::IpAddr;
use std::sync::{Mutex, MutexGuard};

use crate::vocab::ams::{AmsNetId, RouteEntry};

/// Most entries the table holds; an add-route beyond it is refused (a datagram flood cannot
/// grow the table without bound). Far above what a TwinCAT router's route dialog lists.
pub const MAX_ROUTES: usize = 256;

/// Why a route was not added.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum RouteError {
    #[error("route table full ({MAX_ROUTES} entries)")]
    Full,
}

/// Who may talk to the server. `open`: the configured list was empty, so everyone is served,
/// and routes added later are recorded without shutting anyone else out.
#[derive(Debug)]
pub struct RouteTable {
    open: bool,
    entries: Mutex<Vec<RouteEntry>>,
}

impl RouteTable {
    /// The table of the configured allow-list (`ServerConfig::allow`); empty = everyone.
    pub fn new(configured: &[RouteEntry]) -> Self {
        RouteTable {
            open: configured.is_empty(),
            entries: Mutex::new(configured.iter().take(MAX_ROUTES).copied().collect()),
        }
    }

    fn lock(&self) -> MutexGuard<'_, Vec<RouteEntry>> {
        self.entries.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Every client is served (no allow-list was configured).
    pub fn is_open(&self) -> bool {
        self.open
    }

    /// The peer's IP address is routed (or everyone is).
    pub fn routes_ip(&self, ip: IpAddr) -> bool {
        self.open || self.lock().contains(&RouteEntry::Ip(ip))
    }

    /// The source NetId is routed (or everyone is).
    pub fn routes_net_id(&self, id: AmsNetId) -> bool {
        self.open || self.lock().contains(&RouteEntry::NetId(id))
    }

    /// Some NetId is routed: a peer whose IP is not listed may still send frames from one.
    pub fn has_net_id_routes(&self) -> bool {
        self.lock()
            .iter()
            .any(|r| matches!(r, RouteEntry::NetId(_)))
    }

    /// Add `entry` (once); refused when the table is full.
    pub fn add(&self, entry: RouteEntry) -> Result<(), RouteError> {
        let mut e = self.lock();
        if e.contains(&entry) {
            return Ok(());
        }
        if e.len() >= MAX_ROUTES {
            return Err(RouteError::Full);
        }
        e.push(entry);
        Ok(())
    }

    /// The entries, configured and added, in order.
    pub fn entries(&self) -> Vec<RouteEntry> {
        self.lock().clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_open_table_stays_open_when_routes_are_added() {
        let t = RouteTable::new(&[]);
        t.add(RouteEntry::NetId(AmsNetId([10, 0, 0, 1, 1, 1])))
            .unwrap();
        assert!(t.routes_net_id(AmsNetId([10, 0, 0, 2, 1, 1])));
        assert_eq!(t.entries().len(), 1);
    }

    #[test]
    fn a_closed_table_admits_what_is_added_and_stays_bounded() {
        let listed = RouteEntry::Ip("10.0.0.9".parse().unwrap());
        let t = RouteTable::new(&[listed]);
        let id = AmsNetId([10, 0, 0, 1, 1, 1]);
        assert!(!t.routes_net_id(id));
        t.add(RouteEntry::NetId(id)).unwrap();
        t.add(RouteEntry::NetId(id)).unwrap();
        assert!(t.routes_net_id(id));
        assert_eq!(t.entries().len(), 2, "added once");
        for i in 0..MAX_ROUTES {
            let _ = t.add(RouteEntry::NetId(AmsNetId([
                1,
                2,
                (i >> 8) as u8,
                i as u8,
                1,
                1,
            ])));
        }
        assert_eq!(t.entries().len(), MAX_ROUTES);
        assert_eq!(
            t.add(RouteEntry::NetId(AmsNetId([9, 9, 9, 9, 9, 9]))),
            Err(RouteError::Full)
        );
    }
}
