//! Tool radius compensation (G41 tool left of the path, G42 right, G40 off) in the G17 plane:
//! each programmed line or arc is offset by the radius of the D word's tool; where two offset
//! elements meet, an outer corner gets an arc around the programmed corner point and an inner
//! corner is cut at the intersection of the two offset elements (lines and arcs alike).
//!
//! The element being compensated waits for its successor (its end depends on it): the
//! planner holds one programmed block back while compensation is on. Selection: the block that
//! switches G41/G42 on runs straight from its programmed start to the compensated start of the
//! next element. Deselection: the G40 block runs straight from the compensated end of the last
//! element to its programmed end. A stop (dwell, program end) ends the element at its own
//! offset end point; the next element continues from there by a straight connection.
//!
//! An impossible compensation — the tool radius is not below an arc's radius on the inside,
//! or two elements too short for their offsets to meet — is error [`TRC_IMPOSSIBLE`].

use crate::queue::{CompSide, Move, MoveKind, Plane};
use crate::vocab::axis::Position;

pub(crate) use crate::lang::codes::TRC_IMPOSSIBLE;
/// Below this two points are one, mm.
const EPS_MM: f64 = 1e-9;

/// Why planning a block failed (compensation impossible, a software limit crossed): an
/// error number from `lang::codes` and its text, for the channel's error.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PlanError {
    pub(crate) code: u32,
    pub(crate) msg: String,
    /// The program and line of the refused block, where known.
    pub(crate) block: Option<(String, u64)>,
}

fn impossible(msg: String) -> PlanError {
    PlanError {
        code: TRC_IMPOSSIBLE,
        msg,
        block: None,
    }
}

/// The state of one compensation run.
#[derive(Debug, Clone)]
pub(crate) struct Comp {
    side: CompSide,
    radius_mm: f64,
    pending: Pending,
    /// Left normal of the last element at its end (for elements without an XY direction).
    last_normal: [f64; 2],
}

#[derive(Debug, Clone)]
enum Pending {
    /// The selection block: its programmed start and end; its compensated end depends on the
    /// next element.
    Selection(Move),
    /// An offset element whose start is fixed; `prog` is what was programmed.
    Element { off: Move, prog: Move },
    /// Nothing waits: the last compensated point, and the programmed point it belongs to.
    Rest { at: Position },
}

impl Comp {
    /// Compensation switches on with the selection block `mv`.
    pub(crate) fn select(side: CompSide, radius_mm: f64, mv: Move) -> Self {
        Comp {
            side,
            radius_mm,
            pending: Pending::Selection(mv),
            last_normal: [0.0, 1.0],
        }
    }

    pub(crate) fn side(&self) -> CompSide {
        self.side
    }

    /// The next compensated block `mv` (same side): moves for the window, in order.
    pub(crate) fn next(&mut self, mv: Move, out: &mut Vec<Move>) -> Result<(), PlanError> {
        let b = self.offset(&mv)?;
        match std::mem::replace(&mut self.pending, Pending::Rest { at: mv.end }) {
            Pending::Selection(sel) => {
                out.push(line(sel.start, b.start, &sel));
                self.pending = Pending::Element { off: b, prog: mv };
            }
            Pending::Rest { at } => {
                if dist2(&at, &b.start) > EPS_MM {
                    out.push(line(at, b.start, &mv));
                }
                self.pending = Pending::Element { off: b, prog: mv };
            }
            Pending::Element { off, prog } => {
                let b = self.join(off, &prog, b, out)?;
                self.pending = Pending::Element { off: b, prog: mv };
            }
        }
        Ok(())
    }

    /// A stop or the end of compensation: the waiting element ends at its own offset end.
    pub(crate) fn finish(&mut self, out: &mut Vec<Move>) -> Result<(), PlanError> {
        match std::mem::replace(&mut self.pending, Pending::Rest { at: [0.0; 6] }) {
            Pending::Selection(sel) => {
                let end = self.offset_point(&sel, true);
                out.push(line(sel.start, end, &sel));
                self.pending = Pending::Rest { at: end };
            }
            Pending::Element { off, .. } => {
                let end = off.end;
                out.push(off);
                self.pending = Pending::Rest { at: end };
            }
            Pending::Rest { at } => self.pending = Pending::Rest { at },
        }
        Ok(())
    }

    /// Deselection by the G40 block `mv`: the waiting element, then a line to `mv`'s end.
    pub(crate) fn deselect(mut self, mv: Move, out: &mut Vec<Move>) -> Result<(), PlanError> {
        self.finish(out)?;
        if let Pending::Rest { at } = self.pending {
            out.push(line(at, mv.end, &mv));
        }
        Ok(())
    }

    /// Left normal (unit, XY) of `m` at its start or end; a block without XY motion keeps
    /// the last element's.
    fn normal(&self, m: &Move, at_end: bool) -> [f64; 2] {
        let no_xy = matches!(m.kind, MoveKind::Line | MoveKind::Rapid)
            && (m.end[0] - m.start[0]).hypot(m.end[1] - m.start[1]) <= EPS_MM;
        if no_xy {
            return self.last_normal;
        }
        let t = tangent2(m, at_end);
        [-t[1], t[0]]
    }

    fn sign(&self) -> f64 {
        if self.side == CompSide::Right {
            -1.0
        } else {
            1.0
        }
    }

    fn offset_point(&self, m: &Move, at_end: bool) -> Position {
        let n = self.normal(m, at_end);
        let mut p = if at_end { m.end } else { m.start };
        p[0] += self.sign() * self.radius_mm * n[0];
        p[1] += self.sign() * self.radius_mm * n[1];
        p
    }

    /// The offset element of `m`.
    fn offset(&mut self, m: &Move) -> Result<Move, PlanError> {
        let mut o = *m;
        match m.kind {
            MoveKind::Arc {
                plane,
                center,
                radius_mm,
                cw,
                sweep_rad,
            } => {
                if plane != Plane::Xy {
                    return Err(impossible(
                        "tool radius compensation works in the G17 plane only".into(),
                    ));
                }
                // Tool towards the centre: left of a ccw arc, right of a cw arc.
                let inside = (self.side == CompSide::Left) != cw;
                let r = if inside {
                    radius_mm - self.radius_mm
                } else {
                    radius_mm + self.radius_mm
                };
                if r <= 1e-6 {
                    return Err(impossible(format!(
                        "tool radius {} mm not below the arc radius {radius_mm} mm on its inside",
                        self.radius_mm
                    )));
                }
                o.start = self.offset_point(m, false);
                o.end = self.offset_point(m, true);
                o.kind = MoveKind::Arc {
                    plane,
                    center,
                    radius_mm: r,
                    cw,
                    sweep_rad,
                };
            }
            _ => {
                o.start = self.offset_point(m, false);
                o.end = self.offset_point(m, true);
            }
        }
        self.last_normal = self.normal(m, true);
        Ok(o)
    }

    /// Join offset element `a` (programmed `prog_a`) with the next offset element `b`: the
    /// finished `a` (and the corner arc of an outer corner) into `out`; `b` with its start
    /// fixed back.
    fn join(
        &self,
        a: Move,
        prog_a: &Move,
        mut b: Move,
        out: &mut Vec<Move>,
    ) -> Result<Move, PlanError> {
        if dist2(&a.end, &b.start) <= EPS_MM {
            b.start = a.end;
            out.push(a);
            return Ok(b);
        }
        let corner = prog_a.end;
        let (ta, tb) = (tangent2(&a, true), tangent2(&b, false));
        let left_turn = ta[0] * tb[1] - ta[1] * tb[0] > 0.0;
        let outer = match self.side {
            CompSide::Right => left_turn,
            _ => !left_turn,
        };
        if outer {
            let cw = self.side == CompSide::Left;
            let arc = arc_around(corner, self.radius_mm, a.end, b.start, cw, &b);
            out.push(a);
            out.push(arc);
            return Ok(b);
        }
        let x = intersect(&a, &b, corner).ok_or_else(|| {
            impossible(format!(
                "tool radius compensation impossible at X{:.4} Y{:.4}: the offset elements do not meet",
                corner[0], corner[1]
            ))
        })?;
        out.push(trim(a, None, Some(x)));
        Ok(trim(b, Some(x), None))
    }
}

/// A straight move from `from` to `to` with `like`'s feed and path state.
fn line(from: Position, to: Position, like: &Move) -> Move {
    Move {
        kind: MoveKind::Line,
        start: from,
        end: to,
        feed_mm_per_min: like.feed_mm_per_min,
        path: like.path,
    }
}

/// The arc of radius `r` around `c` from `p` to `q` (cw when `cw`), with `like`'s feed.
fn arc_around(c: Position, r: f64, p: Position, q: Position, cw: bool, like: &Move) -> Move {
    let a0 = (p[1] - c[1]).atan2(p[0] - c[0]);
    let a1 = (q[1] - c[1]).atan2(q[0] - c[0]);
    let sweep = if cw { a0 - a1 } else { a1 - a0 }.rem_euclid(std::f64::consts::TAU);
    Move {
        kind: MoveKind::Arc {
            plane: Plane::Xy,
            center: [c[0], c[1]],
            radius_mm: r,
            cw,
            sweep_rad: sweep.max(1e-12),
        },
        start: p,
        end: q,
        feed_mm_per_min: like.feed_mm_per_min,
        path: like.path,
    }
}

/// Unit XY tangent of `m` at its start or end.
fn tangent2(m: &Move, at_end: bool) -> [f64; 2] {
    match m.kind {
        MoveKind::Arc {
            center,
            radius_mm,
            cw,
            ..
        } if radius_mm > 0.0 => {
            let p = if at_end { m.end } else { m.start };
            let r = [
                (p[0] - center[0]) / radius_mm,
                (p[1] - center[1]) / radius_mm,
            ];
            if cw {
                [r[1], -r[0]]
            } else {
                [-r[1], r[0]]
            }
        }
        _ => {
            let (dx, dy) = (m.end[0] - m.start[0], m.end[1] - m.start[1]);
            let l = dx.hypot(dy).max(1e-300);
            [dx / l, dy / l]
        }
    }
}

/// The intersection of the offset elements `a` and `b` nearest the programmed corner, if it
/// lies on both.
fn intersect(a: &Move, b: &Move, corner: Position) -> Option<[f64; 2]> {
    let mut cands: Vec<[f64; 2]> = Vec::with_capacity(4);
    match (a.kind, b.kind) {
        (
            MoveKind::Arc {
                center: c1,
                radius_mm: r1,
                ..
            },
            MoveKind::Arc {
                center: c2,
                radius_mm: r2,
                ..
            },
        ) => circle_circle(c1, r1, c2, r2, &mut cands),
        (
            MoveKind::Arc {
                center, radius_mm, ..
            },
            _,
        ) => line_circle(xy(&b.start), xy(&b.end), center, radius_mm, &mut cands),
        (
            _,
            MoveKind::Arc {
                center, radius_mm, ..
            },
        ) => line_circle(xy(&a.start), xy(&a.end), center, radius_mm, &mut cands),
        _ => line_line(
            xy(&a.start),
            xy(&a.end),
            xy(&b.start),
            xy(&b.end),
            &mut cands,
        ),
    }
    let k = xy(&corner);
    cands
        .into_iter()
        .filter(|x| on_element(a, *x) && on_element(b, *x))
        .min_by(|p, q| d2(*p, k).total_cmp(&d2(*q, k)))
}

fn xy(p: &Position) -> [f64; 2] {
    [p[0], p[1]]
}

fn d2(p: [f64; 2], q: [f64; 2]) -> f64 {
    (p[0] - q[0]).hypot(p[1] - q[1])
}

fn dist2(p: &Position, q: &Position) -> f64 {
    (p[0] - q[0]).hypot(p[1] - q[1])
}

fn line_line(p: [f64; 2], q: [f64; 2], r: [f64; 2], s: [f64; 2], out: &mut Vec<[f64; 2]>) {
    let d1 = [q[0] - p[0], q[1] - p[1]];
    let d2v = [s[0] - r[0], s[1] - r[1]];
    let den = d1[0] * d2v[1] - d1[1] * d2v[0];
    if den.abs() < 1e-15 {
        return;
    }
    let t = ((r[0] - p[0]) * d2v[1] - (r[1] - p[1]) * d2v[0]) / den;
    out.push([p[0] + t * d1[0], p[1] + t * d1[1]]);
}

fn line_circle(p: [f64; 2], q: [f64; 2], c: [f64; 2], r: f64, out: &mut Vec<[f64; 2]>) {
    let d = [q[0] - p[0], q[1] - p[1]];
    let f = [p[0] - c[0], p[1] - c[1]];
    let a = d[0] * d[0] + d[1] * d[1];
    if a <= 0.0 {
        return;
    }
    let b = 2.0 * (f[0] * d[0] + f[1] * d[1]);
    let cc = f[0] * f[0] + f[1] * f[1] - r * r;
    let disc = b * b - 4.0 * a * cc;
    if disc < 0.0 {
        return;
    }
    let sq = disc.sqrt();
    for t in [(-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)] {
        out.push([p[0] + t * d[0], p[1] + t * d[1]]);
    }
}

fn circle_circle(c1: [f64; 2], r1: f64, c2: [f64; 2], r2: f64, out: &mut Vec<[f64; 2]>) {
    let d = d2(c1, c2);
    if d <= 0.0 || d > r1 + r2 || d < (r1 - r2).abs() {
        return;
    }
    let a = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d);
    let h = (r1 * r1 - a * a).max(0.0).sqrt();
    let m = [
        c1[0] + a * (c2[0] - c1[0]) / d,
        c1[1] + a * (c2[1] - c1[1]) / d,
    ];
    let n = [-(c2[1] - c1[1]) / d, (c2[0] - c1[0]) / d];
    out.push([m[0] + h * n[0], m[1] + h * n[1]]);
    out.push([m[0] - h * n[0], m[1] - h * n[1]]);
}

/// Does `x` lie on element `m` (within a small tolerance)?
fn on_element(m: &Move, x: [f64; 2]) -> bool {
    const TOL: f64 = 1e-7;
    match m.kind {
        MoveKind::Arc {
            center,
            cw,
            sweep_rad,
            ..
        } => {
            let a0 = (m.start[1] - center[1]).atan2(m.start[0] - center[0]);
            let ax = (x[1] - center[1]).atan2(x[0] - center[0]);
            let along = if cw { a0 - ax } else { ax - a0 }.rem_euclid(std::f64::consts::TAU);
            along <= sweep_rad + TOL || along >= std::f64::consts::TAU - TOL
        }
        _ => {
            let d = [m.end[0] - m.start[0], m.end[1] - m.start[1]];
            let l2 = d[0] * d[0] + d[1] * d[1];
            if l2 <= 0.0 {
                return false;
            }
            let t = ((x[0] - m.start[0]) * d[0] + (x[1] - m.start[1]) * d[1]) / l2;
            (-TOL..=1.0 + TOL).contains(&t)
        }
    }
}

/// `m` with a new start and/or end point in XY (Z and the other axes kept).
fn trim(mut m: Move, start: Option<[f64; 2]>, end: Option<[f64; 2]>) -> Move {
    if let Some(s) = start {
        m.start[0] = s[0];
        m.start[1] = s[1];
    }
    if let Some(e) = end {
        m.end[0] = e[0];
        m.end[1] = e[1];
    }
    if let MoveKind::Arc {
        center,
        cw,
        ref mut sweep_rad,
        ..
    } = m.kind
    {
        let a0 = (m.start[1] - center[1]).atan2(m.start[0] - center[0]);
        let a1 = (m.end[1] - center[1]).atan2(m.end[0] - center[0]);
        let s = if cw { a0 - a1 } else { a1 - a0 }.rem_euclid(std::f64::consts::TAU);
        // The trimmed sweep is the one nearest the untrimmed (a full circle cut short or
        // lengthened past its start stays about a full turn).
        let tau = std::f64::consts::TAU;
        *sweep_rad = [s, s + tau]
            .into_iter()
            .filter(|c| *c > 1e-12)
            .min_by(|p, q| (p - *sweep_rad).abs().total_cmp(&(q - *sweep_rad).abs()))
            .unwrap_or(*sweep_rad);
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::arc::{arc_move, ArcSpec};
    use crate::queue::PathMode;

    fn p(x: f64, y: f64) -> Position {
        [x, y, 0.0, 0.0, 0.0, 0.0]
    }

    fn arc(from: Position, to: Position, ij: Option<[f64; 2]>, r: Option<f64>, cw: bool) -> Move {
        arc_move(
            &ArcSpec {
                plane: Plane::Xy,
                ijk: match ij {
                    Some([i, j]) => [Some(i), Some(j), None],
                    None => [None; 3],
                },
                radius: r,
                cw,
            },
            from,
            to,
            3000.0,
            1e-6,
        )
        .unwrap()
    }

    #[test]
    fn full_circle_inside_keeps_its_turn() {
        let sel = line(
            p(-60.0, 0.0),
            p(-30.0, 0.0),
            &Move {
                kind: MoveKind::Line,
                start: p(0.0, 0.0),
                end: p(0.0, 0.0),
                feed_mm_per_min: 3000.0,
                path: PathMode::default(),
            },
        );
        let mut c = Comp::select(CompSide::Left, 5.0, sel);
        let mut out = Vec::new();
        c.next(
            arc(p(-30.0, 0.0), p(-30.0, 0.0), Some([30.0, 0.0]), None, false),
            &mut out,
        )
        .unwrap();
        c.next(
            arc(p(-30.0, 0.0), p(-20.0, -10.0), None, Some(10.0), true),
            &mut out,
        )
        .unwrap();
        for m in &out {
            eprintln!(
                "{:?} {:?} -> {:?} len {}",
                m.kind,
                &m.start[..2],
                &m.end[..2],
                m.length_mm()
            );
        }
        let circle = out[1];
        assert!(circle.length_mm() > 150.0, "{circle:?}");
    }
}
