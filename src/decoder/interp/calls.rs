//! Subroutine and cycle calls, their return, and the `#` commands (`#FLUSH`, `#CACHE`,
//! `#SPLINE`, `#HSC`, `#CONTOUR MODE`, `#VAR`, `#COMMENT`, `#MSG`, `#TIME`).

use std::sync::Arc;

use super::implicit::HeldEnd;
use super::{block_words, expr, Interpreter};
use crate::decoder::error::{var_error, DecodeError, Res};
use crate::decoder::frame::{Frame, FrameKind, Source};
use crate::decoder::io::DecoderIo;
use crate::decoder::line::BlockAt;
use crate::decoder::note::Note;
use crate::decoder::reader::CacheRead;
use crate::decoder::reader::Reader;
use crate::lang::block::{Call, Command, SplineCommand, Value};
use crate::lang::codes;
use crate::lang::eval;
use crate::queue::{Action, BlockInfo, SyncMessage};
use crate::source::cache::LoadStep;
use crate::source::store::{Opened, ProgramKind};
use crate::vocab::event::CacheOp;
use crate::vocab::flush::FlushKind;

impl Interpreter {
    /// One `#VAR` declaration, already validated by the parser (sizes, element count). The
    /// values it made count against this tick's declaration budget.
    pub(in crate::decoder) fn declare(&mut self, d: &crate::lang::block::VarDecl) -> Res<usize> {
        if let Some(crate::lang::block::VarType::String(max)) = d.ty {
            // A string variable: its start value (checked by the parser) or "" in every
            // element (docs/nc-language.md, "Strings").
            let made = self
                .vars
                .declare_str(
                    d.scope,
                    &d.name,
                    &d.dims,
                    max,
                    d.text.as_deref().unwrap_or(""),
                )
                .map_err(var_error)?;
            return Ok(made);
        }
        let init = match &d.init {
            Some(e) => self.eval(e)?,
            None => 0.0,
        };
        let mut values = Vec::with_capacity(d.values.len());
        for e in &d.values {
            values.push(self.eval(e)?);
        }
        let made = self
            .vars
            .declare(d.scope, &d.name, &d.dims, init)
            .map_err(var_error)?;
        self.vars.fill(d.scope, &d.name, &values);
        Ok(made)
    }

    /// M17/M29: back to the caller, past the call line.
    pub(in crate::decoder) fn return_from_subroutine(
        &mut self,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
    ) {
        if rd.pop(notes) {
            self.vars.pop_level();
        }
        if self.implicit.m6_depth.is_some_and(|d| rd.depth() < d) {
            self.implicit.m6_depth = None;
        }
    }

    /// A global subroutine call without a call line (an implicit call): the frame is pushed,
    /// its blocks run as those of `L name` would.
    pub(super) fn call_global(
        &mut self,
        name: &str,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        self.call_implicit(name, FrameKind::Global, Vec::new(), rd, notes, io)
    }

    /// An implicit call of `name` as `kind`, with `params` as its `@P` values.
    fn call_implicit(
        &mut self,
        name: &str,
        kind: FrameKind,
        params: Vec<(u32, f64)>,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        if rd.depth() > self.settings.max_depth {
            return Err(DecodeError::new(
                codes::NESTING_TOO_DEEP,
                format!("subroutine nesting deeper than {}", self.settings.max_depth),
            ));
        }
        let frame = self.open_subroutine(name, kind, rd, notes, io)?;
        self.vars.push_level(params);
        rd.push(frame);
        Ok(())
    }

    /// The subroutine `g800_prog_file[g - 800]` names (P-CHAN-00187), if configured.
    pub(super) fn g800_subroutine(&self, g: u32) -> Option<&str> {
        let i = usize::try_from(g.checked_sub(800)?).ok()?;
        self.settings.implicit.g800.get(i)?.as_deref()
    }

    /// G800–G819 as the last action of its block (TF5200 programming manual, "Implicit
    /// subroutine calls"): its subroutine runs, as a cycle when parameters were given (read
    /// as `@P1`, `@P2`, …); an end in the same block waits for its return.
    pub(super) fn call_g800(
        &mut self,
        g: u32,
        params: &[(u32, f64)],
        end: Option<(u32, BlockInfo)>,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        let Some(name) = self.g800_subroutine(g).map(str::to_string) else {
            return Err(DecodeError::new(
                codes::UNKNOWN_G,
                format!("unknown G function G{g}"),
            ));
        };
        let depth = rd.depth();
        let kind = if params.is_empty() {
            FrameKind::Global
        } else {
            FrameKind::Cycle
        };
        self.call_implicit(&name, kind, params.to_vec(), rd, notes, io)?;
        if let Some((m, info)) = end {
            self.implicit.held.push(HeldEnd { m, info, depth });
        }
        Ok(())
    }

    /// Program start: `start_init_prog_file` (P-CHAN-00119) is called as the first action.
    /// Asked before every line: inline, so the answer for all lines but the first is one
    /// test (the call itself is out of line).
    #[inline]
    pub(in crate::decoder) fn start_subroutine(
        &mut self,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        if !std::mem::take(&mut self.implicit.start_pending) {
            return Ok(());
        }
        self.call_start_subroutine(rd, notes, io)
    }

    #[inline(never)]
    fn call_start_subroutine(
        &mut self,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        match self.settings.implicit.at_start.clone() {
            Some(name) => self.call_global(&name, rd, notes, io),
            None => Ok(()),
        }
    }

    /// M6 with `m6_prog_file` (P-CHAN-00118) set, outside the M6 subroutine itself: its name.
    pub(super) fn m6_subroutine(&self, w: &block_words::Words) -> Option<String> {
        let name = self.settings.implicit.at_m6.as_ref()?;
        (self.implicit.m6_depth.is_none() && w.has_m(6)).then(|| name.clone())
    }

    /// M6 as the last action of its block: the M6 subroutine is called; an end in the same
    /// block waits for its return.
    pub(super) fn call_m6(
        &mut self,
        name: &str,
        end_m: Option<u32>,
        info: BlockInfo,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        let depth = rd.depth();
        self.call_global(name, rd, notes, io)?;
        self.implicit.m6_depth = Some(rd.depth());
        if let Some(m) = end_m {
            self.implicit.held.push(HeldEnd { m, info, depth });
        }
        Ok(())
    }

    /// M02/M30 of the main program: first the end subroutine (P-CHAN-00252), once; then the
    /// end itself.
    pub(super) fn program_end(
        &mut self,
        m: u32,
        info: BlockInfo,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        let main = rd.top().kind() == FrameKind::Main;
        if main && !self.implicit.end_called {
            if let Some(name) = self.settings.implicit.at_end.clone() {
                self.implicit.end_called = true;
                let depth = rd.depth();
                self.call_global(&name, rd, notes, io)?;
                self.implicit.held.push(HeldEnd { m, info, depth });
                return Ok(());
            }
        }
        self.emit(info, Action::End { m }, true, io);
        self.end_program(rd, notes);
        Ok(())
    }

    /// After a return: an end held back for the frame now on top is applied.
    pub(in crate::decoder) fn resume_held_end(
        &mut self,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        let held = match self.implicit.held.last() {
            Some(h) if h.depth == rd.depth() => self.implicit.held.pop(),
            _ => None,
        };
        let Some(h) = held else {
            return Ok(());
        };
        match h.m {
            17 | 29 => {
                rd.top().flow().warn_open_flow(notes);
                self.return_from_subroutine(rd, notes);
                self.resume_held_end(rd, notes, io)
            }
            m => {
                self.program_end_checks(m, rd, notes)?;
                self.program_end(m, h.info, rd, notes, io)
            }
        }
    }

    pub(in crate::decoder) fn exec_command(
        &mut self,
        c: &Command,
        at: BlockAt<'_>,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        let info = self.info(rd, at, io);
        match c {
            Command::Flush(kind) => {
                if let Some((code, what)) = self.modal.flush_refusal() {
                    return Err(DecodeError::new(
                        code,
                        format!("#FLUSH while {what} is active"),
                    ));
                }
                self.emit(info, Action::Flush(*kind), false, io);
                if *kind == FlushKind::Wait && self.search.is_none() {
                    rd.wait_for_idle();
                }
            }
            Command::CacheLoad { .. } | Command::CacheClear { .. } | Command::CacheClearAll => {
                self.exec_cache(c, rd, notes, io)?;
                if !rd.line_waits() {
                    self.emit(info, Action::None, false, io);
                }
            }
            Command::CommentBegin => rd.top().set_comment_block(true),
            // Outside a comment block `#COMMENT END` closes nothing; accepted silently.
            Command::CommentEnd => {}
            // MVS_SLP functions output earlier wait here, before the next block
            // (decoder/interp/techno.rs).
            Command::ExplicitSync => {
                self.emit(info.clone(), Action::None, false, io);
                if let Some(wait) = self.techno.explicit_sync() {
                    self.emit(info, wait, true, io);
                }
            }
            Command::Spline(s) => {
                match s {
                    SplineCommand::On => self.modal.spline = true,
                    SplineCommand::Off => self.modal.spline = false,
                    t => self.modal.spline_type = *t,
                }
                self.emit(info, Action::None, false, io);
            }
            Command::Hsc { on, .. } => {
                self.modal.hsc = *on;
                self.emit(info, Action::None, false, io);
            }
            Command::ContourMode { options } => {
                if let Some(dev) = crate::decoder::modal::path_dev_mm(options) {
                    self.modal.contour_dev_mm = dev;
                }
                self.emit(info, Action::None, false, io)
            }
            // `ON [...]`: the parameters, then G261; `OFF`: G260.
            Command::ContourSwitch { on, options } => {
                if let Some(dev) = crate::decoder::modal::path_dev_mm(options) {
                    self.modal.contour_dev_mm = dev;
                }
                self.modal.contouring = *on;
                self.emit(info, Action::None, false, io)
            }
            Command::Var => rd.top().set_var_block(true),
            Command::EndVar => {}
            Command::Msg(m) => {
                let text = self.format_message(m)?;
                let save = m.save();
                if crate::lang::msg::synchronous(m) {
                    // Reported when execution reaches the block (channel log).
                    let m = Box::new(SyncMessage { text, save });
                    self.emit(info, Action::Message(m), false, io);
                } else {
                    notes.push(Note::Message { text, save });
                    self.emit(info, Action::None, false, io);
                }
            }
            Command::Time(v) => {
                let seconds = match v {
                    Value::Num(n) => *n,
                    Value::Expr(e) => self.eval(e)?,
                };
                let seconds = super::words::dwell_seconds(seconds, codes::DWELL_RANGE_TIME)?;
                self.emit(info, Action::Dwell { seconds }, false, io);
            }
            // The report file's name: read (a string, or the refusal the variable gets), not
            // used, as ncchannel writes no report file (`#MSG SAVE` goes to the event log).
            Command::MsgFileName(v) => {
                let var = crate::lang::block::Expr::Var(v.clone());
                if let eval::Val::Num(_) = expr::eval_value(&var, &expr::Env(self))? {
                    return Err(eval::EvalError::NumberAsString(v.to_string()).into());
                }
                self.emit(info, Action::None, false, io);
            }
            // Accepted without effect (lang::dialect): a block like any other.
            Command::Inert { .. } => self.emit(info, Action::None, false, io),
            Command::Transform(t) => {
                self.transform(t, notes)?;
                self.emit(info, Action::None, false, io);
            }
        }
        Ok(())
    }

    /// `#MSG`: its values evaluated, in written order, and put into its text
    /// (`lang::msg::format_message`, bounded by `MAX_MSG_CHARS`).
    fn format_message(&mut self, m: &crate::lang::Message) -> Res<String> {
        let mut values = Vec::with_capacity(m.args.len());
        for e in &m.args {
            values.push(expr::eval_value(e, &expr::Env(self))?);
        }
        crate::lang::msg::format_message(m, &values)
            .map_err(|e| DecodeError::new(e.code(), e.to_string()))
    }

    /// `#CACHE LOAD`, `#CACHE CLEAR`, `#CACHE CLEAR ALL` (TF5200 File Caching).
    fn exec_cache(
        &mut self,
        c: &Command,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        match c {
            Command::CacheLoad { file } => {
                let loaded = match rd.take_cache_read() {
                    // The line again, after the loader read the file.
                    Some(CacheRead {
                        file: f,
                        read: Some(read),
                        ..
                    }) if f.eq_ignore_ascii_case(file) => io.cache.finish_load(file, read)?,
                    _ => match io.cache.load(file, io.store)? {
                        LoadStep::Done(loaded) => loaded,
                        LoadStep::Reading(pending) => {
                            rd.wait_for_cache_read(CacheRead {
                                file: file.clone(),
                                pending,
                                read: None,
                            });
                            return Ok(());
                        }
                    },
                };
                notes.push(Note::Cache {
                    op: loaded.op(),
                    file: file.clone(),
                });
            }
            Command::CacheClear { file } => {
                io.cache.clear(file)?;
                notes.push(Note::Cache {
                    op: CacheOp::Clear,
                    file: file.clone(),
                });
            }
            Command::CacheClearAll => {
                io.cache.clear_all()?;
                notes.push(Note::Cache {
                    op: CacheOp::ClearAll,
                    file: String::new(),
                });
            }
            _ => {}
        }
        Ok(())
    }

    pub(in crate::decoder) fn exec_call(
        &mut self,
        c: &Call,
        at: BlockAt<'_>,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res {
        if rd.depth() > self.settings.max_depth {
            return Err(DecodeError::new(
                codes::NESTING_TOO_DEEP,
                format!("subroutine nesting deeper than {}", self.settings.max_depth),
            ));
        }
        let info = self.info(rd, at, io);
        match c {
            Call::Global { file } => {
                self.call_global(file, rd, notes, io)?;
                self.emit(info, Action::None, false, io);
            }
            Call::Cycle {
                name,
                local,
                params,
            } => {
                if self.call_cycle(name, *local, params, rd, notes, io)? {
                    self.emit(info, Action::None, false, io);
                }
            }
            Call::Local { name } => {
                let Some(frame) = self.local_frame(rd, name, "local subroutine call (LL)")? else {
                    return Ok(());
                };
                self.emit(info, Action::None, false, io);
                self.vars.push_level(Vec::new());
                rd.push(frame);
            }
        }
        Ok(())
    }

    /// A global subroutine or cycle: the cache first, then the file system, then the stream.
    pub(super) fn open_subroutine(
        &mut self,
        name: &str,
        kind: FrameKind,
        rd: &mut Reader,
        notes: &mut Vec<Note>,
        io: &mut DecoderIo<'_>,
    ) -> Res<Frame> {
        if let Some(p) = io.cache.get(name) {
            if io.want_text {
                // Only with events on: the hot call path stays free of the allocation.
                notes.push(Note::Cache {
                    op: CacheOp::Hit,
                    file: name.to_string(),
                });
            }
            let prog = p.name.clone();
            return Ok(Frame::new(kind, Source::File(p), prog));
        }
        match io.store.open(name, ProgramKind::Subroutine)? {
            Opened::File(p) => {
                let prog: Arc<str> = p.name.clone();
                Ok(Frame::new(kind, Source::File(p), prog))
            }
            // Read by the loader: the frame's first line waits for it.
            Opened::Loading(p) => {
                let prog: Arc<str> = p.name.clone();
                Ok(Frame::new(kind, Source::Loading(p), prog))
            }
            Opened::Stream { name } => {
                if rd.stream_active() {
                    return Err(DecodeError::new(
                        codes::STREAM_ALREADY_ACTIVE,
                        "the streaming program is already running",
                    ));
                }
                rd.begin_stream();
                notes.push(Note::ProgramStart {
                    prog: name.clone(),
                    stream: true,
                });
                Ok(Frame::new(kind, Source::Stream, name))
            }
        }
    }
}
