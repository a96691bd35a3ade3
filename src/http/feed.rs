//! The feed: one thread that polls every channel through the door at [`FEED_PERIOD`] and hands
//! each update, as a ready Server-Sent Event, to every connected page's bounded queue.
//!
//! A poll is one `Status` request per channel, served by the runtime between ticks like any
//! ADS read, and made only while a page is connected; the program text for the listing is
//! asked for only when the executing program changes, and error records only when the
//! channel's error count grows. A page whose queue is full is dropped (its stream ends, the
//! browser reconnects), so a slow page costs neither the runtime nor the other pages anything.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Instant;

use crossbeam_channel::{Receiver, Sender, TrySendError};
use serde::Serialize;

use super::snapshot::{channel_view, cycle_view, ErrorView, Listing, ListingView, Update};
use super::{Backend, FEED_PERIOD, PAGE_QUEUE_UPDATES};
use crate::machine::{Op, Reply, Status};
use crate::vocab::stats::LiveCycleStats;

/// Errors a page is told about when it connects, per channel (older ones are counted only).
pub const KEPT_ERRORS: usize = 32;
/// Error records fetched per channel per poll at most: a channel raising errors faster than
/// that shows the newest ones and the total.
const ERRORS_PER_POLL: u64 = 8;

/// One Server-Sent Event, ready to write.
pub type Event = Arc<str>;

fn event(name: &str, data: &impl Serialize) -> Option<Event> {
    let json = serde_json::to_string(data).ok()?;
    Some(Arc::from(format!("event: {name}\ndata: {json}\n\n")))
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// The connected pages and what a page needs on connecting (listings, recent errors).
#[derive(Default)]
pub struct Pages {
    queues: Mutex<Vec<Sender<Event>>>,
    greeting: Mutex<Greeting>,
    /// Updates sent so far, and pages dropped for reading too slowly.
    pub updates: AtomicU64,
    pub dropped: AtomicU64,
}

#[derive(Default)]
struct Greeting {
    listings: Vec<Option<Event>>,
    errors: Vec<VecDeque<Event>>,
}

impl Pages {
    /// A new page's queue, primed with the listings and recent errors.
    pub fn subscribe(&self) -> Receiver<Event> {
        let greeting = lock(&self.greeting);
        let primed = greeting.listings.iter().flatten().count()
            + greeting.errors.iter().map(VecDeque::len).sum::<usize>();
        let (tx, rx) = crossbeam_channel::bounded(PAGE_QUEUE_UPDATES + primed);
        for e in greeting.listings.iter().flatten() {
            let _ = tx.try_send(Arc::clone(e));
        }
        for e in greeting.errors.iter().flatten() {
            let _ = tx.try_send(Arc::clone(e));
        }
        lock(&self.queues).push(tx);
        rx
    }

    /// Pages connected now.
    pub fn connected(&self) -> usize {
        lock(&self.queues).len()
    }

    fn broadcast(&self, e: &Event) {
        lock(&self.queues).retain(|q| match q.try_send(Arc::clone(e)) {
            Ok(()) => true,
            Err(TrySendError::Full(_)) => {
                self.dropped.fetch_add(1, Ordering::Relaxed);
                false
            }
            Err(TrySendError::Disconnected(_)) => false,
        });
    }

    /// Drop every page (shutdown): their streams end.
    pub fn close_all(&self) {
        lock(&self.queues).clear();
    }

    fn set_listing(&self, index: usize, e: Event) {
        let mut g = lock(&self.greeting);
        if g.listings.len() <= index {
            g.listings.resize(index + 1, None);
        }
        g.listings[index] = Some(e);
    }

    fn push_error(&self, index: usize, e: Event) {
        let mut g = lock(&self.greeting);
        if g.errors.len() <= index {
            g.errors.resize_with(index + 1, VecDeque::new);
        }
        let q = &mut g.errors[index];
        if q.len() == KEPT_ERRORS {
            q.pop_front();
        }
        q.push_back(e);
    }
}

/// What the feed remembers of one channel between polls.
#[derive(Default)]
struct Seen {
    /// The program whose text was asked for last, and the text if the channel had it.
    asked: Option<Arc<str>>,
    listing: Option<Listing>,
    /// Error records fetched so far.
    errors: u64,
}

/// The polling thread's state.
struct Poller {
    backend: Backend,
    live: Option<Arc<LiveCycleStats>>,
    pages: Arc<Pages>,
    seen: Vec<Seen>,
    seq: u64,
}

impl Poller {
    fn poll(&mut self) {
        let n = self.backend.channel_count();
        self.seen.resize_with(usize::from(n), Seen::default);
        let mut channels = Vec::with_capacity(usize::from(n));
        let mut cycle = None;
        for ch in 1..=n {
            let Ok(s) = self.backend.status(ch) else {
                continue;
            };
            let i = usize::from(ch - 1);
            self.follow_program(ch, i, &s);
            self.follow_errors(ch, i, &s);
            cycle.get_or_insert_with(|| cycle_view(&s, self.live.as_ref().map(|l| l.read())));
            channels.push(channel_view(ch, &s, self.seen[i].listing.as_ref()));
        }
        self.seq += 1;
        let update = Update {
            seq: self.seq,
            cycle,
            channels,
        };
        if let Some(e) = event("status", &update) {
            self.pages.broadcast(&e);
            self.pages.updates.fetch_add(1, Ordering::Relaxed);
        }
    }

    /// A new executing program: ask the channel for its text once, and send its listing.
    fn follow_program(&mut self, ch: u16, i: usize, s: &Status) {
        let prog: Option<Arc<str>> = s
            .active_block
            .as_ref()
            .map(|b| Arc::clone(&b.prog))
            .or_else(|| s.program.as_deref().map(Arc::from));
        let seen = &mut self.seen[i];
        if prog.is_none() || seen.asked == prog {
            return;
        }
        seen.asked.clone_from(&prog);
        let Some(prog) = prog else { return };
        let text = match self.backend.call(ch, Op::ProgramText(Arc::clone(&prog))) {
            Ok(Reply::ProgramText(t)) => t,
            _ => None,
        };
        let view = match text {
            Some(t) => {
                let l = Listing::new(prog, t);
                let v = l.view(ch);
                seen.listing = Some(l);
                v
            }
            // The stream (or a program already done): no text to list.
            None => {
                seen.listing = None;
                ListingView {
                    ch,
                    program: Some(prog.to_string()),
                    lines: Vec::new(),
                    lines_left_out: 0,
                }
            }
        };
        if let Some(e) = event("listing", &view) {
            self.pages.set_listing(i, Arc::clone(&e));
            self.pages.broadcast(&e);
        }
    }

    /// New errors since the last poll: fetch their records (the newest few) and send them.
    fn follow_errors(&mut self, ch: u16, i: usize, s: &Status) {
        let total = s.errors_total;
        let seen = &mut self.seen[i];
        if total <= seen.errors {
            return;
        }
        let first = seen.errors.max(total.saturating_sub(ERRORS_PER_POLL));
        seen.errors = total;
        for index in first..total {
            let Ok(r) = self.backend.error_record(ch, index) else {
                continue;
            };
            let Some((code, text)) = r.error else {
                continue;
            };
            let view = ChannelError {
                ch,
                error: ErrorView { index, code, text },
            };
            if let Some(e) = event("nc-error", &view) {
                self.pages.push_error(i, Arc::clone(&e));
                self.pages.broadcast(&e);
            }
        }
    }
}

/// The `nc-error` event: one error a channel raised (not `error`, which EventSource uses
/// for its own connection errors).
#[derive(Serialize)]
struct ChannelError {
    ch: u16,
    #[serde(flatten)]
    error: ErrorView,
}

/// The running feed thread.
pub struct Feed {
    pub pages: Arc<Pages>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Feed {
    /// Start polling `backend`; `live` adds the runtime's lateness and overruns.
    pub fn start(backend: Backend, live: Option<Arc<LiveCycleStats>>) -> std::io::Result<Feed> {
        let pages = Arc::new(Pages::default());
        let stop = Arc::new(AtomicBool::new(false));
        let mut poller = Poller {
            backend,
            live,
            pages: Arc::clone(&pages),
            seen: Vec::new(),
            seq: 0,
        };
        let thread_stop = Arc::clone(&stop);
        let thread = std::thread::Builder::new()
            .name("http-feed".into())
            .spawn(move || {
                // Absolute deadlines: the rate stays FEED_PERIOD however long a poll takes.
                let mut next = Instant::now();
                while !thread_stop.load(Ordering::Acquire) {
                    // No page, no polls: an idle view costs the runtime nothing.
                    if poller.pages.connected() > 0 {
                        poller.poll();
                    }
                    next += FEED_PERIOD;
                    let now = Instant::now();
                    match next.checked_duration_since(now) {
                        Some(wait) => std::thread::sleep(wait),
                        None => next = now,
                    }
                }
            })?;
        Ok(Feed {
            pages,
            stop,
            thread: Some(thread),
        })
    }

    /// Stop polling and end every page's stream.
    pub fn stop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        self.pages.close_all();
    }
}

impl Drop for Feed {
    fn drop(&mut self) {
        self.stop();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(i: usize) -> Event {
        Arc::from(format!("event: status\ndata: {i}\n\n"))
    }

    #[test]
    fn a_page_that_stops_reading_is_dropped_not_buffered() {
        let pages = Pages::default();
        let slow = pages.subscribe();
        let quick = pages.subscribe();
        for i in 0..=PAGE_QUEUE_UPDATES {
            pages.broadcast(&ev(i));
            // The quick page keeps up.
            assert_eq!(quick.try_recv().ok(), Some(ev(i)));
        }
        assert_eq!(pages.connected(), 1);
        assert_eq!(pages.dropped.load(Ordering::Relaxed), 1);
        // The slow page gets what was queued, then its stream ends.
        assert_eq!(slow.try_iter().count(), PAGE_QUEUE_UPDATES);
        assert!(slow.recv().is_err());
    }

    #[test]
    fn a_new_page_hears_the_listing_and_the_recent_errors_only() {
        let pages = Pages::default();
        pages.set_listing(0, ev(1000));
        for i in 0..KEPT_ERRORS + 5 {
            pages.push_error(0, ev(i));
        }
        let page = pages.subscribe();
        let got: Vec<Event> = page.try_iter().collect();
        assert_eq!(got.len(), 1 + KEPT_ERRORS);
        assert_eq!(got[0], ev(1000));
        assert_eq!(got[1], ev(5));
    }
}
