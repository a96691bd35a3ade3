//! The ADS server's connection table: who holds a slot, when each last made progress, and
//! which connection gives its slot up to a new client when the table is full.
//!
//! Progress is a request answered (or a router port request): trickled bytes, router or
//! unknown frames, frames dropped for want of a route and notifications sent to a client
//! do not count. When all `max_connections` slots are held, a new client takes the slot of
//! the connection that has made no progress for longest, provided that is at least
//! [`EVICT_QUIET`]; when every connection made progress more recently, the new client is
//! refused. Why eviction rather than a per-peer cap or a minimum rate: docs/ads-limits.md.

use std::collections::HashMap;
use std::net::{Shutdown, SocketAddr, TcpStream};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// A connection that has made no progress for this long gives its slot up to a new client
/// when the table is full. Clients that poll (HMIs read every second or faster) and streaming
/// clients make progress far more often; a client that only listens to notifications is
/// quiet and may lose its slot when the table is full.
pub const EVICT_QUIET: Duration = Duration::from_secs(5);

/// When a connection last made progress, updated by its own thread.
#[derive(Debug)]
pub(super) struct Progress {
    epoch: Instant,
    /// Nanoseconds from `epoch` to the last progress.
    last_ns: AtomicU64,
}

impl Progress {
    fn new(epoch: Instant) -> Self {
        let p = Progress {
            epoch,
            last_ns: AtomicU64::new(0),
        };
        p.mark();
        p
    }

    /// The connection made progress now.
    pub(super) fn mark(&self) {
        let ns = u64::try_from(self.epoch.elapsed().as_nanos()).unwrap_or(u64::MAX);
        self.last_ns.store(ns, Ordering::Relaxed);
    }

    /// How long since the last progress.
    fn quiet(&self) -> Duration {
        let last = Duration::from_nanos(self.last_ns.load(Ordering::Relaxed));
        self.epoch.elapsed().saturating_sub(last)
    }
}

struct Slot {
    /// A clone of the connection's socket, to close it on eviction or shutdown.
    socket: TcpStream,
    peer: SocketAddr,
    progress: Arc<Progress>,
    /// Closed to make room; its thread is ending and its slot no longer counts.
    evicted: bool,
}

/// What [`Slots::admit`] decided for a new connection.
pub(super) enum Admission {
    /// A free slot: the connection's id and progress.
    Admitted(u64, Arc<Progress>),
    /// The slot of `victim`, quiet for `quiet`, which was closed to make room.
    Evicted {
        id: u64,
        progress: Arc<Progress>,
        victim: SocketAddr,
        quiet: Duration,
    },
    /// Every slot is held by a connection that made progress within [`EVICT_QUIET`].
    Full,
}

/// The table of connections.
pub(super) struct Slots {
    max: usize,
    epoch: Instant,
    next_id: AtomicU64,
    table: Mutex<HashMap<u64, Slot>>,
}

impl Slots {
    pub(super) fn new(max: usize) -> Self {
        Slots {
            max,
            epoch: Instant::now(),
            next_id: AtomicU64::new(1),
            table: Mutex::new(HashMap::new()),
        }
    }

    fn lock(&self) -> MutexGuard<'_, HashMap<u64, Slot>> {
        self.table.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Give `socket` (a clone of the new connection's) a slot, evicting the quietest
    /// connection when the table is full. Evicted connections still being closed count
    /// against a second bound of `max` more, so threads stay bounded by 2 × `max`.
    pub(super) fn admit(&self, socket: TcpStream, peer: SocketAddr) -> Admission {
        let mut table = self.lock();
        if table.len() >= 2 * self.max {
            return Admission::Full;
        }
        let held = table.values().filter(|s| !s.evicted).count();
        let mut evicted = None;
        if held >= self.max {
            let victim = table
                .iter_mut()
                .filter(|(_, s)| !s.evicted)
                .map(|(_, s)| (s.progress.quiet(), s))
                .filter(|(quiet, _)| *quiet >= EVICT_QUIET)
                .max_by_key(|(quiet, _)| *quiet);
            let Some((quiet, slot)) = victim else {
                return Admission::Full;
            };
            slot.evicted = true;
            let _ = slot.socket.shutdown(Shutdown::Both);
            evicted = Some((slot.peer, quiet));
        }
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        let progress = Arc::new(Progress::new(self.epoch));
        table.insert(
            id,
            Slot {
                socket,
                peer,
                progress: Arc::clone(&progress),
                evicted: false,
            },
        );
        match evicted {
            None => Admission::Admitted(id, progress),
            Some((victim, quiet)) => Admission::Evicted {
                id,
                progress,
                victim,
                quiet,
            },
        }
    }

    /// The connection `id` ended.
    pub(super) fn leave(&self, id: u64) {
        self.lock().remove(&id);
    }

    /// Whether `id` was closed to make room for another client.
    pub(super) fn was_evicted(&self, id: u64) -> bool {
        self.lock().get(&id).is_some_and(|s| s.evicted)
    }

    /// Close every connection (the server stops).
    pub(super) fn close_all(&self) {
        for s in self.lock().values() {
            let _ = s.socket.shutdown(Shutdown::Both);
        }
    }
}
