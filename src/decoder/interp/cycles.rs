//! Cycle calls: `L CYCLE [NAME=file @P1=… @P2="text"]` runs a cycle file, `LL CYCLE
//! [NAME=sub …]` a `%L sub` section of the calling file (TF5200 programming manual, "Cycles as
//! global or local subroutines (Call L | LL CYCLE)"). The parameters are evaluated at the call and visible as `@P<n>` in the new
//! level; a string parameter is kept as written, so `IS_STRING[@P1]` and `EXIST[@P1]` see
//! it, and using it as a number is 900008 (docs/nc-language.md, "Constructs of real
//! programs").

use super::{expr, Interpreter};
use crate::decoder::error::{DecodeError, Res};
use crate::decoder::frame::{Frame, FrameKind, Source};
use crate::decoder::io::DecoderIo;
use crate::decoder::labels;
use crate::decoder::note::Note;
use crate::decoder::reader::Reader;
use crate::lang::block::CycleArg;
use crate::lang::codes;
use crate::lang::eval::Val;

impl Interpreter {
    /// The cycle's frame is pushed, its parameters evaluated into the new level. `Ok(false)`:
    /// the call line waits (the label index for `LL CYCLE` is being built) and did nothing.
    pub(super) fn call_cycle(
        &mut self,
        name: &str,
        local: bool,
        params: &[(u32, CycleArg)],
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res<bool> {
        let mut numbers = Vec::with_capacity(params.len());
        let mut texts = Vec::new();
        for (n, a) in params {
            match a {
                // An expression may give a string too (`@P1=V.L.NAME`).
                CycleArg::Expr(e) => match expr::eval_value(e, &expr::Env(self))? {
                    Val::Num(v) => numbers.push((*n, v)),
                    Val::Str(s) => texts.push((*n, Box::from(s))),
                },
                CycleArg::Str(s) => texts.push((*n, Box::from(s.as_str()))),
            }
        }
        let frame = if local {
            match self.local_frame(rd, name, "local cycle call (LL CYCLE)")? {
                Some(f) => f,
                None => return Ok(false),
            }
        } else {
            self.open_subroutine(name, FrameKind::Cycle, rd, notes, io)?
        };
        self.vars.push_cycle_level(numbers, texts);
        rd.push(frame);
        Ok(true)
    }

    /// The frame of `%L name` in the running file, for `LL name` and `LL CYCLE` (`what`
    /// names the call in the streaming error): not in a streaming program, where it is 21479.
    /// `Ok(None)`: the label index (or a search for the section) is still being built; the
    /// call line waits and runs again.
    pub(super) fn local_frame(
        &mut self,
        rd: &mut Reader,
        name: &str,
        what: &str,
    ) -> Res<Option<Frame>> {
        let Some(index) = rd.label_index() else {
            return Ok(None);
        };
        let found = match index.local_sub(name) {
            Some(at) => Some(at),
            None if index.overflowed => {
                match rd.searched(labels::ScanGoal::LocalSub(name.to_ascii_uppercase())) {
                    Some(labels::ScanFound::LocalSub(at)) => at,
                    _ => return Ok(None),
                }
            }
            None => None,
        };
        let Some(at) = found else {
            return Err(DecodeError::new(
                codes::LOCAL_SUB_NOT_FOUND,
                format!("local subroutine {name} not found"),
            ));
        };
        let top = rd.top();
        let Some(p) = top.file() else {
            return Err(DecodeError::new(
                codes::STREAM_LOCAL_CALL,
                format!("{what} in streaming program"),
            ));
        };
        let mut frame = Frame::new(
            FrameKind::Local,
            Source::File(p.clone()),
            top.prog().clone(),
        );
        frame.set_label_index(index);
        frame.seek(at);
        Ok(Some(frame))
    }
}
