//! Random motion blocks for the tick-by-tick limit tests: a deterministic generator and
//! rapids, lines (short and long, in 3-D) and arcs / helices in every plane.

use ncchannel::vocab::axis::Position;
use ncchannel::{arc_move, ArcSpec};
use ncchannel::{Move, MoveKind, PathMode, Plane};

/// A small deterministic generator (no dependency): xorshift64*.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

fn p(x: f64, y: f64, z: f64) -> Position {
    [x, y, z, 0.0, 0.0, 0.0]
}

/// G0 to a random point of the box ±50 × ±50 × ±20 mm.
pub fn rapid(rng: &mut Rng, at: Position) -> Move {
    let to = p(
        rng.range(-50.0, 50.0),
        rng.range(-50.0, 50.0),
        rng.range(-20.0, 20.0),
    );
    Move {
        kind: MoveKind::Rapid,
        start: at,
        end: to,
        feed_mm_per_min: 0.0,
        path: PathMode::default(),
    }
}

/// G1 of 0.05 … 0.5 mm or 1 … 20 mm in a random 3-D direction.
pub fn line(rng: &mut Rng, at: Position, feed: f64) -> Move {
    let len = if rng.next() < 0.5 {
        rng.range(0.05, 0.5)
    } else {
        rng.range(1.0, 20.0)
    };
    let (th, ph) = (rng.range(0.0, 6.3), rng.range(-0.5, 0.5));
    let to = p(
        at[0] + len * th.cos() * ph.cos(),
        at[1] + len * th.sin() * ph.cos(),
        at[2] + len * ph.sin(),
    );
    Move {
        kind: MoveKind::Line,
        start: at,
        end: to,
        feed_mm_per_min: feed,
        path: PathMode::default(),
    }
}

/// G2/G3 in a random plane: radius 0.5 … 15 mm, 0.1 … 6 rad, a helix of up to ±2 mm.
pub fn arc(rng: &mut Rng, at: Position, feed: f64) -> Move {
    let planes = [Plane::Xy, Plane::Zx, Plane::Yz];
    let plane = planes[(rng.next() * 3.0) as usize % 3];
    let (ia, ib, inn) = plane.axes();
    let r = rng.range(0.5, 15.0);
    let phi0 = rng.range(0.0, 6.3);
    let sweep = rng.range(0.1, 6.0);
    let cw = rng.next() < 0.5;
    let center = [at[ia] - r * phi0.cos(), at[ib] - r * phi0.sin()];
    let phi1 = if cw { phi0 - sweep } else { phi0 + sweep };
    let mut to = at;
    to[ia] = center[0] + r * phi1.cos();
    to[ib] = center[1] + r * phi1.sin();
    to[inn] += rng.range(-2.0, 2.0);
    let mut ijk = [None; 3];
    ijk[ia] = Some(center[0] - at[ia]);
    ijk[ib] = Some(center[1] - at[ib]);
    let spec = ArcSpec {
        plane,
        ijk,
        radius: None,
        cw,
    };
    match arc_move(&spec, at, to, feed, 1e-6) {
        Ok(m) => m,
        Err(e) => panic!("a generated arc is consistent by construction: {e:?}"),
    }
}
