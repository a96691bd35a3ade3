//! Limit check: per-axis velocity, acceleration and jerk from finite differences of the positions
//! recorded each tick, compared with the axis limits — what the motion tests run over a whole
//! program.
//!
//! v_k = (p_k − p_{k−1}) / dt is the mean velocity over a tick, so it can never exceed a limit the
//! motion kept; a_k = (v_k − v_{k−1}) / dt is a weighted mean of the acceleration over two ticks
//! plus the velocity jumps at corners the window covers.
//! j_k = (a_k − a_{k−1}) / dt likewise (only for axes with a jerk limit). All are checked
//! against limit × (1 + ε): without the axis filter ε covers the corner case the planner's
//! junction rule bounds only approximately (several corners inside one tick with unequal block
//! lengths); with it the bounds are exact and ε is rounding.

use ncchannel::vocab::axis::{Position, MAX_AXES};

use ncchannel::AxisLimits;

/// Tolerance for a trapezoid profile without the axis filter: 2 % (see the module header).
pub const DEFAULT_EPS: f64 = 0.02;
/// Tolerance with the axis filter on: its bounds are exact, this is rounding.
pub const FILTERED_EPS: f64 = 1e-6;

/// The worst tick seen for one axis and one quantity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Worst {
    /// |value| / limit.
    pub ratio: f64,
    /// Tick number (0 = first recorded position).
    pub tick: u64,
}

impl Worst {
    /// Keep `ratio` at `tick` when it is worse than what was seen.
    fn note(&mut self, ratio: f64, tick: u64) {
        if ratio > self.ratio {
            *self = Worst { ratio, tick };
        }
    }
}

/// Feed it every tick's position; ask for the worst ratios.
#[derive(Debug, Clone)]
pub struct LimitCheck {
    vmax_mm_per_s: [f64; MAX_AXES],
    amax_mm_per_s2: [f64; MAX_AXES],
    jmax_mm_per_s3: [f64; MAX_AXES],
    dt_s: f64,
    eps: f64,
    prev: Option<Position>,
    prev_v: Option<[f64; MAX_AXES]>,
    prev_a: Option<[f64; MAX_AXES]>,
    ticks: u64,
    pub worst_velocity: [Worst; MAX_AXES],
    pub worst_accel: [Worst; MAX_AXES],
    pub worst_jerk: [Worst; MAX_AXES],
}

impl LimitCheck {
    pub fn new(axes: &[AxisLimits], dt_s: f64, eps: f64) -> Self {
        let mut vmax = [f64::INFINITY; MAX_AXES];
        let mut amax = [f64::INFINITY; MAX_AXES];
        let mut jmax = [f64::INFINITY; MAX_AXES];
        for a in axes {
            if a.index < MAX_AXES {
                vmax[a.index] = a.max_velocity_mm_per_min / 60.0;
                amax[a.index] = a.max_accel_mm_per_s2;
                jmax[a.index] = a.max_jerk_mm_per_s3.unwrap_or(f64::INFINITY);
            }
        }
        let w = Worst {
            ratio: 0.0,
            tick: 0,
        };
        LimitCheck {
            vmax_mm_per_s: vmax,
            amax_mm_per_s2: amax,
            jmax_mm_per_s3: jmax,
            dt_s,
            eps,
            prev: None,
            prev_v: None,
            prev_a: None,
            ticks: 0,
            worst_velocity: [w; MAX_AXES],
            worst_accel: [w; MAX_AXES],
            worst_jerk: [w; MAX_AXES],
        }
    }

    /// The position after one more tick.
    pub fn record(&mut self, p: Position) {
        if let Some(q) = self.prev {
            let mut v = [0.0; MAX_AXES];
            for i in 0..MAX_AXES {
                v[i] = (p[i] - q[i]) / self.dt_s;
                self.worst_velocity[i].note(v[i].abs() / self.vmax_mm_per_s[i], self.ticks);
            }
            if let Some(u) = self.prev_v {
                let mut acc = [0.0; MAX_AXES];
                for i in 0..MAX_AXES {
                    acc[i] = (v[i] - u[i]) / self.dt_s;
                    self.worst_accel[i].note(acc[i].abs() / self.amax_mm_per_s2[i], self.ticks);
                }
                if let Some(b) = self.prev_a {
                    for i in 0..MAX_AXES {
                        let j = (acc[i] - b[i]) / self.dt_s;
                        self.worst_jerk[i].note(j.abs() / self.jmax_mm_per_s3[i], self.ticks);
                    }
                }
                self.prev_a = Some(acc);
            }
            self.prev_v = Some(v);
        }
        self.prev = Some(p);
        self.ticks += 1;
    }

    /// Forget the velocity history (after a deliberate instant stop such as a reset).
    pub fn restart(&mut self) {
        self.prev = None;
        self.prev_v = None;
        self.prev_a = None;
    }

    /// Every axis kept |v| ≤ vmax·(1+ε) and |a| ≤ amax·(1+ε); else a description of the worst.
    pub fn verdict(&self) -> Result<(), String> {
        let mut bad = Vec::new();
        for i in 0..MAX_AXES {
            let (wv, wa, wj) = (
                self.worst_velocity[i],
                self.worst_accel[i],
                self.worst_jerk[i],
            );
            let letter = ncchannel::vocab::axis::AXIS_LETTERS[i] as char;
            if wv.ratio > 1.0 + self.eps {
                bad.push(format!(
                    "{letter}: velocity {:.6} × limit at tick {}",
                    wv.ratio, wv.tick
                ));
            }
            if wa.ratio > 1.0 + self.eps {
                bad.push(format!(
                    "{letter}: acceleration {:.6} × limit at tick {}",
                    wa.ratio, wa.tick
                ));
            }
            if wj.ratio > 1.0 + self.eps {
                bad.push(format!(
                    "{letter}: jerk {:.6} × limit at tick {}",
                    wj.ratio, wj.tick
                ));
            }
        }
        if bad.is_empty() {
            Ok(())
        } else {
            Err(bad.join("; "))
        }
    }
}
