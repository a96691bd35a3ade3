//! The ADS server's connection table: who holds a slot, when each last made progress, and
//! which connection gives its slot up to a new client when the table is full.
//!
//! Progress is a request answered (or a router port request): trickled bytes, router or
//! unknown frames, frames dropped for want of a route and notifications sent to a client
//! do not count. When all `max_connections` slots are held, a new client takes the slot of
//! the oldest connection that has not completed a request within [`FIRST_REQUEST_GRACE`] of
//! connecting; failing that, of the connection that has made no progress for longest,
//! provided that is at least [`EVICT_QUIET`]; when neither exists, the new client is
//! refused. One remote (non-loopback) address holds at most a quarter of the slots
//! ([`Slots::per_remote_peer`]). Why: docs/ads-limits.md.

use std::collections::HashMap;
use std::net::{Shutdown, SocketAddr, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// A connection that has made no progress for this long gives its slot up to a new client
/// when the table is full. Clients that poll (HMIs read every second or faster) and streaming
/// clients make progress far more often; a client that only listens to notifications is
/// quiet and may lose its slot when the table is full.
pub const EVICT_QUIET: Duration = Duration::from_secs(5);

/// A connection that has not completed a request this long after it connected gives its
/// slot up to a new client, before any connection that has. Every ADS client sends its first
/// request at once after connecting; a connection that sends nothing (a port scanner, a
/// crashed client's reconnect loop, a flood of empty connects) is not a client yet. Long
/// enough for a client on a slow link to complete its first request, short enough that 60
/// empty connects a second cannot keep all 64 slots younger than it.
pub const FIRST_REQUEST_GRACE: Duration = Duration::from_millis(500);

/// When a connection last made progress, updated by its own thread.
#[derive(Debug)]
pub(super) struct Progress {
    epoch: Instant,
    /// Nanoseconds from `epoch` to the last progress, or to the connect before the first.
    last_ns: AtomicU64,
    /// Whether a request of the connection has been answered.
    answered: AtomicBool,
}

impl Progress {
    fn new(epoch: Instant) -> Self {
        Progress {
            epoch,
            last_ns: AtomicU64::new(Self::now_ns(epoch)),
            answered: AtomicBool::new(false),
        }
    }

    fn now_ns(epoch: Instant) -> u64 {
        u64::try_from(epoch.elapsed().as_nanos()).unwrap_or(u64::MAX)
    }

    /// The connection made progress now.
    pub(super) fn mark(&self) {
        self.last_ns
            .store(Self::now_ns(self.epoch), Ordering::Relaxed);
        self.answered.store(true, Ordering::Relaxed);
    }

    /// How long the connection has waited for its first request since it connected, or
    /// `None` once one was answered.
    fn unanswered_for(&self) -> Option<Duration> {
        (!self.answered.load(Ordering::Relaxed)).then(|| self.quiet())
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
    /// The slot of `victim`, which was closed to make room.
    Evicted {
        id: u64,
        progress: Arc<Progress>,
        victim: SocketAddr,
        why: Victim,
    },
    /// Every slot is held by a connection that made progress within [`EVICT_QUIET`], or that
    /// connected within [`FIRST_REQUEST_GRACE`].
    Full,
    /// The new client's remote address already holds [`Slots::per_remote_peer`] slots.
    PeerFull(usize),
}

/// Why a connection gave its slot up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Victim {
    /// No request of it was answered in this long since it connected.
    NoFirstRequest(Duration),
    /// It made no progress for this long.
    Quiet(Duration),
}

impl std::fmt::Display for Victim {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Victim::NoFirstRequest(d) => write!(
                f,
                "no request since it connected {:.1} s ago",
                d.as_secs_f64()
            ),
            Victim::Quiet(d) => write!(f, "no request for {:.1} s", d.as_secs_f64()),
        }
    }
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

    /// Slots one remote (non-loopback) address may hold: a quarter of the table, at least
    /// one. Loopback clients share one address and are not capped (docs/ads-limits.md).
    pub(super) fn per_remote_peer(&self) -> usize {
        (self.max / 4).max(1)
    }

    /// Give `socket` (a clone of the new connection's) a slot, evicting a connection when the
    /// table is full (the module's header says which). Evicted connections still being
    /// closed count against a second bound of `max` more, so threads stay bounded by 2 × `max`.
    pub(super) fn admit(&self, socket: TcpStream, peer: SocketAddr) -> Admission {
        let mut table = self.lock();
        if table.len() >= 2 * self.max {
            return Admission::Full;
        }
        if !peer.ip().is_loopback() {
            let same_peer = table
                .values()
                .filter(|s| !s.evicted && s.peer.ip() == peer.ip())
                .count();
            if same_peer >= self.per_remote_peer() {
                return Admission::PeerFull(same_peer);
            }
        }
        let held = table.values().filter(|s| !s.evicted).count();
        let mut evicted = None;
        if held >= self.max {
            let Some(slot) = Self::victim(&mut table) else {
                return Admission::Full;
            };
            let why = match slot.progress.unanswered_for() {
                Some(d) => Victim::NoFirstRequest(d),
                None => Victim::Quiet(slot.progress.quiet()),
            };
            slot.evicted = true;
            let _ = slot.socket.shutdown(Shutdown::Both);
            evicted = Some((slot.peer, why));
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
            Some((victim, why)) => Admission::Evicted {
                id,
                progress,
                victim,
                why,
            },
        }
    }

    /// The connection to close for a newcomer: the oldest one without a first request past
    /// [`FIRST_REQUEST_GRACE`], else the quietest past [`EVICT_QUIET`].
    fn victim(table: &mut HashMap<u64, Slot>) -> Option<&mut Slot> {
        let mut no_first: Option<(Duration, u64)> = None;
        let mut quietest: Option<(Duration, u64)> = None;
        for (&id, s) in table.iter().filter(|(_, s)| !s.evicted) {
            match s.progress.unanswered_for() {
                Some(d) if d >= FIRST_REQUEST_GRACE => {
                    if no_first.is_none_or(|(best, _)| d > best) {
                        no_first = Some((d, id));
                    }
                }
                Some(_) => {}
                None => {
                    let q = s.progress.quiet();
                    if q >= EVICT_QUIET && quietest.is_none_or(|(best, _)| q > best) {
                        quietest = Some((q, id));
                    }
                }
            }
        }
        let (_, id) = no_first.or(quietest)?;
        table.get_mut(&id)
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

#[cfg(test)]
mod tests {
    use std::net::{SocketAddr, TcpListener, TcpStream};

    use super::{Admission, Slots};

    /// A connected socket to hand to `admit` (its own peer address is not what is tested).
    fn socket(listener: &TcpListener) -> TcpStream {
        TcpStream::connect(listener.local_addr().expect("address")).expect("connect")
    }

    #[test]
    fn one_remote_address_holds_a_quarter_of_the_slots_loopback_any() {
        let listener = TcpListener::bind("127.0.0.1:0").expect("bind");
        let slots = Slots::new(8);
        let remote: SocketAddr = "192.0.2.1:40000".parse().expect("address");
        let other: SocketAddr = "192.0.2.2:40000".parse().expect("address");
        let local: SocketAddr = "127.0.0.1:40000".parse().expect("address");
        for _ in 0..2 {
            assert!(matches!(
                slots.admit(socket(&listener), remote),
                Admission::Admitted(..)
            ));
        }
        assert!(matches!(
            slots.admit(socket(&listener), remote),
            Admission::PeerFull(2)
        ));
        assert!(matches!(
            slots.admit(socket(&listener), other),
            Admission::Admitted(..)
        ));
        for _ in 0..5 {
            assert!(matches!(
                slots.admit(socket(&listener), local),
                Admission::Admitted(..)
            ));
        }
        // All 8 held, each connected just now: nobody is evicted for a ninth.
        assert!(matches!(
            slots.admit(socket(&listener), local),
            Admission::Full
        ));
    }
}
