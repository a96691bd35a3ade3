//! Control flow as a forward skip machine: `$IF`, `$SWITCH`, loops and `$GOTO`, line by line.
//!
//! Nothing here ever looks ahead in the program text: a false branch, a non-matching `$CASE`
//! or a forward jump only sets a skip state, and the lines that follow are examined one by one
//! as they arrive — which is what makes these statements work across stream packets.

use crate::lang::block::{Block, Body, Control, GotoTarget, Label};
use crate::lang::{Expr, VarRef};

use super::error::{DecodeError, Res};
use super::frame::{FlowEntry, Frame, Skip, SkipUntil, MAX_SEEN_LABELS};
use super::interp::Interpreter;
use super::labels::{LabelAt, ScanFound, ScanGoal};
use super::line::{LineMeta, LinePos};
use super::reader::Reader;
use crate::lang::codes;
use crate::lang::control::{
    block_ends_program, control_name, goto_label, goto_text, items_have_m, label_matches,
    label_text, nesting, Nesting,
};
use crate::lang::eval::is_true;

/// Whether `c` closes the loop `e`.
pub(crate) fn closes_loop(e: &FlowEntry, c: &Control) -> bool {
    matches!(
        (e, c),
        (FlowEntry::For { .. }, Control::EndFor)
            | (FlowEntry::While { .. }, Control::EndWhile)
            | (FlowEntry::Do { .. }, Control::EndDo(_))
            | (FlowEntry::Repeat { .. }, Control::Until(_))
    )
}

impl Frame {
    /// Record a label passed in a stream: a label seen twice is codes::LABEL_TWICE; a later `$GOTO` to a
    /// seen label is a backward jump.
    pub(super) fn note_label(&mut self, l: &Label) -> Res {
        let top = self;
        if !top.is_stream() {
            return Ok(());
        }
        if top.seen_labels.contains(l) {
            return Err(DecodeError::new(
                codes::LABEL_TWICE,
                format!("label {} defined twice", label_text(l)),
            ));
        }
        if top.seen_labels.len() < MAX_SEEN_LABELS {
            top.seen_labels.insert(l.clone());
        }
        Ok(())
    }

    /// One line while skipping. Returns whether the line is to be executed after all (the
    /// label line a forward jump was looking for).
    pub(super) fn skip_line(&mut self, block: &Block, ip: &Interpreter) -> Res<bool> {
        let Some(skip) = self.skip.clone() else {
            return Ok(true);
        };
        if let SkipUntil::Label(t) = &skip.until {
            return self.skip_to_label(block, t);
        }
        if skip.until == SkipUntil::LocalSubroutine {
            match &block.body {
                Body::Items(items) if items_have_m(items, &[17, 29]) => self.skip = None,
                // A section without M17/M29 ends at the next main program head, which runs.
                Body::ProgramHead { local: false, .. } => {
                    self.skip = None;
                    return Ok(true);
                }
                _ => {}
            }
            return Ok(false);
        }
        let Body::Control(c) = &block.body else {
            return Ok(false);
        };
        if self.skip_nested(c, skip.depth) {
            return Ok(false);
        }
        self.skip_reaches(&skip.until, c, ip)
    }

    /// A forward jump (streams): the line with the label runs; structures passed on the way
    /// keep the flow stack right; a program end before the label is 20840.
    fn skip_to_label(&mut self, block: &Block, t: &GotoTarget) -> Res<bool> {
        let is_stream = self.is_stream();
        if let Some(l) = &block.label {
            self.note_label(l)?;
            if label_matches(l, t) {
                self.skip = None;
                return Ok(true);
            }
        }
        if let Body::Control(c) = &block.body {
            // Structures opened or closed between jump and label keep the stack right.
            let top = self;
            match c {
                Control::If(_) => top.flow.push(FlowEntry::If { taken: true }),
                Control::Switch(_) => top.flow.push(FlowEntry::Switch { value: f64::NAN }),
                Control::EndIf if matches!(top.flow.last(), Some(FlowEntry::If { .. })) => {
                    top.flow.pop();
                }
                Control::EndSwitch if matches!(top.flow.last(), Some(FlowEntry::Switch { .. })) => {
                    top.flow.pop();
                }
                _ => {}
            }
        }
        if is_stream && block_ends_program(block) {
            return Err(DecodeError::new(
                codes::LABEL_NOT_FOUND,
                format!("label {} not found before program end", goto_text(t)),
            ));
        }
        Ok(false)
    }

    /// A structure opened or closed inside the skipped region: counted, and the line is
    /// skipped. `true` when the line belongs to such a nested structure.
    fn skip_nested(&mut self, c: &Control, depth: u32) -> bool {
        match nesting(c) {
            Nesting::Open => {
                if let Some(s) = self.skip.as_mut() {
                    s.depth += 1;
                }
                true
            }
            Nesting::Close if depth > 0 => {
                if let Some(s) = self.skip.as_mut() {
                    s.depth -= 1;
                }
                true
            }
            _ => depth > 0,
        }
    }

    /// A statement at the skipped structure's own level: does it end the skip? `true` when
    /// the line is then to be executed (the loop end a `$CONTINUE` looked for).
    fn skip_reaches(&mut self, until: &SkipUntil, c: &Control, ip: &Interpreter) -> Res<bool> {
        match (until, c) {
            (SkipUntil::IfBranch, Control::ElseIf(e)) if is_true(ip.eval(e)?) => {
                self.skip = None;
                self.set_if_taken();
            }
            (SkipUntil::IfBranch, Control::Else) => {
                self.skip = None;
                self.set_if_taken();
            }
            (SkipUntil::IfBranch | SkipUntil::IfEnd, Control::EndIf) => {
                let top = self;
                top.skip = None;
                top.flow.pop();
            }
            (SkipUntil::Case, Control::Case(e)) => {
                let v = ip.eval(e)?;
                if let Some(FlowEntry::Switch { value }) = self.flow.last() {
                    if crate::lang::eval::case_matches(*value, v) {
                        self.skip = None;
                    }
                }
            }
            (SkipUntil::Case, Control::Default) => self.skip = None,
            (SkipUntil::Case | SkipUntil::SwitchEnd, Control::EndSwitch) => {
                let top = self;
                top.skip = None;
                top.flow.pop();
            }
            (SkipUntil::LoopExit, c) => {
                let top = self;
                if top.flow.last().is_some_and(|e| closes_loop(e, c)) {
                    top.skip = None;
                    top.flow.pop();
                }
            }
            (SkipUntil::LoopContinue, c) => {
                let top = self;
                if top.flow.last().is_some_and(|e| closes_loop(e, c)) {
                    top.skip = None;
                    return Ok(true);
                }
            }
            _ => {}
        }
        Ok(false)
    }

    pub(super) fn set_if_taken(&mut self) {
        if let Some(FlowEntry::If { taken }) = self.flow.last_mut() {
            *taken = true;
        }
    }

    pub(super) fn begin_skip(&mut self, until: SkipUntil) {
        self.skip = Some(Skip::new(until));
    }
}

/// The error for a `$` statement met outside its structure.
pub(super) fn stray(c: &Control) -> DecodeError {
    use crate::lang::codes::StrayKind as K;
    let kind = match c {
        Control::Else => Some(K::Else),
        Control::ElseIf(_) => Some(K::ElseIf),
        Control::EndIf => Some(K::EndIf),
        Control::Case(_) => Some(K::Case),
        Control::Default => Some(K::Default),
        Control::Break => Some(K::Break),
        Control::EndSwitch => Some(K::EndSwitch),
        Control::EndFor => Some(K::EndFor),
        Control::EndWhile => Some(K::EndWhile),
        Control::EndDo(_) => Some(K::EndDo),
        Control::Until(_) => Some(K::Until),
        Control::Continue => Some(K::Continue),
        _ => None,
    };
    let code = kind.map_or(codes::SYNTAX, K::code);
    DecodeError::new(code, format!("unexpected {}", control_name(c)))
}

impl Frame {
    /// Run a `$` statement. A jump it makes is returned, for [`goto`] to make with the
    /// reader's label index.
    pub(super) fn exec_control<'c>(
        &mut self,
        c: &'c Control,
        meta: LineMeta,
        ip: &mut Interpreter,
    ) -> Res<Option<&'c GotoTarget>> {
        match c {
            Control::Break | Control::Continue => self.exec_leave(c).map(|()| None),
            Control::For {
                var,
                start,
                end,
                step,
            } => self
                .exec_for(var, start, end, step.as_deref(), ip)
                .map(|()| None),
            Control::EndFor => self.exec_end_for(c, ip).map(|()| None),
            Control::While(_)
            | Control::EndWhile
            | Control::Do
            | Control::EndDo(_)
            | Control::Repeat
            | Control::Until(_) => self.exec_loop(c, meta, ip).map(|()| None),
            _ => self.exec_branch(c, ip),
        }
    }

    /// Open a structure whose condition decides whether its body runs (`$IF`, `$WHILE`):
    /// pushed either way, the body skipped when the condition is false.
    fn open_conditional(
        &mut self,
        e: &crate::lang::block::Expr,
        entry: impl FnOnce(bool) -> FlowEntry,
        or_skip: SkipUntil,
        ip: &Interpreter,
    ) -> Res {
        let v = is_true(ip.eval(e)?);
        self.flow.push(entry(v));
        if !v {
            self.begin_skip(or_skip);
        }
        Ok(())
    }

    /// `$IF`, `$SWITCH` and their parts, `$GOTO`.
    fn exec_branch<'c>(&mut self, c: &'c Control, ip: &Interpreter) -> Res<Option<&'c GotoTarget>> {
        match c {
            Control::If(e) => {
                self.open_conditional(e, |v| FlowEntry::If { taken: v }, SkipUntil::IfBranch, ip)?
            }
            Control::IfGoto(e, t) if is_true(ip.eval(e)?) => return Ok(Some(t)),
            Control::ElseIf(_) | Control::Else => match self.flow.last() {
                Some(FlowEntry::If { .. }) => self.begin_skip(SkipUntil::IfEnd),
                _ => return Err(stray(c)),
            },
            Control::EndIf => match self.flow.last() {
                Some(FlowEntry::If { .. }) => {
                    self.flow.pop();
                }
                _ => return Err(stray(c)),
            },
            Control::Switch(e) => {
                let value = ip.eval(e)?;
                self.flow.push(FlowEntry::Switch { value });
                self.begin_skip(SkipUntil::Case);
            }
            // Executing into a later case: fall through (no `$BREAK` before it).
            Control::Case(_) | Control::Default => match self.flow.last() {
                Some(FlowEntry::Switch { .. }) => {}
                _ => return Err(stray(c)),
            },
            Control::EndSwitch => match self.flow.last() {
                Some(FlowEntry::Switch { .. }) => {
                    self.flow.pop();
                }
                _ => return Err(stray(c)),
            },
            Control::Goto(t) => return Ok(Some(t)),
            _ => {}
        }
        Ok(None)
    }

    /// `$BREAK` and `$CONTINUE`: close the structures they leave, skip to the end.
    fn exec_leave(&mut self, c: &Control) -> Res {
        match c {
            Control::Break => {
                let inner = self
                    .flow
                    .iter()
                    .rev()
                    .find(|e| e.is_loop() || matches!(e, FlowEntry::Switch { .. }))
                    .cloned();
                match inner {
                    Some(FlowEntry::Switch { .. }) => {
                        // Close inner $IFs between the $BREAK and its switch.
                        while matches!(self.flow.last(), Some(FlowEntry::If { .. })) {
                            self.flow.pop();
                        }
                        self.begin_skip(SkipUntil::SwitchEnd);
                    }
                    Some(_) => {
                        while matches!(
                            self.flow.last(),
                            Some(FlowEntry::If { .. } | FlowEntry::Switch { .. })
                        ) {
                            self.flow.pop();
                        }
                        self.begin_skip(SkipUntil::LoopExit);
                    }
                    None => return Err(stray(c)),
                }
            }
            Control::Continue => {
                if !self.flow.iter().any(FlowEntry::is_loop) {
                    return Err(stray(c));
                }
                while matches!(
                    self.flow.last(),
                    Some(FlowEntry::If { .. } | FlowEntry::Switch { .. })
                ) {
                    self.flow.pop();
                }
                self.begin_skip(SkipUntil::LoopContinue);
            }
            _ => {}
        }
        Ok(())
    }

    /// `$FOR`: set the variable to its start and enter the body, or skip it.
    fn exec_for(
        &mut self,
        var: &VarRef,
        start: &Expr,
        end: &Expr,
        step: Option<&Expr>,
        ip: &mut Interpreter,
    ) -> Res {
        let key = ip.resolve(var)?;
        let start = ip.eval(start)?;
        let end = ip.eval(end)?;
        let step = match step {
            Some(s) => ip.eval(s)?,
            None => 1.0,
        };
        if step == 0.0 || !step.is_finite() {
            return Err(DecodeError::new(
                codes::BAD_VALUE,
                "$FOR step must not be 0",
            ));
        }
        ip.set_var(key.clone(), start)?;
        let body = self.line_pos();
        self.flow.push(FlowEntry::For {
            var: key,
            end,
            step,
            body,
        });
        if !for_continues(start, end, step) {
            self.begin_skip(SkipUntil::LoopExit);
        }
        Ok(())
    }

    /// `$ENDFOR`: step the variable and go round again, or leave the loop.
    fn exec_end_for(&mut self, c: &Control, ip: &mut Interpreter) -> Res {
        match self.flow.last().cloned() {
            Some(FlowEntry::For {
                var,
                end,
                step,
                body,
            }) => {
                let v = ip.var(&var).unwrap_or(0.0) + step;
                ip.set_var(var, v)?;
                if for_continues(v, end, step) {
                    self.seek(body);
                } else {
                    self.flow.pop();
                }
            }
            _ => return Err(stray(c)),
        }
        Ok(())
    }

    /// `$WHILE`, `$DO` and `$REPEAT` loops.
    fn exec_loop(&mut self, c: &Control, meta: LineMeta, ip: &Interpreter) -> Res {
        let here = LinePos {
            pos: meta.offset as usize,
            line_no: meta.line - 1,
        };
        match c {
            Control::While(e) => self.open_conditional(
                e,
                |_| FlowEntry::While { head: here },
                SkipUntil::LoopExit,
                ip,
            )?,
            Control::EndWhile => match self.flow.last().cloned() {
                Some(FlowEntry::While { head }) => {
                    // Back to the $WHILE line, which evaluates and pushes again.
                    self.flow.pop();
                    self.seek(head);
                }
                _ => return Err(stray(c)),
            },
            Control::Do | Control::Repeat => {
                let body = self.line_pos();
                let entry = match c {
                    Control::Do => FlowEntry::Do { body },
                    _ => FlowEntry::Repeat { body },
                };
                self.flow.push(entry);
            }
            // `$ENDDO cond` loops while cond holds, `$UNTIL cond` until it holds.
            Control::EndDo(e) | Control::Until(e) => {
                let (body, again_if) = match (c, self.flow.last()) {
                    (Control::EndDo(_), Some(FlowEntry::Do { body })) => (*body, true),
                    (Control::Until(_), Some(FlowEntry::Repeat { body })) => (*body, false),
                    _ => return Err(stray(c)),
                };
                if is_true(ip.eval(e)?) == again_if {
                    self.seek(body);
                } else {
                    self.flow.pop();
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// Continue at a label: its structural depth decides which open structures the jump
    /// leaves.
    pub(super) fn jump_to(&mut self, (at, depth): LabelAt) {
        let top = self;
        top.seek(at);
        top.flow.truncate(depth);
        while top.flow.len() < depth {
            top.flow.push(FlowEntry::If { taken: true });
        }
    }

    pub(super) fn check_open_flow(&mut self) -> Res {
        if !self.flow.is_empty() {
            return Err(DecodeError::new(
                codes::OPEN_CONTROL_BLOCK,
                "open control blocks at program end",
            ));
        }
        Ok(())
    }
}

/// `$GOTO`: in a stream a forward skip to the label; in a file a jump by the label index of
/// the top frame's text, which the reader builds over several ticks.
pub(super) fn goto(rd: &mut Reader, t: &GotoTarget) -> Res {
    let top = rd.top();
    if top.is_stream() {
        let key = goto_label(t);
        if top.seen_labels.contains(&key) {
            return Err(DecodeError::new(
                codes::STREAM_BACKWARD_JUMP,
                format!("backward jump to {} in streaming program", goto_text(t)),
            ));
        }
        top.skip = Some(Skip::new(SkipUntil::Label(t.clone())));
        return Ok(());
    }
    // A file frame: the label index, built over several ticks; the line waits for it.
    let Some(index) = rd.label_index() else {
        return Ok(());
    };
    let found = match index.find(t) {
        Some(at) => Some(at),
        None if index.overflowed => match rd.searched(ScanGoal::Label(goto_label(t))) {
            Some(ScanFound::Label(at)) => at,
            _ => return Ok(()),
        },
        None => None,
    };
    let Some((at, depth)) = found else {
        return Err(DecodeError::new(
            codes::LABEL_NOT_FOUND,
            format!("label {} not found", goto_text(t)),
        ));
    };
    rd.top().jump_to((at, depth));
    Ok(())
}

pub(super) fn for_continues(v: f64, end: f64, step: f64) -> bool {
    if step > 0.0 {
        v <= end + 1e-9
    } else {
        v >= end - 1e-9
    }
}
