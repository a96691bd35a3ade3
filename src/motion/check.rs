//! Limit check: per-axis velocity and acceleration from finite differences of the positions
//! recorded each tick, compared with the axis limits — what the tests (and anyone suspicious of
//! the planner) run over a whole program.
//!
//! v_k = (p_k − p_{k−1}) / dt is the mean velocity over a tick, so it can never exceed a limit the
//! motion kept; a_k = (v_k − v_{k−1}) / dt is a weighted mean of the acceleration over two ticks
//! plus the velocity jumps at corners the window covers. Both are checked against
//! limit × (1 + ε): ε covers rounding and the corner case the planner's junction rule bounds
//! only approximately (several corners inside one tick with unequal block lengths).

use crate::queue::{Position, MAX_AXES};

use super::AxisLimits;

/// Tolerance the tests use: 2 %.
pub const DEFAULT_EPS: f64 = 0.02;

/// The worst tick seen for one axis and one quantity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Worst {
    /// |value| / limit.
    pub ratio: f64,
    /// Tick number (0 = first recorded position).
    pub tick: u64,
}

/// Feed it every tick's position; ask for the worst ratios.
#[derive(Debug, Clone)]
pub struct LimitCheck {
    vmax_mm_per_s: [f64; MAX_AXES],
    amax_mm_per_s2: [f64; MAX_AXES],
    dt_s: f64,
    eps: f64,
    prev: Option<Position>,
    prev_v: Option<[f64; MAX_AXES]>,
    ticks: u64,
    pub worst_velocity: [Worst; MAX_AXES],
    pub worst_accel: [Worst; MAX_AXES],
}

impl LimitCheck {
    pub fn new(axes: &[AxisLimits], dt_s: f64, eps: f64) -> Self {
        let mut vmax = [f64::INFINITY; MAX_AXES];
        let mut amax = [f64::INFINITY; MAX_AXES];
        for a in axes {
            if a.index < MAX_AXES {
                vmax[a.index] = a.max_velocity_mm_per_min / 60.0;
                amax[a.index] = a.max_accel_mm_per_s2;
            }
        }
        let w = Worst {
            ratio: 0.0,
            tick: 0,
        };
        LimitCheck {
            vmax_mm_per_s: vmax,
            amax_mm_per_s2: amax,
            dt_s,
            eps,
            prev: None,
            prev_v: None,
            ticks: 0,
            worst_velocity: [w; MAX_AXES],
            worst_accel: [w; MAX_AXES],
        }
    }

    /// The position after one more tick.
    pub fn record(&mut self, p: Position) {
        if let Some(q) = self.prev {
            let mut v = [0.0; MAX_AXES];
            for i in 0..MAX_AXES {
                v[i] = (p[i] - q[i]) / self.dt_s;
                let r = v[i].abs() / self.vmax_mm_per_s[i];
                if r > self.worst_velocity[i].ratio {
                    self.worst_velocity[i] = Worst {
                        ratio: r,
                        tick: self.ticks,
                    };
                }
            }
            if let Some(u) = self.prev_v {
                for i in 0..MAX_AXES {
                    let a = (v[i] - u[i]) / self.dt_s;
                    let r = a.abs() / self.amax_mm_per_s2[i];
                    if r > self.worst_accel[i].ratio {
                        self.worst_accel[i] = Worst {
                            ratio: r,
                            tick: self.ticks,
                        };
                    }
                }
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
    }

    /// Every axis kept |v| ≤ vmax·(1+ε) and |a| ≤ amax·(1+ε); else a description of the worst.
    pub fn verdict(&self) -> Result<(), String> {
        let mut bad = Vec::new();
        for i in 0..MAX_AXES {
            let (wv, wa) = (self.worst_velocity[i], self.worst_accel[i]);
            let letter = crate::queue::AXIS_LETTERS[i] as char;
            if wv.ratio > 1.0 + self.eps {
                bad.push(format!(
                    "{letter}: velocity {:.3} × limit at tick {}",
                    wv.ratio, wv.tick
                ));
            }
            if wa.ratio > 1.0 + self.eps {
                bad.push(format!(
                    "{letter}: acceleration {:.3} × limit at tick {}",
                    wa.ratio, wa.tick
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
