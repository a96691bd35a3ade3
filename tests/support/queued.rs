//! Decoded blocks as the planner takes them from the block queue, for the motion tests that
//! drive `Motion::step` directly.

use std::sync::Arc;

use ncchannel::vocab::axis::Position;
use ncchannel::{arc_move, ArcSpec};
use ncchannel::{Action, BlockInfo, BlockQueue, Move, MoveKind, PathMode, Plane, QueuedBlock};

/// The event of line `line` of `t.nc`.
pub fn info(line: u32) -> BlockInfo {
    BlockInfo {
        prog: Arc::from("t.nc"),
        line,
        offset: 0,
        counter: line as u64,
        n: None,
        text: None,
        stream: false,
    }
}

/// Line `line` doing `action`.
pub fn block(line: u32, action: Action) -> QueuedBlock {
    QueuedBlock {
        info: info(line),
        action,
        silent: false,
    }
}

/// The R50 circle around the origin at F6000 from (50, 0), counter-clockwise, into `q`: one
/// G03 (`chords` = 0) or `chords` G01 lines with `path` (contouring), then M30. Returns the
/// start, which is also the end.
pub fn r50_circle(q: &mut BlockQueue, chords: usize, path: PathMode) -> Position {
    let start = [50.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    if chords == 0 {
        let spec = ArcSpec {
            plane: Plane::Xy,
            ijk: [Some(-50.0), Some(0.0), None],
            radius: None,
            cw: false,
        };
        let mv = arc_move(&spec, start, start, 6000.0, 1e-6).unwrap();
        q.push(block(1, Action::Move(Box::new(mv))));
    } else {
        let mut at = start;
        for k in 1..=chords {
            let phi = std::f64::consts::TAU * k as f64 / chords as f64;
            let mut to = start;
            if k < chords {
                to[0] = 50.0 * phi.cos();
                to[1] = 50.0 * phi.sin();
            }
            let mv = Move {
                kind: MoveKind::Line,
                start: at,
                end: to,
                feed_mm_per_min: 6000.0,
                path,
            };
            q.push(block(k as u32, Action::Move(Box::new(mv))));
            at = to;
        }
    }
    q.push(block(chords as u32 + 1, Action::End { m: 30 }));
    start
}
