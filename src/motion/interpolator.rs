//! Interpolator: advances the path position of one block through a tick along a trapezoidal
//! velocity profile, and turns a path position into axis positions (lines, G2/G3 arcs in
//! G17/G18/G19, helices).
//!
//! The profile is integrated in closed form (phases of constant acceleration +a, 0, −a), not
//! by stepping the velocity per tick: a block that ends inside a tick hands the rest of the tick
//! to the next block, so block end times are exact and a square at F1000 reaches its corners
//! when the trapezoid says. Time is whatever the caller passes; no clock is read here.

use crate::queue::Move;
use crate::vocab::axis::{Position, MAX_AXES};

/// Below this a remaining length counts as the block end, mm.
pub(crate) const END_EPS_MM: f64 = 1e-9;
/// Velocities closer than this count as equal, mm/s.
const V_EPS: f64 = 1e-9;
/// Phases one block can pass through in one tick: accelerate, cruise, decelerate, plus slack
/// for rounding; the loop is bounded so no input can make a tick spin.
const MAX_PHASES: usize = 8;

/// What the profile of one block aims for this tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Profile {
    /// Block path length, mm.
    pub(crate) length_mm: f64,
    /// Path acceleration and deceleration limit, mm/s² (> 0).
    pub(crate) accel_mm_per_s2: f64,
    /// Velocity to cruise at (feed × override, or 0 during a feed hold), mm/s.
    pub(crate) cruise_mm_per_s: f64,
    /// Velocity planned at the block end, mm/s.
    pub(crate) exit_mm_per_s: f64,
}

/// Where the block stands after [`advance`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Advanced {
    /// Seconds of the offered time used.
    pub(crate) used_s: f64,
    /// The block end was reached.
    pub(crate) finished: bool,
}

/// The squared velocity braking at `a` from `v` over `rem` leaves, and the exit the block can
/// still reach: that velocity where it lies above the planned exit, else the exit.
///
/// Why the tolerance: v² − 2·a·rem cancels when braking exactly to the exit, and its rounding
/// (about 1e-16·v²) turns into a velocity of about 1e-8·v after the square root — enough for
/// a block "stopped" at its end to creep on (an M00 after it then saw a moving axis). A
/// squared difference within 1e-9·v² of the exit's counts as the exit.
fn reachable_exit(v: f64, a: f64, rem: f64, exit_mm_per_s: f64) -> (f64, f64) {
    let reach2 = v * v - 2.0 * a * rem;
    let exit2 = exit_mm_per_s * exit_mm_per_s;
    if reach2 > exit2 + REACH_EPS * v * v {
        (reach2, reach2.sqrt())
    } else {
        (reach2, exit_mm_per_s.max(0.0))
    }
}

/// Relative tolerance of a squared velocity (see [`reachable_exit`]).
const REACH_EPS: f64 = 1e-9;

/// How much of a phase one call took.
enum Took {
    /// All of it, and it reached the block end.
    Finished,
    /// All of it; the block goes on.
    Whole,
    /// The rest of the tick: the phase goes on in the next.
    TickOver,
}

/// Run one phase (acceleration mm/s², duration s, velocity at its end mm/s, whether it reaches
/// the block end) for at most `left` s, moving `s_mm` and `v_mm_per_s` with it.
fn take_phase(
    s_mm: &mut f64,
    v_mm_per_s: &mut f64,
    p: &Profile,
    (acc, dur, v_end, to_end): (f64, f64, f64, bool),
    left: f64,
) -> Took {
    let v = *v_mm_per_s;
    if dur <= left {
        if to_end {
            *s_mm = p.length_mm;
            *v_mm_per_s = v_end.max(0.0);
            return Took::Finished;
        }
        *s_mm = (*s_mm + (v + v_end) * 0.5 * dur).min(p.length_mm);
        *v_mm_per_s = v_end.max(0.0);
        Took::Whole
    } else {
        *s_mm = (*s_mm + v * left + 0.5 * acc * left * left).min(p.length_mm);
        *v_mm_per_s = (v + acc * left).max(0.0);
        Took::TickOver
    }
}

/// Advance path position `s_mm` and path velocity `v_mm_per_s` along `p` by at most `dt_s`.
///
/// The velocity follows the largest of: accelerate at `a` towards the cruise velocity, cruise,
/// and brake at `a` so the block ends at the planned exit velocity. When the velocity is
/// already too high to brake to the exit (the override was lowered after planning), it brakes
/// at `a` all the way and ends faster; the next block then brakes on.
pub(crate) fn advance(s_mm: &mut f64, v_mm_per_s: &mut f64, p: &Profile, dt_s: f64) -> Advanced {
    // The swing rule with no window is exactly this rule: braking and accelerating may follow
    // each other at once.
    advance_swing(s_mm, v_mm_per_s, p, dt_s, &mut Swing::new(0.0))
}

/// The swing rule of a straight rest-to-rest run: between a phase at +a and one at −a (either
/// order) the profile holds its velocity for at least `window_s`, the jerk window that follows.
///
/// Why. A moving average of length T over the positions makes the jerk (a(t) − a(t − T)) / T.
/// With the acceleration in {−a, 0, +a} and never +a and −a less than T apart, |a(t) − a(t − T)|
/// is at most a, so a window T = a / j bounds the jerk by j — half the window the general case
/// needs (2·a / j), and a trapezoid at a filtered by a / j is the time-optimal jerk-limited
/// profile (docs/motion.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Swing {
    /// Least time at constant velocity between accelerating and braking, s.
    pub(crate) window_s: f64,
    /// Seconds since the last accelerating phase ended (0 while in it).
    pub(crate) since_accel_s: f64,
    /// Seconds since the last braking phase ended (0 while in it).
    pub(crate) since_brake_s: f64,
}

impl Swing {
    /// A run that starts at rest: no phase before it.
    pub(crate) fn new(window_s: f64) -> Self {
        Swing {
            window_s: window_s.max(0.0),
            since_accel_s: f64::INFINITY,
            since_brake_s: f64::INFINITY,
        }
    }

    fn pass(&mut self, acc: f64, dur: f64) {
        if acc > 0.0 {
            self.since_accel_s = 0.0;
            self.since_brake_s += dur;
        } else if acc < 0.0 {
            self.since_brake_s = 0.0;
            self.since_accel_s += dur;
        } else {
            self.since_accel_s += dur;
            self.since_brake_s += dur;
        }
    }

    /// Seconds until braking is allowed (0: now).
    fn brake_wait_s(&self) -> f64 {
        self.wait_after(self.since_accel_s)
    }

    /// Seconds until accelerating is allowed (0: now).
    fn accel_wait_s(&self) -> f64 {
        self.wait_after(self.since_brake_s)
    }

    /// What is left of the window `since_s` after the opposite phase ended (0: none).
    fn wait_after(&self, since_s: f64) -> f64 {
        let w = self.window_s - since_s;
        if w > SWING_EPS_S {
            w
        } else {
            0.0
        }
    }
}

/// Waits shorter than this count as over, s (rounding of the phase sums).
const SWING_EPS_S: f64 = 1e-9;

/// The phase holding `v` for at most `wait` s: until the braking curve to `ve` at `a`, or to
/// the block end `rem` mm ahead when `v` is not above the exit.
fn hold_phase(v: f64, wait: f64, ve: f64, a: f64, rem: f64) -> (f64, f64, f64, bool) {
    let (d, to_end) = if v > ve {
        ((rem - (v * v - ve * ve) / (2.0 * a)).max(0.0), false)
    } else {
        (rem, true)
    };
    let dur = d / v;
    if dur <= wait {
        (0.0, dur, v, to_end)
    } else {
        (0.0, wait, v, false)
    }
}

/// [`advance`] under the swing rule: the same accelerate / cruise / brake phases, but braking
/// starts only `window_s` after accelerating ended and accelerating only `window_s` after
/// braking ended; meanwhile the velocity is held. To keep the end reachable, acceleration
/// stops at the highest velocity from which holding it for `window_s` and then braking still
/// meets the exit at the block end. A feed hold or a lowered override therefore brakes up to
/// `window_s` later than in [`advance`], as a jerk-limited machine does.
pub(crate) fn advance_swing(
    s_mm: &mut f64,
    v_mm_per_s: &mut f64,
    p: &Profile,
    dt_s: f64,
    sw: &mut Swing,
) -> Advanced {
    let a = p.accel_mm_per_s2.max(1e-9);
    let win = sw.window_s;
    let mut t = 0.0;
    for _ in 0..MAX_PHASES {
        let rem = p.length_mm - *s_mm;
        if rem <= END_EPS_MM {
            *s_mm = p.length_mm;
            return Advanced {
                used_s: t,
                finished: true,
            };
        }
        let left = dt_s - t;
        if left <= 0.0 {
            break;
        }
        let v = *v_mm_per_s;
        let (reach2, ve) = reachable_exit(v, a, rem, p.exit_mm_per_s);
        let brake = (ve * ve + 2.0 * a * rem).sqrt();
        let vc = p.cruise_mm_per_s.max(0.0);
        let eps = V_EPS * (1.0 + v.max(vc));
        let hold = |v: f64, wait: f64| hold_phase(v, wait, ve, a, rem);
        // (acceleration, duration of the phase, velocity at its end, reaches block end)
        let (acc, dur, v_end, to_end) = if v >= brake - eps {
            // On the braking curve: brake to the end. The cap below makes this come at least
            // `window_s` after accelerating ended; rounding aside, it is never early.
            (-a, ((v - ve) / a).max(0.0), ve, true)
        } else if v > vc + eps {
            let wait = sw.brake_wait_s();
            if wait > 0.0 {
                hold(v, wait)
            } else {
                let d = (v * v - vc * vc) / (2.0 * a);
                if d >= rem {
                    let ve2 = reach2.max(0.0).sqrt();
                    (-a, ((v - ve2) / a).max(0.0), ve2, true)
                } else {
                    (-a, (v - vc) / a, vc, false)
                }
            }
        } else if v >= vc - eps && vc <= V_EPS {
            // Held (or 0 % override) and standing: time passes, the path does not.
            *v_mm_per_s = 0.0;
            sw.pass(0.0, left);
            return Advanced {
                used_s: dt_s,
                finished: false,
            };
        } else {
            let wait = sw.accel_wait_s();
            // The highest velocity from which holding it for `win` and braking still meets the
            // exit: accelerate to u, hold u·win, brake — together at most `rem`.
            let c = rem + (v * v + ve * ve) / (2.0 * a);
            let cap = 0.5 * a * (-win + (win * win + 4.0 * c / a).sqrt());
            let target = vc.min(cap);
            if v < target - eps && wait <= 0.0 {
                let x = (target * target - v * v) / (2.0 * a);
                if x >= rem {
                    let v1 = (v * v + 2.0 * a * rem).sqrt();
                    (a, (v1 - v) / a, v1, true)
                } else {
                    (a, (target - v) / a, target, false)
                }
            } else if v <= V_EPS {
                // Standing, not yet allowed to accelerate: time passes.
                let w = wait.min(left);
                sw.pass(0.0, w);
                t += w;
                if wait <= left {
                    continue;
                }
                break;
            } else if v < target - eps {
                hold(v, wait)
            } else {
                // At the cap (or the cruise): hold until the braking curve.
                hold(v, f64::INFINITY)
            }
        };
        let took = take_phase(s_mm, v_mm_per_s, p, (acc, dur, v_end, to_end), left);
        sw.pass(acc, dur.min(left));
        match took {
            Took::Finished => {
                return Advanced {
                    used_s: t + dur,
                    finished: true,
                }
            }
            Took::Whole => t += dur,
            Took::TickOver => {
                t = dt_s;
                break;
            }
        }
    }
    let finished = p.length_mm - *s_mm <= END_EPS_MM;
    if finished {
        *s_mm = p.length_mm;
    }
    Advanced {
        used_s: t.min(dt_s),
        finished,
    }
}

/// Axis positions at path position `s_mm` of `m` (of length `length_mm`). The block end is
/// returned exactly at `s_mm >= length_mm`: corners and arc end points are hit, not neared.
pub(crate) fn point_at(m: &Move, length_mm: f64, s_mm: f64) -> Position {
    if s_mm >= length_mm || length_mm <= 0.0 {
        return m.end;
    }
    m.point_at(s_mm / length_mm)
}

/// Unit tangent of `m` at its start (`at_end` false) or end, by axis.
pub(crate) fn tangent(m: &Move, length_mm: f64, at_end: bool) -> [f64; MAX_AXES] {
    let mut t = [0.0; MAX_AXES];
    if length_mm <= 0.0 {
        return t;
    }
    for (i, ti) in t.iter_mut().enumerate() {
        *ti = (m.end[i] - m.start[i]) / length_mm;
    }
    if let Some(c) = m.arc() {
        let ang = c.angle_at(if at_end { 1.0 } else { 0.0 });
        // d(point)/d(u) of the circle part, divided by the path length.
        let k = c.dir * c.radius_mm * c.sweep_rad / length_mm;
        t[c.a] = -k * ang.sin();
        t[c.b] = k * ang.cos();
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::queue::{MoveKind, Plane};

    fn run(p: &Profile, v0: f64, dt: f64) -> (f64, Vec<(f64, f64)>) {
        let (mut s, mut v, mut t) = (0.0, v0, 0.0);
        let mut samples = Vec::new();
        for _ in 0..1_000_000 {
            let r = advance(&mut s, &mut v, p, dt);
            t += r.used_s;
            samples.push((s, v));
            if r.finished {
                return (t, samples);
            }
        }
        panic!("never finished");
    }

    #[test]
    fn trapezoid_takes_the_textbook_time() {
        // 10 mm, a = 1000, v = 50: ramps of 0.05 s covering 1.25 mm each, cruise 7.5 mm.
        let p = Profile {
            length_mm: 10.0,
            accel_mm_per_s2: 1000.0,
            cruise_mm_per_s: 50.0,
            exit_mm_per_s: 0.0,
        };
        let (t, samples) = run(&p, 0.0, 0.001);
        assert!((t - (0.1 + 7.5 / 50.0)).abs() < 1e-9, "{t}");
        assert_eq!(samples.last().unwrap(), &(10.0, 0.0));
        // Velocity changes at most a·dt per tick.
        let mut prev = 0.0;
        for (_, v) in samples {
            assert!((v - prev).abs() <= 1000.0 * 0.001 + 1e-9);
            prev = v;
        }
    }

    #[test]
    fn triangle_when_the_block_is_short() {
        let p = Profile {
            length_mm: 1.0,
            accel_mm_per_s2: 1000.0,
            cruise_mm_per_s: 500.0,
            exit_mm_per_s: 0.0,
        };
        let (t, _) = run(&p, 0.0, 0.0005);
        // Peak sqrt(a·L) = 31.62 mm/s; total 2·sqrt(L/a).
        assert!((t - 2.0 * (1.0f64 / 1000.0).sqrt()).abs() < 1e-9, "{t}");
    }

    #[test]
    fn hold_brakes_to_a_stop_and_stays() {
        let p = Profile {
            length_mm: 100.0,
            accel_mm_per_s2: 1000.0,
            cruise_mm_per_s: 0.0,
            exit_mm_per_s: 0.0,
        };
        let (mut s, mut v) = (0.0, 50.0);
        for _ in 0..100 {
            advance(&mut s, &mut v, &p, 0.001);
        }
        assert_eq!(v, 0.0);
        assert!((s - 50.0 * 50.0 / 2000.0).abs() < 1e-9, "{s}");
    }

    #[test]
    fn arc_tangents_are_unit_and_perpendicular_to_the_radius() {
        let m = Move {
            kind: MoveKind::Arc {
                plane: Plane::Xy,
                center: [0.0, 0.0],
                radius_mm: 10.0,
                cw: false,
                sweep_rad: std::f64::consts::FRAC_PI_2,
            },
            start: [10.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            end: [0.0, 10.0, 0.0, 0.0, 0.0, 0.0],
            feed_mm_per_min: 1000.0,
            path: Default::default(),
        };
        let l = m.length_mm();
        let t0 = tangent(&m, l, false);
        let t1 = tangent(&m, l, true);
        assert!((t0[0]).abs() < 1e-12 && (t0[1] - 1.0).abs() < 1e-12);
        assert!((t1[0] + 1.0).abs() < 1e-12 && t1[1].abs() < 1e-12);
        assert_eq!(point_at(&m, l, l), m.end);
    }
}
