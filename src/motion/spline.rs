//! Splines (G151 / `#SPLINE ON`, `#SPLINE TYPE AKIMA|BSPLINE`): the programmed end points of
//! successive G1 blocks become a smooth curve, handed to the planner as short lines.
//!
//! B-spline: a uniform cubic B-spline over the points as control polygon, clamped (the first
//! and last point tripled) so it starts and ends at them; each curve segment depends on four
//! consecutive points, so a point arriving completes one segment — the curve follows a stream
//! one point behind. Akima: per axis, over the cumulative chord length, a Hermite cubic through
//! the points with Akima's tangents (H. Akima, "A new method of interpolation and smooth curve
//! fitting based on local procedures", J. ACM 17 (1970)); a tangent needs two points on either
//! side, so the segment ending at point k is complete when point k + 2 has arrived (at the
//! ends the slopes are extrapolated as Akima proposes).
//!
//! Why short lines. The planner, the interpolator, the junction rule and the axis filter are
//! proven on lines; a curve cut into pieces of at most [`MAX_PIECE_MM`] (2 … 8 per segment) has
//! direction changes of a fraction of a degree between pieces, so the junction rule passes
//! them at speed, and every limit check applies unchanged. The pieces of one programmed block
//! count once towards the lookahead window.

use std::collections::VecDeque;

use crate::queue::{Move, MoveKind, PathMode, SplineKind};
use crate::vocab::axis::{Position, MAX_AXES};

/// Longest piece a curve segment is cut into, mm.
pub(crate) const MAX_PIECE_MM: f64 = 0.02;
const MIN_PIECES: usize = 2;
const MAX_PIECES: usize = 8;

/// The points of the spline being built and what waits for them.
#[derive(Debug, Clone)]
pub(crate) struct Spline {
    kind: SplineKind,
    /// Points not yet fully consumed (B-spline: padded control points; Akima: the last ≤ 6).
    pts: VecDeque<Position>,
    feed_mm_per_min: f64,
    path: PathMode,
    /// Points received (the start point counts as 0).
    received: usize,
    /// Akima: index (in received numbering) of the first point of the next segment to emit.
    next_segment: usize,
}

/// One finished curve segment: the pieces, and the received point it belongs to (its block's
/// event goes on the first piece).
#[derive(Debug, Clone)]
pub(crate) struct Segment {
    pub(crate) pieces: Vec<Move>,
    pub(crate) point: usize,
}

impl Spline {
    /// A spline starting at `start` (the position before its first block).
    pub(crate) fn new(
        kind: SplineKind,
        start: Position,
        feed_mm_per_min: f64,
        path: PathMode,
    ) -> Self {
        let mut pts = VecDeque::with_capacity(8);
        match kind {
            SplineKind::BSpline => {
                pts.extend([start, start, start]);
            }
            SplineKind::Akima => pts.push_back(start),
        }
        Spline {
            kind,
            pts,
            feed_mm_per_min,
            path,
            received: 0,
            next_segment: 0,
        }
    }

    pub(crate) fn kind(&self) -> SplineKind {
        self.kind
    }

    /// Points received so far (the start point not counted).
    pub(crate) fn received(&self) -> usize {
        self.received
    }

    /// The last point received.
    pub(crate) fn last(&self) -> Position {
        self.pts.back().copied().unwrap_or([0.0; MAX_AXES])
    }

    /// Point `p` (feed `feed_mm_per_min`) arrives: the segments it completes.
    pub(crate) fn push(&mut self, p: Position, feed_mm_per_min: f64, out: &mut Vec<Segment>) {
        self.received += 1;
        self.feed_mm_per_min = feed_mm_per_min;
        self.pts.push_back(p);
        match self.kind {
            SplineKind::BSpline => self.bspline_emit(out),
            SplineKind::Akima => {
                while self.next_segment + 3 <= self.received {
                    self.akima_emit(out);
                }
            }
        }
    }

    /// The spline ends: the rest of the curve, ending exactly at the last point.
    pub(crate) fn finish(mut self, out: &mut Vec<Segment>) {
        match self.kind {
            SplineKind::BSpline => {
                if self.received == 0 {
                    return;
                }
                let last = self.last();
                for _ in 0..2 {
                    self.pts.push_back(last);
                    self.bspline_emit(out);
                }
                if let Some(s) = out.last_mut() {
                    if let Some(m) = s.pieces.last_mut() {
                        m.end = last;
                    }
                }
            }
            SplineKind::Akima => {
                while self.next_segment < self.received {
                    self.akima_emit(out);
                }
            }
        }
    }

    fn bspline_emit(&mut self, out: &mut Vec<Segment>) {
        while self.pts.len() >= 4 {
            let c = [self.pts[0], self.pts[1], self.pts[2], self.pts[3]];
            let f = |t: f64| -> Position {
                let (t2, t3) = (t * t, t * t * t);
                let b0 = (1.0 - t).powi(3) / 6.0;
                let b1 = (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0;
                let b2 = (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0;
                let b3 = t3 / 6.0;
                let mut p = [0.0; MAX_AXES];
                for (i, pi) in p.iter_mut().enumerate() {
                    *pi = b0 * c[0][i] + b1 * c[1][i] + b2 * c[2][i] + b3 * c[3][i];
                }
                p
            };
            let chord = dist(&c[1], &c[2]).max(dist(&c[0], &c[3]) / 3.0);
            let pieces = self.pieces(f, chord);
            self.pts.pop_front();
            if !pieces.is_empty() {
                out.push(Segment {
                    pieces,
                    point: self.received,
                });
            }
        }
    }

    /// The Hermite segment from received point `next_segment` to the next one; slopes of
    /// missing points (at the ends) are extrapolated.
    fn akima_emit(&mut self, out: &mut Vec<Segment>) {
        // pts holds received points first..=received; the segment starts at index `i` in pts.
        let first = self.received + 1 - self.pts.len();
        let i = self.next_segment - first;
        let n = self.pts.len();
        if i + 1 >= n {
            self.next_segment = self.received;
            return;
        }
        let p0 = self.pts[i];
        let p1 = self.pts[i + 1];
        let h = dist(&p0, &p1);
        // Slopes m[k] over pts[k]→pts[k+1] (per axis, per mm of chord), k = i−2 … i+2,
        // extrapolated where points are missing.
        let slope = |k: isize| -> Option<Position> {
            if k < 0 || (k as usize) + 1 >= n {
                return None;
            }
            let (a, b) = (self.pts[k as usize], self.pts[k as usize + 1]);
            let d = dist(&a, &b);
            if d <= 0.0 {
                return None;
            }
            let mut m = [0.0; MAX_AXES];
            for (ax, mi) in m.iter_mut().enumerate() {
                *mi = (b[ax] - a[ax]) / d;
            }
            Some(m)
        };
        let ii = i as isize;
        let mut m: [Option<Position>; 5] = [
            slope(ii - 2),
            slope(ii - 1),
            slope(ii),
            slope(ii + 1),
            slope(ii + 2),
        ];
        extrapolate_slopes(&mut m);
        let (Some(ma), Some(mb), Some(mc), Some(md), Some(me)) = (m[0], m[1], m[2], m[3], m[4])
        else {
            self.next_segment += 1;
            return;
        };
        let t0 = akima_tangent(ma, mb, mc, md);
        let t1 = akima_tangent(mb, mc, md, me);
        let f = |s: f64| -> Position {
            let (s2, s3) = (s * s, s * s * s);
            let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
            let h10 = s3 - 2.0 * s2 + s;
            let h01 = -2.0 * s3 + 3.0 * s2;
            let h11 = s3 - s2;
            let mut p = [0.0; MAX_AXES];
            for (ax, pi) in p.iter_mut().enumerate() {
                *pi = h00 * p0[ax] + h10 * h * t0[ax] + h01 * p1[ax] + h11 * h * t1[ax];
            }
            p
        };
        let mut pieces = self.pieces(f, h);
        if let Some(last) = pieces.last_mut() {
            last.end = p1;
        }
        self.next_segment += 1;
        // Keep two points before the next segment's start for its slopes.
        let keep_from = self.next_segment.saturating_sub(2).max(first);
        for _ in first..keep_from {
            self.pts.pop_front();
        }
        if !pieces.is_empty() {
            out.push(Segment {
                pieces,
                point: self.next_segment,
            });
        }
    }

    /// Cut the curve `f` on [0, 1] (chord about `chord_mm`) into lines.
    fn pieces(&self, f: impl Fn(f64) -> Position, chord_mm: f64) -> Vec<Move> {
        let n = ((chord_mm / MAX_PIECE_MM).ceil() as usize).clamp(MIN_PIECES, MAX_PIECES);
        let mut out = Vec::with_capacity(n);
        let mut prev = f(0.0);
        for k in 1..=n {
            let p = f(k as f64 / n as f64);
            if dist(&prev, &p) > 1e-9 {
                out.push(Move {
                    kind: MoveKind::Line,
                    start: prev,
                    end: p,
                    feed_mm_per_min: self.feed_mm_per_min,
                    path: self.path,
                });
                prev = p;
            }
        }
        out
    }
}

fn dist(a: &Position, b: &Position) -> f64 {
    let mut s = 0.0;
    for i in 0..MAX_AXES {
        s += (b[i] - a[i]) * (b[i] - a[i]);
    }
    s.sqrt()
}

/// Akima's extrapolation of the slopes missing at the ends of the received points:
/// m[k−1] = 2·m[k] − m[k+1], mirrored at the far end; one known neighbour is copied.
fn extrapolate_slopes(m: &mut [Option<Position>; 5]) {
    let lin = |a: Position, b: Position| -> Position {
        let mut r = [0.0; MAX_AXES];
        for ax in 0..MAX_AXES {
            r[ax] = 2.0 * a[ax] - b[ax];
        }
        r
    };
    for k in (0..2).rev() {
        if m[k].is_none() {
            if let (Some(a), Some(b)) = (m[k + 1], m[k + 2]) {
                m[k] = Some(lin(a, b));
            } else if let Some(a) = m[k + 1] {
                m[k] = Some(a);
            }
        }
    }
    for k in 3..5 {
        if m[k].is_none() {
            if let (Some(a), Some(b)) = (m[k - 1], m[k - 2]) {
                m[k] = Some(lin(a, b));
            } else if let Some(a) = m[k - 1] {
                m[k] = Some(a);
            }
        }
    }
}

/// Akima's tangent at a point from the slopes of the two chords before it (m1, m2) and the
/// two after it (m3, m4), per axis (H. Akima, J. ACM 17 (1970)).
fn akima_tangent(m1: Position, m2: Position, m3: Position, m4: Position) -> Position {
    let mut t = [0.0; MAX_AXES];
    for ax in 0..MAX_AXES {
        let w1 = (m4[ax] - m3[ax]).abs();
        let w2 = (m2[ax] - m1[ax]).abs();
        t[ax] = if w1 + w2 > 1e-12 {
            (w1 * m2[ax] + w2 * m3[ax]) / (w1 + w2)
        } else {
            0.5 * (m2[ax] + m3[ax])
        };
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Position {
        [x, y, 0.0, 0.0, 0.0, 0.0]
    }

    fn run(kind: SplineKind, pts: &[Position]) -> Vec<Segment> {
        let mut s = Spline::new(kind, p(0.0, 0.0), 1000.0, PathMode::default());
        let mut out = Vec::new();
        for q in pts {
            s.push(*q, 1000.0, &mut out);
        }
        s.finish(&mut out);
        out
    }

    #[test]
    fn akima_passes_through_every_point_and_is_continuous() {
        let pts: Vec<Position> = (1..=12)
            .map(|k| {
                let a = k as f64 * 0.3;
                p(10.0 * a.sin(), 10.0 * (1.0 - a.cos()))
            })
            .collect();
        let segs = run(SplineKind::Akima, &pts);
        assert_eq!(segs.len(), pts.len());
        for (s, q) in segs.iter().zip(&pts) {
            assert_eq!(s.pieces.last().unwrap().end, *q);
        }
        let all: Vec<&Move> = segs.iter().flat_map(|s| &s.pieces).collect();
        assert!(all.windows(2).all(|w| w[0].end == w[1].start));
        assert_eq!(all[0].start, p(0.0, 0.0));
    }

    #[test]
    fn bspline_starts_and_ends_at_the_points_and_stays_in_the_polygon_hull() {
        let pts = [p(10.0, 0.0), p(10.0, 10.0), p(0.0, 10.0)];
        let segs = run(SplineKind::BSpline, &pts);
        let all: Vec<&Move> = segs.iter().flat_map(|s| &s.pieces).collect();
        assert_eq!(all[0].start, p(0.0, 0.0));
        assert_eq!(all.last().unwrap().end, p(0.0, 10.0));
        assert!(all.windows(2).all(|w| w[0].end == w[1].start));
        assert!(all.iter().all(|m| (-1e-9..=10.0 + 1e-9).contains(&m.end[0])
            && (-1e-9..=10.0 + 1e-9).contains(&m.end[1])));
        // The curve cuts the corner at (10, 0): it never reaches it.
        assert!(all.iter().all(|m| m.end != p(10.0, 0.0)));
    }
}
