//! Planning plus interpolation per tick with a 32-block lookahead window on a stream of 0.1 mm
//! segments at F6000 (1,000 blocks per second: one block arrives, is released and re-planned,
//! and one finishes every 1 ms tick — the planner's busiest steady state), in seven set-ups:
//! plain (trapezoid profiles), jerk (jerk limits 20,000 mm/s³ and a 50 ms corner filter, the
//! axis filter on), contour (G261, every corner blended by an arc within 0.05 mm), contour +
//! jerk, trc (G41 with a 5 mm tool: every segment offset and joined), spline_akima (G151,
//! Akima through the points) and spline_bspline+jerk.
//!
//! Criterion reports the mean per tick; `per_tick_percentiles` times 200,000 single ticks with
//! `Instant` and prints p50 / p99 / max, the figure the budget (p99 ≤ 10 µs) is stated in.

use std::hint::black_box;
use std::sync::Arc;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion};
use ncchannel::vocab::axis::Position;
use ncchannel::vocab::techno::NoUnits;
use ncchannel::{
    Action, BlockInfo, BlockQueue, CompSide, Move, MoveKind, PathMode, QueuedBlock, SplineKind,
};
use ncchannel::{AxisLimits, Motion, MotionNote, PlannerSettings};

const DT: f64 = 0.001;
const WINDOW: usize = 32;

/// A motion fed 0.1 mm segments along a circle of radius 50 mm (so every junction has a small
/// corner and the junction rule works), one block per tick.
struct Bench {
    motion: Motion,
    path: PathMode,
    queue: BlockQueue,
    notes: Vec<MotionNote>,
    at: Position,
    angle: f64,
    n: u64,
    info: BlockInfo,
}

/// One set-up: name, jerk limit, corner filter (s), the blocks' cross-block state.
type Setup = (&'static str, Option<f64>, f64, PathMode);

const PLAIN: PathMode = PathMode {
    contour_dev_mm: None,
    comp: CompSide::Off,
    tool_offset: 0,
    spline: None,
};

const SETUPS: [Setup; 7] = [
    ("plain", None, 0.0, PLAIN),
    ("jerk", Some(20_000.0), 0.05, PLAIN),
    (
        "contour",
        None,
        0.0,
        PathMode {
            contour_dev_mm: Some(0.05),
            ..PLAIN
        },
    ),
    (
        "contour+jerk",
        Some(20_000.0),
        0.05,
        PathMode {
            contour_dev_mm: Some(0.05),
            ..PLAIN
        },
    ),
    (
        "trc",
        None,
        0.0,
        PathMode {
            comp: CompSide::Left,
            tool_offset: 1,
            ..PLAIN
        },
    ),
    (
        "spline_akima",
        None,
        0.0,
        PathMode {
            spline: Some(SplineKind::Akima),
            ..PLAIN
        },
    ),
    (
        "spline_bspline+jerk",
        Some(20_000.0),
        0.05,
        PathMode {
            spline: Some(SplineKind::BSpline),
            ..PLAIN
        },
    ),
];

impl Bench {
    fn new((_, jerk, corner_s, path): Setup) -> Self {
        let axes = (0..3)
            .map(|index| AxisLimits {
                index,
                max_velocity_mm_per_min: 30000.0,
                max_accel_mm_per_s2: 2000.0,
                max_jerk_mm_per_s3: jerk,
                rapid_mm_per_min: 30000.0,
                min_mm: -1e9,
                max_mm: 1e9,
            })
            .collect();
        let mut b = Bench {
            motion: Motion::with_planner(
                axes,
                PlannerSettings {
                    lookahead_blocks: WINDOW,
                    corner_smoothing_s: corner_s,
                },
            ),
            path,
            queue: BlockQueue::new(WINDOW + 8),
            notes: Vec::new(),
            at: [50.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            angle: 0.0,
            n: 0,
            info: BlockInfo {
                prog: Arc::from("bench.nc"),
                line: 0,
                offset: 0,
                counter: 0,
                n: None,
                text: None,
                stream: true,
            },
        };
        // Tool data set D1: radius 5 mm (the trc set-up).
        b.motion.set_tool_radii(vec![(1, 5.0)]);
        // Fill the window and run into the steady state.
        for _ in 0..WINDOW + 8 {
            b.push();
        }
        for _ in 0..2000 {
            b.tick();
        }
        b
    }

    fn push(&mut self) {
        self.angle += 0.1 / 50.0;
        let to = [
            50.0 * self.angle.cos(),
            50.0 * self.angle.sin(),
            0.0,
            0.0,
            0.0,
            0.0,
        ];
        self.n += 1;
        let mut info = self.info.clone();
        info.counter = self.n;
        self.queue.push(QueuedBlock {
            info,
            action: Action::Move(Box::new(Move {
                kind: MoveKind::Line,
                start: self.at,
                end: to,
                feed_mm_per_min: 6000.0,
                path: self.path,
            })),
            silent: false,
        });
        self.at = to;
    }

    /// One tick: the stream delivers a block when the queue has room, motion steps.
    fn tick(&mut self) {
        if self.queue.has_room() {
            self.push();
        }
        self.motion
            .step(DT, &mut self.queue, &mut self.notes, &NoUnits);
        self.notes.clear();
    }
}

fn per_tick(c: &mut Criterion) {
    for setup in SETUPS {
        let mut b = Bench::new(setup);
        c.bench_function(
            &format!("motion/tick_window32_0.1mm_F6000/{}", setup.0),
            |bench| {
                bench.iter(|| {
                    b.tick();
                    black_box(b.motion.position());
                })
            },
        );
        assert!(
            b.motion.velocity_mm_per_s() > 10.0,
            "the bench must measure moving motion"
        );
    }
}

fn per_tick_percentiles(_c: &mut Criterion) {
    for setup in SETUPS {
        percentiles(setup);
    }
}

fn percentiles(setup: Setup) {
    let mut b = Bench::new(setup);
    let mut ns: Vec<u64> = Vec::with_capacity(200_000);
    let mut v_min = f64::INFINITY;
    for _ in 0..200_000 {
        let t = Instant::now();
        b.tick();
        ns.push(t.elapsed().as_nanos() as u64);
        v_min = v_min.min(b.motion.velocity_mm_per_s());
    }
    ns.sort_unstable();
    let pct = |p: f64| ns[((ns.len() as f64 - 1.0) * p) as usize] as f64 / 1000.0;
    println!(
        "motion per tick, {} (window {WINDOW}, 0.1 mm at F6000, 200000 ticks): \
         p50 {:.2} µs, p99 {:.2} µs, max {:.2} µs; path velocity ≥ {:.1} mm/s",
        setup.0,
        pct(0.5),
        pct(0.99),
        *ns.last().unwrap_or(&0) as f64 / 1000.0,
        v_min
    );
}

criterion_group!(benches, per_tick, per_tick_percentiles);
criterion_main!(benches);
