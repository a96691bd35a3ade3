//! Virtual time's work clock: one read per tick, at the tick's end, which is also the next
//! tick's start (ticks run back to back).
//!
//! Why not `Instant::now` throughout: the OS clock's read (the vDSO's `clock_gettime`) cost
//! about 46 ns on a KVM guest with clocksource `tsc`, against about 20 ns for the time stamp
//! counter read directly and converted (`quanta::Clock::raw` and `delta`): a tenth of a
//! soak's tick against a twentieth (measured on an AMD EPYC guest, where perf put the OS
//! clock's read at 7-8 % of a soak's wall time). But quanta calibrates the counter against the
//! OS clock before its first read, spinning until the two agree: 0.6 to 2 ms, and up to
//! 200 ms by its own bound on a noisy machine. A short run (every `ncchannel run` of a small
//! program, most tests) would pay that for nothing. So a run reads the OS clock for its first
//! [`CALIBRATE_AFTER`] ticks, then has a thread of its own calibrate the counter (once per
//! process) and goes over to it once the calibration is there.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// Ticks a run reads the OS clock before it asks for the calibrated counter: about 30 ms of
/// a soak's wall time, far past any short run.
const CALIBRATE_AFTER: u64 = 1 << 16;

/// How often, in ticks, a run still on the OS clock looks whether the calibration is done.
const LOOK_EVERY: u64 = 1 << 10;

/// The calibrated counter, once a thread made it.
static COUNTER: OnceLock<quanta::Clock> = OnceLock::new();

/// A calibration thread was started (one per process).
static CALIBRATING: AtomicBool = AtomicBool::new(false);

/// Where the last lap ended.
enum Mark {
    Os(Instant),
    Counter(quanta::Clock, u64),
}

/// The laps of one run: each the time since the last one ended.
pub(crate) struct Stopwatch {
    mark: Mark,
    laps: u64,
}

impl Stopwatch {
    /// A stopwatch started now: on the counter where a calibration was already made.
    pub(crate) fn start() -> Self {
        let mut sw = Stopwatch {
            mark: Mark::Os(Instant::now()),
            laps: 0,
        };
        sw.restart();
        sw
    }

    /// Start the next lap now (a run that goes on after a pause: a soak runs in chunks),
    /// keeping the count of laps, so the calibration is asked for once the laps of all the
    /// chunks together pass [`CALIBRATE_AFTER`].
    pub(crate) fn restart(&mut self) {
        self.mark = match COUNTER.get() {
            Some(c) => Mark::Counter(c.clone(), c.raw()),
            None => Mark::Os(Instant::now()),
        };
    }

    /// The time since the last lap (or the start), and a new lap from now.
    #[inline]
    pub(crate) fn lap(&mut self) -> Duration {
        match &mut self.mark {
            Mark::Counter(c, last) => {
                let now = c.raw();
                let d = c.delta(*last, now);
                *last = now;
                d
            }
            Mark::Os(last) => {
                let now = Instant::now();
                let d = now.saturating_duration_since(*last);
                *last = now;
                self.laps += 1;
                if self.laps.is_multiple_of(LOOK_EVERY) {
                    self.look_for_counter();
                }
                d
            }
        }
    }

    /// Past [`CALIBRATE_AFTER`] laps: start the calibration (once per process), and go over
    /// to the counter once it is there.
    #[cold]
    fn look_for_counter(&mut self) {
        if self.laps < CALIBRATE_AFTER {
            return;
        }
        if let Some(c) = COUNTER.get() {
            self.mark = Mark::Counter(c.clone(), c.raw());
            return;
        }
        if !CALIBRATING.swap(true, Ordering::AcqRel) {
            // A thread that fails to start leaves the run on the OS clock, as it began.
            let _ = std::thread::Builder::new()
                .name("tsc-calibration".into())
                .spawn(|| COUNTER.get_or_init(quanta::Clock::new));
        }
    }

    /// The run reads the calibrated counter now.
    #[cfg(test)]
    fn on_counter(&self) -> bool {
        matches!(self.mark, Mark::Counter(..))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_restart_keeps_the_count_of_laps() {
        let mut sw = Stopwatch::start();
        sw.laps = CALIBRATE_AFTER - 1;
        sw.restart();
        assert_eq!(sw.laps, CALIBRATE_AFTER - 1);
    }

    #[test]
    fn a_long_run_goes_over_to_the_counter_and_its_laps_add_up_to_the_wall_time() {
        // The wall clock starts first, so every lap lies inside it.
        let wall = Instant::now();
        let mut sw = Stopwatch::start();
        let mut laps = 0u64;
        let mut total = Duration::ZERO;
        // The calibration runs on its own thread: the run looks every LOOK_EVERY laps.
        while !sw.on_counter() {
            total += sw.lap();
            laps += 1;
            assert!(
                laps < CALIBRATE_AFTER + 50_000_000,
                "the calibrated counter never came"
            );
        }
        let on_counter_from = Instant::now();
        let mut counted = Duration::ZERO;
        while on_counter_from.elapsed() < Duration::from_millis(20) {
            counted += sw.lap();
        }
        counted += sw.lap();
        let wall_on_counter = on_counter_from.elapsed();
        // The counter's laps measure the same wall time as the OS clock, within 10 %.
        let ratio = counted.as_secs_f64() / wall_on_counter.as_secs_f64();
        assert!((0.9..1.1).contains(&ratio), "counter laps / wall = {ratio}");
        assert!(total <= wall.elapsed());
        // A later run starts on the counter at once, and a restarted one stays on it.
        assert!(Stopwatch::start().on_counter());
        sw.restart();
        assert!(sw.on_counter());
    }
}
