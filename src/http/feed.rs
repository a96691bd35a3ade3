//! The feed: one thread that polls every channel through the door at [`FEED_PERIOD`] and hands
//! each update, as a ready Server-Sent Event, to every connected page's bounded queue.
//!
//! A poll is one `Status` and one `DrainLive` request per channel, served by the runtime
//! between ticks like any ADS read, made whether or not a page is connected (the drain keeps
//! the channel's path since its program started for a page that connects late, and the
//! latest update answers `GET /snapshot.json`); the program text for the listing is
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

use super::path::{PathStore, StreamLines};
use super::snapshot::{
    channel_view, cycle_view, ErrorView, Listing, ListingView, Recorded, Update, WindowView,
};
use super::{Backend, FEED_PERIOD, PAGE_QUEUE_UPDATES};
use crate::machine::live::LiveDrain;
use crate::machine::{Op, Reply, Status};
use crate::vocab::stats::{LiveCycleStats, WORK_BUCKETS};

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
    /// Each channel's path since its program started, sent whole to a new page.
    paths: Vec<PathStore>,
    /// Each channel's latest stream lines.
    streams: Vec<Option<Event>>,
    /// The latest update as JSON (`GET /snapshot.json`).
    snapshot: Option<Arc<str>>,
    /// What `serve --soak --http` last published of the soak (counters and invariants).
    soak: Option<serde_json::Value>,
}

impl Pages {
    /// A new page's queue, primed with the listings, the paths since the programs started,
    /// the stream lines and the recent errors.
    pub fn subscribe(&self) -> Receiver<Event> {
        let greeting = lock(&self.greeting);
        let paths: Vec<Event> = greeting
            .paths
            .iter()
            .enumerate()
            .filter_map(|(i, p)| event("path", &p.whole(channel_number(i))))
            .collect();
        let primed = greeting.listings.iter().flatten().count()
            + greeting.errors.iter().map(VecDeque::len).sum::<usize>()
            + greeting.streams.iter().flatten().count()
            + paths.len();
        let (tx, rx) = crossbeam_channel::bounded(PAGE_QUEUE_UPDATES + primed);
        for e in greeting
            .listings
            .iter()
            .flatten()
            .chain(greeting.streams.iter().flatten())
            .chain(&paths)
            .chain(greeting.errors.iter().flatten())
        {
            let _ = tx.try_send(Arc::clone(e));
        }
        lock(&self.queues).push(tx);
        rx
    }

    /// The soak's counters and invariants for the next updates (`serve --soak --http`).
    pub fn publish_soak(&self, soak: serde_json::Value) {
        lock(&self.greeting).soak = Some(soak);
    }

    /// The latest update as JSON, once the feed has polled.
    pub fn snapshot(&self) -> Option<Arc<str>> {
        lock(&self.greeting).snapshot.clone()
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

    fn set_stream(&self, index: usize, e: Event) {
        let mut g = lock(&self.greeting);
        if g.streams.len() <= index {
            g.streams.resize(index + 1, None);
        }
        g.streams[index] = Some(e);
    }

    /// Add a drain to channel `index`'s path; the `path` event of what is new, if anything.
    fn extend_path(&self, index: usize, drain: &mut LiveDrain) -> Option<Event> {
        let mut g = lock(&self.greeting);
        if g.paths.len() <= index {
            g.paths.resize_with(index + 1, PathStore::default);
        }
        let update = g.paths[index].extend(channel_number(index), drain)?;
        event("path", &update)
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

/// The 1-based channel number of feed index `i`.
fn channel_number(i: usize) -> u16 {
    u16::try_from(i + 1).unwrap_or(u16::MAX)
}

/// What the feed remembers of one channel between polls.
#[derive(Default)]
struct Seen {
    /// The program whose text was asked for last, and the text if the channel had it.
    asked: Option<Arc<str>>,
    listing: Option<Listing>,
    /// Error records fetched so far.
    errors: u64,
    /// Ticks of the present program's start and stop, from the channel's live record.
    started_tick: Option<u64>,
    stopped_tick: Option<u64>,
    executed: crate::machine::live::Executed,
}

/// Seconds of cycle history the window statistics cover.
pub const CYCLE_WINDOW_S: usize = 10;

/// One reading of the runtime's work histogram, kept a second for the window.
struct CycleReading {
    buckets: [u64; WORK_BUCKETS],
    overruns: u64,
    ticks: u64,
}

/// The polling thread's state.
struct Poller {
    backend: Backend,
    live: Option<Arc<LiveCycleStats>>,
    pages: Arc<Pages>,
    seen: Vec<Seen>,
    seq: u64,
    /// One reading a second, the last [`CYCLE_WINDOW_S`] + 1.
    cycle_history: VecDeque<CycleReading>,
    /// The p99 of each past second's work, µs, oldest first (the page's trend).
    p99_trend: VecDeque<f64>,
}

/// Seconds of p99 trend the page draws.
const TREND_S: usize = 60;

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
            self.follow_record(ch, i);
            cycle.get_or_insert_with(|| cycle_view(&s, self.live.as_ref().map(|l| l.read())));
            let times = self.times(i, &s);
            channels.push(channel_view(ch, &s, self.seen[i].listing.as_ref(), times));
        }
        self.seq += 1;
        let window = self.cycle_window();
        let soak = lock(&self.pages.greeting).soak.clone();
        let update = Update {
            seq: self.seq,
            cycle,
            window,
            channels,
            soak,
        };
        if let Ok(json) = serde_json::to_string(&update) {
            lock(&self.pages.greeting).snapshot = Some(Arc::from(json.as_str()));
            if self.pages.connected() > 0 {
                self.pages
                    .broadcast(&Arc::from(format!("event: status\ndata: {json}\n\n")));
                self.pages.updates.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    /// The cycle statistics of the last [`CYCLE_WINDOW_S`] seconds, from the runtime's live
    /// work histogram (read once a second).
    fn cycle_window(&mut self) -> Option<WindowView> {
        let live = self.live.as_ref()?;
        let per_s = (1.0 / FEED_PERIOD.as_secs_f64()).round() as u64;
        if self.cycle_history.is_empty() || self.seq.is_multiple_of(per_s.max(1)) {
            let r = live.read();
            let reading = CycleReading {
                buckets: live.work_buckets(),
                overruns: r.overruns,
                ticks: r.ticks,
            };
            if let Some(prev) = self.cycle_history.back() {
                let second: Vec<u64> = reading
                    .buckets
                    .iter()
                    .zip(prev.buckets)
                    .map(|(a, b)| a.saturating_sub(b))
                    .collect();
                if self.p99_trend.len() == TREND_S {
                    self.p99_trend.pop_front();
                }
                self.p99_trend
                    .push_back(crate::vocab::stats::work_quantile_us(&second, 0.99));
            }
            if self.cycle_history.len() > CYCLE_WINDOW_S {
                self.cycle_history.pop_front();
            }
            self.cycle_history.push_back(reading);
        }
        let (first, last) = (self.cycle_history.front()?, self.cycle_history.back()?);
        let counts: Vec<u64> = last
            .buckets
            .iter()
            .zip(first.buckets)
            .map(|(a, b)| a.saturating_sub(b))
            .collect();
        Some(WindowView::new(
            &counts,
            self.cycle_history.len().saturating_sub(1),
            last.ticks.saturating_sub(first.ticks),
            last.overruns.saturating_sub(first.overruns),
            self.p99_trend.iter().copied().collect(),
        ))
    }

    /// Elapsed and estimated remaining time of channel `i`'s program.
    fn times(&self, i: usize, s: &Status) -> Recorded {
        let seen = &self.seen[i];
        let Some(start) = seen.started_tick else {
            return Recorded {
                executed: seen.executed,
                ..Recorded::default()
            };
        };
        let end = seen.stopped_tick.unwrap_or(s.tick).max(start);
        let elapsed_s = (end - start) as f64 * s.period.as_secs_f64();
        let share = match (&s.active_block, &seen.listing) {
            (Some(b), Some(l)) if *b.prog == *l.program && seen.stopped_tick.is_none() => {
                Some(l.share_before(b.offset))
            }
            _ => None,
        };
        let remaining_s = match share {
            _ if seen.stopped_tick.is_some() => Some(0.0),
            Some(f) if f > 0.01 => Some(elapsed_s * (1.0 - f) / f),
            _ => None,
        };
        Recorded {
            elapsed_s: Some(elapsed_s),
            remaining_s,
            executed: seen.executed,
        }
    }

    /// Drain channel `ch`'s live record: new path points and stream lines to the pages.
    fn follow_record(&mut self, ch: u16, i: usize) {
        let Ok(Reply::Live(mut drain)) = self.backend.call(ch, Op::DrainLive) else {
            return;
        };
        let seen = &mut self.seen[i];
        seen.started_tick = drain.started_tick;
        seen.stopped_tick = drain.stopped_tick;
        seen.executed = drain.executed;
        if let Some(text) = drain.stream.take() {
            let lines = StreamLines::new(ch, &text);
            if let Some(e) = event("stream", &lines) {
                self.pages.set_stream(i, Arc::clone(&e));
                self.pages.broadcast(&e);
            }
        }
        if let Some(e) = self.pages.extend_path(i, &mut drain) {
            self.pages.broadcast(&e);
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
                error: ErrorView {
                    index,
                    code,
                    text,
                    program: None,
                    line: None,
                },
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
            cycle_history: VecDeque::new(),
            p99_trend: VecDeque::new(),
        };
        let thread_stop = Arc::clone(&stop);
        let thread = std::thread::Builder::new()
            .name("http-feed".into())
            .spawn(move || {
                // Absolute deadlines: the rate stays FEED_PERIOD however long a poll takes.
                let mut next = Instant::now();
                while !thread_stop.load(Ordering::Acquire) {
                    // Polled with no page too: the channels' live records are drained, so a
                    // page that connects late gets the path since the program started.
                    poller.poll();
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
