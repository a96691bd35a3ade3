//! The fixed-cycle loop: one thread running ticks of a [`Cycle`] at a fixed period, in real
//! time (absolute deadlines with spin_sleep) or in virtual time (back to back), serving
//! requests from any thread at the start of each tick, and keeping cycle statistics.
//!
//! The runtime knows nothing of NC: it ticks whatever implements [`Cycle`] (the channels, or
//! the synthetic load of `ncchannel bench`).

pub mod realtime;
mod stopwatch;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, Sender, TryRecvError};

use crate::vocab::stats::{CycleStats, Histogram, LiveCycleStats};
pub use crate::vocab::tick::{Clock, Tick};

/// Requests served per tick at most. A flood of requests (say a client hammering the stream
/// object from many connections) then delays its own answers, never the tick: the rest wait
/// in the queue for the next tick. 64 per tick is 64 000 requests a second at 1 ms, far above
/// what ADS clients send to one controller.
pub const MAX_REQUESTS_PER_TICK: usize = 64;

/// Real time: no request is started closer than this to a tick's deadline. A request costs a
/// few microseconds; the margin keeps the tick's start on time.
pub(crate) const SERVE_MARGIN: Duration = Duration::from_micros(250);

/// Whether the runtime goes on after a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    Continue,
    Stop,
}

/// What the runtime ticks.
pub trait Cycle {
    /// A request from another thread (a stream write, a command). It carries its own reply
    /// sender, so the answer goes back in the tick that serves it.
    type Request: Send + 'static;

    /// Serve one request at the start of `tick`, before `step`.
    fn serve(&mut self, req: Self::Request, tick: &Tick);

    /// Do one tick's work.
    fn step(&mut self, tick: &Tick) -> Flow;

    /// The wall time the ticks since the last call stood still waiting for the program
    /// loader with the clock stopped (virtual time), and zero from now on. The runtime takes
    /// it after every tick: that wait is the simulated machine's file system, not the tick's
    /// work, and is reported apart. A cycle that reads no program files keeps the default.
    fn take_clock_stopped(&mut self) -> Duration {
        Duration::ZERO
    }

    /// The tick's work as the runtime measured it (the requests it served and `step`, without
    /// the clock-stopped wait), handed over after every tick. A cycle that shows its own
    /// cycle-time statistics (the machine's, read through the CNC's time objects) records it
    /// here instead of reading the clock a second time; the default ignores it.
    fn record_work(&mut self, _work: Duration) {}

    /// Whether other threads send this cycle requests. A cycle that takes none (the soak's
    /// `Infallible`) says so, and the runtime does not look at its empty queue every tick.
    const TAKES_REQUESTS: bool = true;
}

/// Why [`Runtime::run`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunEnd {
    /// The cycle's `step` answered [`Flow::Stop`].
    Stopped,
    /// `max_ticks` ticks ran.
    MaxTicks,
    /// A [`StopHandle`] asked it to stop.
    StopRequested,
}

/// The result of one [`Runtime::run`].
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub end: RunEnd,
    /// Ticks run by this call.
    pub ticks: u64,
    /// Channel time at the end of the run (all calls): `total ticks × period`.
    pub time: Duration,
    /// Wall-clock time this call took.
    pub wall: Duration,
    /// Requests served by this call.
    pub requests: u64,
}

/// Stops a running [`Runtime`] from another thread, at its next tick boundary.
#[derive(Debug, Clone)]
pub struct StopHandle(Arc<AtomicBool>);

impl StopHandle {
    pub fn stop(&self) {
        self.0.store(true, Ordering::Release);
    }

    pub fn is_stopped(&self) -> bool {
        self.0.load(Ordering::Acquire)
    }
}

/// The fixed-cycle loop over one [`Cycle`].
pub struct Runtime<C: Cycle> {
    cycle: C,
    requests: Receiver<C::Request>,
    period: Duration,
    clock: Clock,
    stop: Arc<AtomicBool>,
    /// A flag set from outside (SIGINT/SIGTERM): stops every run while it is set, unlike
    /// `stop`, which one run consumes.
    external_stop: Option<Arc<AtomicBool>>,
    /// Real time: the deadline of the next tick when the last run ended at `max_ticks`, so a
    /// run cut into chunks (soak, `serve --soak`) keeps one schedule and does not gain a tick
    /// per chunk.
    resume_at: Option<Instant>,
    next_index: u64,
    stats: CycleStats,
    /// Lateness and overruns for readers on other threads, once one asked for them.
    live: Option<Arc<LiveCycleStats>>,
    /// Virtual time's work clock, kept across runs (its laps decide when to calibrate).
    stopwatch: stopwatch::Stopwatch,
}

impl<C: Cycle> Runtime<C> {
    /// A runtime over `cycle` and the sender through which any thread may send it requests.
    /// The queue is unbounded: senders never block, and the per-tick bound
    /// [`MAX_REQUESTS_PER_TICK`] protects the tick.
    ///
    /// # Panics
    /// When `period` is zero (a configuration mistake caught by the caller's validation).
    pub fn new(cycle: C, period: Duration, clock: Clock) -> (Self, Sender<C::Request>) {
        assert!(!period.is_zero(), "runtime period must be positive");
        let (tx, rx) = crossbeam_channel::unbounded();
        let rt = Runtime {
            cycle,
            requests: rx,
            period,
            clock,
            stop: Arc::new(AtomicBool::new(false)),
            external_stop: None,
            resume_at: None,
            next_index: 0,
            stats: CycleStats::default(),
            live: None,
            stopwatch: stopwatch::Stopwatch::start(),
        };
        (rt, tx)
    }

    /// Lateness and overruns as they happen, for a reader on another thread (the live view).
    pub fn live_stats(&mut self) -> Arc<LiveCycleStats> {
        Arc::clone(self.live.get_or_insert_with(Arc::default))
    }

    /// A handle that stops the run from any thread.
    pub fn stop_handle(&self) -> StopHandle {
        StopHandle(Arc::clone(&self.stop))
    }

    /// Also stop, at a tick boundary, whenever `flag` is set (a signal handler's flag).
    pub(crate) fn stop_on(&mut self, flag: Arc<AtomicBool>) {
        self.external_stop = Some(flag);
    }

    pub fn period(&self) -> Duration {
        self.period
    }

    pub fn clock(&self) -> Clock {
        self.clock
    }

    /// Ticks run so far over all calls to `run`.
    pub fn ticks(&self) -> u64 {
        self.next_index
    }

    /// Channel time so far.
    pub fn time(&self) -> Duration {
        channel_time(self.period, self.next_index)
    }

    /// Statistics over all ticks run so far.
    pub fn stats(&self) -> &CycleStats {
        &self.stats
    }

    pub fn cycle(&self) -> &C {
        &self.cycle
    }

    pub fn cycle_mut(&mut self) -> &mut C {
        &mut self.cycle
    }

    /// The cycle and the statistics, when the run is over.
    /// The statistics so far, leaving empty ones: a caller measuring phases of one run (the
    /// live-view bench) takes each phase's figures at its end.
    pub fn take_stats(&mut self) -> CycleStats {
        std::mem::take(&mut self.stats)
    }

    pub fn into_inner(self) -> (C, CycleStats) {
        (self.cycle, self.stats)
    }

    /// The next real-time run starts a schedule of its own at its start, instead of going on
    /// where the last run left off: for a caller that spends the time between runs on other
    /// work (the bench's bare-loop slices), which would otherwise count as lateness.
    pub fn restart_schedule(&mut self) {
        self.resume_at = None;
    }

    /// Whether the next real-time run goes on with the last run's schedule.
    pub fn continues_schedule(&self) -> bool {
        self.resume_at.is_some()
    }

    /// Run ticks until the cycle stops, `max_ticks` ticks have run in this call, or a
    /// [`StopHandle`] fires. A stop request is consumed: a later `run` starts afresh. Tick
    /// numbers and channel time continue across calls.
    ///
    /// In real time, deadlines are absolute (`start + k × period`, `start` this call's start or, after a
    /// run that ended at `max_ticks`, the deadline where it left off), so
    /// sleeping never drifts; a late tick runs at once and the next deadlines stay where they
    /// were, so a hiccup is caught up by ticks running back to back, and channel time stays
    /// `index × period`.
    pub fn run(&mut self, max_ticks: Option<u64>) -> RunSummary {
        let wall_start = Instant::now();
        let base = self.resume_at.take().unwrap_or(wall_start);
        let first = self.next_index;
        let mut requests = 0u64;
        // Virtual time: ticks run back to back, so one clock read per tick is both the end
        // of one tick's work and the start of the next one's (the loop's own steps between
        // them count as work).
        self.stopwatch.restart();
        // Channel time advanced by one period a tick: `index × period` without a 128-bit
        // product every tick.
        let mut time = channel_time(self.period, self.next_index);
        let end = loop {
            let k = self.next_index - first;
            if max_ticks.is_some_and(|m| k >= m) {
                break RunEnd::MaxTicks;
            }
            // Looked at before it is consumed: a swap every tick is a locked instruction.
            if (self.stop.load(Ordering::Relaxed) && self.stop.swap(false, Ordering::AcqRel))
                || self
                    .external_stop
                    .as_ref()
                    .is_some_and(|f| f.load(Ordering::Acquire))
            {
                break RunEnd::StopRequested;
            }
            let tick = Tick {
                index: self.next_index,
                period: self.period,
                time,
                clock: self.clock,
            };
            let (started, late) = match self.clock {
                Clock::Virtual => (None, None),
                Clock::RealTime => {
                    let ideal = base + mul_duration(self.period, k);
                    requests += self.serve_until(ideal, &tick);
                    spin_sleep::sleep_until(ideal);
                    let now = Instant::now();
                    (Some(now), Some(now.saturating_duration_since(ideal)))
                }
            };
            if C::TAKES_REQUESTS {
                requests += self.serve_pending(&tick);
            }
            let flow = self.cycle.step(&tick);
            let stopped = self.cycle.take_clock_stopped();
            self.stats.clock_stopped += stopped;
            let elapsed = match started {
                Some(started) => started.elapsed(),
                None => self.stopwatch.lap(),
            };
            // Virtual time: a wait for the program loader stops the clock; it is the
            // simulated file system's time, counted apart, not the tick's work.
            let work = elapsed.saturating_sub(stopped);
            self.stats.work.record(work);
            self.cycle.record_work(work);
            let overrun = late.is_some_and(|late| late + work > self.period);
            if let Some(late) = late {
                self.stats.lateness.record(late);
                self.stats.overruns += u64::from(overrun);
            }
            if let Some(live) = &self.live {
                live.publish(work, late, overrun);
            }
            self.next_index += 1;
            time = time.saturating_add(self.period);
            if flow == Flow::Stop {
                break RunEnd::Stopped;
            }
        };
        if end == RunEnd::MaxTicks && self.clock == Clock::RealTime {
            self.resume_at = Some(base + mul_duration(self.period, self.next_index - first));
        }
        RunSummary {
            end,
            ticks: self.next_index - first,
            time: self.time(),
            wall: wall_start.elapsed(),
            requests,
        }
    }

    /// Serve up to [`MAX_REQUESTS_PER_TICK`] queued requests; returns how many.
    /// Real time: the wait for the next deadline is spent answering requests as they come,
    /// so a client's write round trip is microseconds, not up to a period (the real CNC's
    /// COM objects are written asynchronously to its cycle, too). Requests stop being taken
    /// `SERVE_MARGIN` before the deadline, so serving never makes a tick late; they are
    /// served with the coming tick's number and time.
    fn serve_until(&mut self, deadline: Instant, tick: &Tick) -> u64 {
        let mut n = 0;
        loop {
            let now = Instant::now();
            let Some(left) = deadline.checked_duration_since(now) else {
                break;
            };
            if left <= SERVE_MARGIN {
                break;
            }
            match self.requests.recv_timeout(left - SERVE_MARGIN) {
                Ok(req) => {
                    self.cycle.serve(req, tick);
                    n += 1;
                }
                Err(_) => break,
            }
        }
        n
    }

    fn serve_pending(&mut self, tick: &Tick) -> u64 {
        // Most ticks find the queue empty: a look at it costs about 40 instructions fewer
        // than a `try_recv` that finds nothing (callgrind, a soak tick of about 2,400).
        if self.requests.is_empty() {
            return 0;
        }
        let mut n = 0;
        while n < MAX_REQUESTS_PER_TICK {
            match self.requests.try_recv() {
                Ok(req) => {
                    self.cycle.serve(req, tick);
                    n += 1;
                }
                Err(TryRecvError::Empty | TryRecvError::Disconnected) => break,
            }
        }
        n as u64
    }
}

fn mul_duration(period: Duration, k: u64) -> Duration {
    // u32 multiplication would overflow after 4 billion ticks (50 days at 1 ms).
    let ns = period.as_nanos().saturating_mul(u128::from(k));
    Duration::from_nanos(u64::try_from(ns).unwrap_or(u64::MAX))
}

fn channel_time(period: Duration, index: u64) -> Duration {
    mul_duration(period, index)
}

/// The reference for lateness: a bare loop that only waits for `ticks` absolute deadlines
/// `period` apart with spin_sleep and records how late each wake-up was. Run it in the same
/// process as the runtime to compare like with like on a shared machine.
pub fn bare_loop(period: Duration, ticks: u64) -> Histogram {
    let mut h = Histogram::new();
    let start = Instant::now();
    for k in 0..ticks {
        let ideal = start + mul_duration(period, k);
        spin_sleep::sleep_until(ideal);
        h.record(Instant::now().saturating_duration_since(ideal));
    }
    h
}
