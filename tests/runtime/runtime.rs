//! The fixed-cycle runtime: tick numbering and channel time, request service from other
//! threads, bounds, stopping, and a brief real-time run with sane statistics.

use std::sync::{Arc, Mutex};
use std::thread;
use std::time::Duration;

use crossbeam_channel::Sender;
use ncchannel::runtime::{
    bare_loop, Clock, Cycle, Flow, RunEnd, Runtime, Tick, MAX_REQUESTS_PER_TICK,
};

const MS: Duration = Duration::from_millis(1);

/// What the test cycle saw, in order.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Seen {
    Serve { id: u64, tick: u64 },
    Step { tick: u64, time: Duration },
}

/// A request: an id and where to send the number of the tick that served it.
struct Ping {
    id: u64,
    reply: Sender<u64>,
}

struct Recorder {
    seen: Arc<Mutex<Vec<Seen>>>,
    stop_at: Option<u64>,
}

impl Recorder {
    fn new(stop_at: Option<u64>) -> (Self, Arc<Mutex<Vec<Seen>>>) {
        let seen = Arc::new(Mutex::new(Vec::new()));
        (
            Recorder {
                seen: Arc::clone(&seen),
                stop_at,
            },
            seen,
        )
    }
}

impl Cycle for Recorder {
    type Request = Ping;

    fn serve(&mut self, req: Ping, tick: &Tick) {
        self.seen.lock().unwrap().push(Seen::Serve {
            id: req.id,
            tick: tick.index,
        });
        let _ = req.reply.send(tick.index);
    }

    fn step(&mut self, tick: &Tick) -> Flow {
        self.seen.lock().unwrap().push(Seen::Step {
            tick: tick.index,
            time: tick.time,
        });
        if Some(tick.index) == self.stop_at {
            Flow::Stop
        } else {
            Flow::Continue
        }
    }
}

fn steps(seen: &[Seen]) -> Vec<(u64, Duration)> {
    seen.iter()
        .filter_map(|s| match s {
            Seen::Step { tick, time } => Some((*tick, *time)),
            _ => None,
        })
        .collect()
}

#[test]
fn virtual_time_counts_ticks_and_time_exactly() {
    let (cycle, seen) = Recorder::new(None);
    let (mut rt, _tx) = Runtime::new(cycle, MS, Clock::Virtual);
    let s = rt.run(Some(1000));
    assert_eq!(s.end, RunEnd::MaxTicks);
    assert_eq!(s.ticks, 1000);
    assert_eq!(s.time, Duration::from_secs(1));
    let st = steps(&seen.lock().unwrap());
    assert_eq!(st.len(), 1000);
    for (i, (tick, time)) in st.iter().enumerate() {
        assert_eq!(*tick, i as u64);
        assert_eq!(*time, MS * i as u32);
    }
    // Virtual time measures work but has no lateness.
    assert_eq!(rt.stats().work.count(), 1000);
    assert_eq!(rt.stats().lateness.count(), 0);
    assert_eq!(rt.stats().overruns, 0);
}

#[test]
fn runs_continue_numbering_and_max_ticks_bounds_each_call() {
    let (cycle, seen) = Recorder::new(None);
    let (mut rt, _tx) = Runtime::new(cycle, Duration::from_micros(250), Clock::Virtual);
    assert_eq!(rt.run(Some(5)).ticks, 5);
    let s = rt.run(Some(3));
    assert_eq!((s.end, s.ticks), (RunEnd::MaxTicks, 3));
    assert_eq!(s.time, Duration::from_micros(2000));
    assert_eq!(rt.ticks(), 8);
    let st: Vec<u64> = steps(&seen.lock().unwrap()).iter().map(|s| s.0).collect();
    assert_eq!(st, (0..8).collect::<Vec<_>>());
    assert_eq!(rt.run(Some(0)).ticks, 0);
}

#[test]
fn the_cycle_can_stop_the_run() {
    let (cycle, _) = Recorder::new(Some(41));
    let (mut rt, _tx) = Runtime::new(cycle, MS, Clock::Virtual);
    let s = rt.run(Some(1000));
    assert_eq!((s.end, s.ticks), (RunEnd::Stopped, 42));
    assert_eq!(s.time, MS * 42);
}

#[test]
fn requests_from_another_thread_are_answered_in_the_tick_that_serves_them() {
    let (cycle, seen) = Recorder::new(None);
    let (mut rt, tx) = Runtime::new(cycle, MS, Clock::Virtual);
    let stop = rt.stop_handle();
    // The runtime runs on its own thread (Runtime is Send).
    let runner = thread::spawn(move || {
        let s = rt.run(None);
        (s, rt)
    });
    let client = thread::spawn(move || {
        let mut answers = Vec::new();
        for id in 0..50 {
            let (rtx, rrx) = crossbeam_channel::bounded(1);
            tx.send(Ping { id, reply: rtx }).unwrap();
            answers.push((id, rrx.recv().unwrap()));
        }
        answers
    });
    let answers = client.join().unwrap();
    stop.stop();
    let (summary, rt) = runner.join().unwrap();
    assert_eq!(summary.end, RunEnd::StopRequested);
    assert_eq!(summary.requests, 50);
    assert_eq!(rt.ticks(), summary.ticks);
    let seen = seen.lock().unwrap();
    for (id, tick) in answers {
        // Served exactly once, in the tick its answer names, before that tick's step.
        let pos = seen
            .iter()
            .position(|s| *s == Seen::Serve { id, tick })
            .expect("served in the answered tick");
        let step = seen
            .iter()
            .position(|s| matches!(s, Seen::Step { tick: t, .. } if *t == tick))
            .expect("that tick stepped");
        assert!(pos < step);
    }
}

#[test]
fn a_flood_of_requests_is_served_at_most_the_bound_per_tick() {
    let (cycle, seen) = Recorder::new(None);
    let (mut rt, tx) = Runtime::new(cycle, MS, Clock::Virtual);
    let (rtx, rrx) = crossbeam_channel::unbounded();
    let total = 3 * MAX_REQUESTS_PER_TICK + 8;
    for id in 0..total as u64 {
        tx.send(Ping {
            id,
            reply: rtx.clone(),
        })
        .unwrap();
    }
    let s = rt.run(Some(6));
    assert_eq!(s.requests, total as u64);
    let ticks: Vec<u64> = rrx.try_iter().collect();
    let per_tick: Vec<usize> = (0..6)
        .map(|t| ticks.iter().filter(|&&x| x == t).count())
        .collect();
    let b = MAX_REQUESTS_PER_TICK;
    assert_eq!(per_tick, vec![b, b, b, 8, 0, 0]);
    // Served in the order sent.
    let ids: Vec<u64> = seen
        .lock()
        .unwrap()
        .iter()
        .filter_map(|s| match s {
            Seen::Serve { id, .. } => Some(*id),
            _ => None,
        })
        .collect();
    assert_eq!(ids, (0..total as u64).collect::<Vec<_>>());
}

#[test]
fn stop_handle_stops_a_free_running_runtime() {
    let (cycle, _) = Recorder::new(None);
    let (mut rt, _tx) = Runtime::new(cycle, MS, Clock::Virtual);
    let stop = rt.stop_handle();
    let runner = thread::spawn(move || rt.run(None));
    thread::sleep(Duration::from_millis(20));
    stop.stop();
    let s = runner.join().unwrap();
    assert_eq!(s.end, RunEnd::StopRequested);
    assert!(s.ticks > 0);
    assert!(!stop.is_stopped(), "the stop request is consumed");
}

#[test]
fn real_time_runs_on_absolute_deadlines_with_sane_statistics() {
    let (cycle, _) = Recorder::new(None);
    let (mut rt, _tx) = Runtime::new(cycle, MS, Clock::RealTime);
    let s = rt.run(Some(300));
    assert_eq!(s.ticks, 300);
    assert_eq!(s.time, MS * 300);
    // Tick 299 cannot start before its deadline 299 ms after the start.
    assert!(s.wall >= MS * 299, "{:?}", s.wall);
    assert!(s.wall < Duration::from_secs(30), "{:?}", s.wall);
    let st = rt.stats();
    assert_eq!(st.work.count(), 300);
    assert_eq!(st.lateness.count(), 300);
    assert!(st.lateness.quantile_ns(0.5) < 50_000_000);
    assert!(st.work.max_ns() > 0);
    assert!(st.overruns <= 300);
}

#[test]
fn bare_loop_waits_for_every_deadline() {
    let t0 = std::time::Instant::now();
    let h = bare_loop(MS, 100);
    assert!(t0.elapsed() >= MS * 99);
    assert_eq!(h.count(), 100);
    assert!(h.quantile_ns(0.5) <= h.quantile_ns(0.99));
    assert!(h.quantile_ns(0.99) <= h.max_ns());
}

/// A real-time run cut into chunks keeps one schedule (a soak in chunks gains no ticks); a
/// caller that spends the time between chunks elsewhere (the bench's bare-loop slices)
/// restarts it, or every tick of the next chunk counts the pause as lateness.
#[test]
fn a_restarted_schedule_does_not_count_the_pause_between_runs_as_lateness() {
    for restart in [false, true] {
        let (cycle, _) = Recorder::new(None);
        let (mut rt, _tx) = Runtime::new(cycle, MS, Clock::RealTime);
        rt.run(Some(10));
        assert!(rt.continues_schedule());
        thread::sleep(Duration::from_millis(200));
        if restart {
            rt.restart_schedule();
        }
        rt.run(Some(30));
        let p50_ms = rt.stats().lateness.quantile_ns(0.5) as f64 / 1e6;
        if restart {
            assert!(p50_ms < 50.0, "restarted: p50 lateness {p50_ms} ms");
        } else {
            assert!(p50_ms >= 150.0, "continued: p50 lateness {p50_ms} ms");
        }
    }
}
