//! Control flow as a forward skip machine: `$IF`, `$SWITCH`, loops and `$GOTO`, line by line.
//!
//! Nothing here ever looks ahead in the program text: a false branch, a non-matching `$CASE`
//! or a forward jump only sets a skip state, and the lines that follow are examined one by one
//! as they arrive — which is what makes these statements work across stream packets.

use std::collections::BTreeSet;

use crate::lang::block::{Block, Body, Control, GotoTarget, Label};
use crate::lang::{Expr, VarRef};

use super::error::{DecodeError, Res};
use super::line::{LineMeta, LinePos};
use super::note::Note;
use super::vars::VarSlot;
use crate::lang::codes;
use crate::lang::control::{
    block_ends_program, control_name, goto_label, goto_text, items_have_m, label_matches,
    label_text, nesting, Nesting,
};
use crate::lang::eval::is_true;

/// One open control structure of a frame.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum FlowEntry {
    /// `$IF`: `taken` once a branch has run, so later `$ELSEIF`/`$ELSE` branches are skipped.
    If { taken: bool },
    /// `$SWITCH`: the value cases compare against.
    Switch { value: f64 },
    /// `$FOR var = start, end, step`: the body starts at `body`.
    For {
        var: VarSlot,
        end: f64,
        step: f64,
        body: LinePos,
    },
    /// `$WHILE`: `head` is the `$WHILE` line itself (the condition is evaluated there).
    While { head: LinePos },
    /// `$DO` … `$ENDDO cond`.
    Do { body: LinePos },
    /// `$REPEAT` … `$UNTIL cond`.
    Repeat { body: LinePos },
}

impl FlowEntry {
    /// The statements that open and close this structure, for messages.
    fn keywords(&self) -> (&'static str, &'static str) {
        match self {
            FlowEntry::If { .. } => ("$IF", "$ENDIF"),
            FlowEntry::Switch { .. } => ("$SWITCH", "$ENDSWITCH"),
            FlowEntry::For { .. } => ("$FOR", "$ENDFOR"),
            FlowEntry::While { .. } => ("$WHILE", "$ENDWHILE"),
            FlowEntry::Do { .. } => ("$DO", "$ENDDO"),
            FlowEntry::Repeat { .. } => ("$REPEAT", "$UNTIL"),
        }
    }

    pub(crate) fn is_loop(&self) -> bool {
        matches!(
            self,
            FlowEntry::For { .. }
                | FlowEntry::While { .. }
                | FlowEntry::Do { .. }
                | FlowEntry::Repeat { .. }
        )
    }
}

/// What the skip machine is looking for.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum SkipUntil {
    /// A false `$IF`/`$ELSEIF`: the next `$ELSEIF` (evaluated), `$ELSE` or `$ENDIF`.
    IfBranch,
    /// A branch has run: the `$ENDIF`.
    IfEnd,
    /// `$SWITCH` looking for its case: a matching `$CASE`, `$DEFAULT` or `$ENDSWITCH`.
    Case,
    /// After `$BREAK` in a switch: the `$ENDSWITCH`.
    SwitchEnd,
    /// A false `$WHILE` or a `$BREAK` in a loop: past the loop's end statement.
    LoopExit,
    /// `$CONTINUE`: the loop's end statement, which is then evaluated.
    LoopContinue,
    /// A forward `$GOTO` (streams): the line with this label.
    Label(GotoTarget),
    /// A `%L name` section met while running the main program: up to its M17/M29, or to the
    /// next `%name` head when it has none.
    LocalSubroutine,
}

/// Skip state: what we look for and how deep inside skipped structures we are.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Skip {
    until: SkipUntil,
    /// Structures opened inside the skipped region and not yet closed.
    depth: u32,
}

impl Skip {
    pub(crate) fn new(until: SkipUntil) -> Self {
        Skip { until, depth: 0 }
    }
}

/// How many stream labels a frame remembers. A stream may run for days; a label passed more
/// than this many labels ago is treated as unknown (a jump to it waits forward for it).
pub(crate) const MAX_SEEN_LABELS: usize = 65_536;

/// A frame's control flow: the structures open in it, what the skip machine looks for, and
/// (streams) the labels passed.
#[derive(Debug, Default)]
pub(crate) struct Flow {
    /// Open control structures, innermost last.
    stack: Vec<FlowEntry>,
    /// Set while lines are being skipped (false branch, forward jump, …).
    skip: Option<Skip>,
    /// Stream frames: labels already passed, to tell a backward jump (21477) from a forward
    /// one and to find labels defined twice (20836). Bounded by `MAX_SEEN_LABELS`; a B-tree
    /// for the reason `LabelIndex` is one.
    seen_labels: BTreeSet<Label>,
}

/// Where a frame goes on after a `$` statement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum FlowStep<'c> {
    /// The next line.
    Next,
    /// Back to a loop's head or body.
    Seek(LinePos),
    /// To a label (`$GOTO`).
    Goto(&'c GotoTarget),
}

/// What the skip machine asks of the interpreter: expressions evaluated, the `$FOR`
/// variable resolved, read and set.
pub(super) trait Env {
    fn eval(&self, e: &Expr) -> Res<f64>;
    fn resolve(&self, v: &VarRef) -> Res<VarSlot>;
    /// A variable's value (`None`: not defined).
    fn var(&self, k: &VarSlot) -> Option<f64>;
    fn set_var(&mut self, k: VarSlot, v: f64) -> Res;
}

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

impl Flow {
    /// Whether freeing the labels passed could cost a tick (then the frame is freed by the
    /// loader thread, `Frame::is_heavy`).
    pub(crate) fn is_heavy(&self) -> bool {
        crate::source::loader::is_heavy_table(self.seen_labels.len())
    }

    /// Record a label passed in a stream: a label seen twice is codes::LABEL_TWICE; a later `$GOTO` to a
    /// seen label is a backward jump.
    pub(super) fn note_label(&mut self, l: &Label, stream: bool) -> Res {
        let top = self;
        if !stream {
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
    #[inline]
    pub(super) fn skip_line(&mut self, block: &Block, stream: bool, ip: &impl Env) -> Res<bool> {
        let Some(skip) = self.skip.clone() else {
            return Ok(true);
        };
        if let SkipUntil::Label(t) = &skip.until {
            return self.skip_to_label(block, t, stream);
        }
        if skip.until == SkipUntil::LocalSubroutine {
            match &block.body {
                Body::Items(items) if items_have_m(items, &[17, 29]) => self.skip = None,
                // A section without M17/M29 ends at the next main program head, which runs.
                Body::ProgramHead(head) if !head.local => {
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
    fn skip_to_label(&mut self, block: &Block, t: &GotoTarget, is_stream: bool) -> Res<bool> {
        if let Some(l) = &block.label {
            self.note_label(l, is_stream)?;
            if label_matches(l, t) {
                self.skip = None;
                return Ok(true);
            }
        }
        if let Body::Control(c) = &block.body {
            // Structures opened or closed between jump and label keep the stack right.
            let top = self;
            match &**c {
                Control::If(_) => top.stack.push(FlowEntry::If { taken: true }),
                Control::Switch(_) => top.stack.push(FlowEntry::Switch { value: f64::NAN }),
                Control::EndIf if matches!(top.stack.last(), Some(FlowEntry::If { .. })) => {
                    top.stack.pop();
                }
                Control::EndSwitch
                    if matches!(top.stack.last(), Some(FlowEntry::Switch { .. })) =>
                {
                    top.stack.pop();
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
    #[inline]
    fn skip_reaches(&mut self, until: &SkipUntil, c: &Control, ip: &impl Env) -> Res<bool> {
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
                top.stack.pop();
            }
            (SkipUntil::Case, Control::Case(e)) => {
                let v = ip.eval(e)?;
                if let Some(FlowEntry::Switch { value }) = self.stack.last() {
                    if crate::lang::eval::case_matches(*value, v) {
                        self.skip = None;
                    }
                }
            }
            (SkipUntil::Case, Control::Default) => self.skip = None,
            (SkipUntil::Case | SkipUntil::SwitchEnd, Control::EndSwitch) => {
                let top = self;
                top.skip = None;
                top.stack.pop();
            }
            (SkipUntil::LoopExit, c) => {
                let top = self;
                if top.stack.last().is_some_and(|e| closes_loop(e, c)) {
                    top.skip = None;
                    top.stack.pop();
                }
            }
            (SkipUntil::LoopContinue, c) => {
                let top = self;
                if top.stack.last().is_some_and(|e| closes_loop(e, c)) {
                    top.skip = None;
                    return Ok(true);
                }
            }
            _ => {}
        }
        Ok(false)
    }

    pub(super) fn set_if_taken(&mut self) {
        if let Some(FlowEntry::If { taken }) = self.stack.last_mut() {
            *taken = true;
        }
    }

    pub(super) fn begin_skip(&mut self, until: SkipUntil) {
        self.skip = Some(Skip::new(until));
    }

    /// Lines are being skipped (a false branch, a forward jump, …).
    pub(super) fn skipping(&self) -> bool {
        self.skip.is_some()
    }

    /// A skip that only `$` statements can end or nest (not a jump to a label, not a local
    /// subroutine's section).
    #[inline]
    pub(super) fn skips_structure(&self) -> bool {
        self.skip
            .as_ref()
            .is_some_and(|s| !matches!(s.until, SkipUntil::Label(_) | SkipUntil::LocalSubroutine))
    }

    /// The label a forward jump is skipping to, if it is one.
    pub(super) fn skipping_to(&self) -> Option<&GotoTarget> {
        match &self.skip {
            Some(Skip {
                until: SkipUntil::Label(t),
                ..
            }) => Some(t),
            _ => None,
        }
    }

    /// A `$GOTO` in a stream: a jump to a label already passed is a backward jump (21477);
    /// to another, the lines are skipped up to the label.
    pub(super) fn skip_to(&mut self, t: &GotoTarget) -> Res {
        let key = goto_label(t);
        if self.seen_labels.contains(&key) {
            return Err(DecodeError::new(
                codes::STREAM_BACKWARD_JUMP,
                format!("backward jump to {} in streaming program", goto_text(t)),
            ));
        }
        self.skip = Some(Skip::new(SkipUntil::Label(t.clone())));
        Ok(())
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

impl Flow {
    /// Run a `$` statement of the line at `meta`, `next` being where the line after it
    /// starts. Where the frame goes on is returned: a loop's way back for the frame to seek,
    /// a jump for the reader to make with its label index (`Reader::goto`).
    pub(super) fn exec_control<'c>(
        &mut self,
        c: &'c Control,
        meta: LineMeta,
        next: LinePos,
        ip: &mut impl Env,
    ) -> Res<FlowStep<'c>> {
        let back = |at: Option<LinePos>| at.map_or(FlowStep::Next, FlowStep::Seek);
        match c {
            Control::Break | Control::Continue => self.exec_leave(c).map(|()| FlowStep::Next),
            Control::For {
                var,
                start,
                end,
                step,
            } => self
                .exec_for(var, start, end, step.as_deref(), next, ip)
                .map(|()| FlowStep::Next),
            Control::EndFor => self.exec_end_for(c, ip).map(back),
            Control::While(_)
            | Control::EndWhile
            | Control::Do
            | Control::EndDo(_)
            | Control::Repeat
            | Control::Until(_) => self.exec_loop(c, meta, next, ip).map(back),
            _ => self
                .exec_branch(c, ip)
                .map(|t| t.map_or(FlowStep::Next, FlowStep::Goto)),
        }
    }

    /// Open a structure whose condition decides whether its body runs (`$IF`, `$WHILE`):
    /// pushed either way, the body skipped when the condition is false.
    fn open_conditional(
        &mut self,
        e: &crate::lang::block::Expr,
        entry: impl FnOnce(bool) -> FlowEntry,
        or_skip: SkipUntil,
        ip: &impl Env,
    ) -> Res {
        let v = is_true(ip.eval(e)?);
        self.stack.push(entry(v));
        if !v {
            self.begin_skip(or_skip);
        }
        Ok(())
    }

    /// `$IF`, `$SWITCH` and their parts, `$GOTO`.
    fn exec_branch<'c>(&mut self, c: &'c Control, ip: &impl Env) -> Res<Option<&'c GotoTarget>> {
        match c {
            Control::If(e) => {
                self.open_conditional(e, |v| FlowEntry::If { taken: v }, SkipUntil::IfBranch, ip)?
            }
            Control::IfGoto(e, t) if is_true(ip.eval(e)?) => return Ok(Some(t)),
            Control::ElseIf(_) | Control::Else => match self.stack.last() {
                Some(FlowEntry::If { .. }) => self.begin_skip(SkipUntil::IfEnd),
                _ => return Err(stray(c)),
            },
            Control::EndIf => match self.stack.last() {
                Some(FlowEntry::If { .. }) => {
                    self.stack.pop();
                }
                _ => return Err(stray(c)),
            },
            Control::Switch(e) => {
                let value = ip.eval(e)?;
                self.stack.push(FlowEntry::Switch { value });
                self.begin_skip(SkipUntil::Case);
            }
            // Executing into a later case: fall through (no `$BREAK` before it).
            Control::Case(_) | Control::Default => match self.stack.last() {
                Some(FlowEntry::Switch { .. }) => {}
                _ => return Err(stray(c)),
            },
            Control::EndSwitch => match self.stack.last() {
                Some(FlowEntry::Switch { .. }) => {
                    self.stack.pop();
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
                    .stack
                    .iter()
                    .rev()
                    .find(|e| e.is_loop() || matches!(e, FlowEntry::Switch { .. }))
                    .cloned();
                match inner {
                    Some(FlowEntry::Switch { .. }) => {
                        // Close inner $IFs between the $BREAK and its switch.
                        while matches!(self.stack.last(), Some(FlowEntry::If { .. })) {
                            self.stack.pop();
                        }
                        self.begin_skip(SkipUntil::SwitchEnd);
                    }
                    Some(_) => {
                        while matches!(
                            self.stack.last(),
                            Some(FlowEntry::If { .. } | FlowEntry::Switch { .. })
                        ) {
                            self.stack.pop();
                        }
                        self.begin_skip(SkipUntil::LoopExit);
                    }
                    None => return Err(stray(c)),
                }
            }
            Control::Continue => {
                if !self.stack.iter().any(FlowEntry::is_loop) {
                    return Err(stray(c));
                }
                while matches!(
                    self.stack.last(),
                    Some(FlowEntry::If { .. } | FlowEntry::Switch { .. })
                ) {
                    self.stack.pop();
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
        next: LinePos,
        ip: &mut impl Env,
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
        let body = next;
        self.stack.push(FlowEntry::For {
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
    fn exec_end_for(&mut self, c: &Control, ip: &mut impl Env) -> Res<Option<LinePos>> {
        match self.stack.last().cloned() {
            Some(FlowEntry::For {
                var,
                end,
                step,
                body,
            }) => {
                let v = ip.var(&var).unwrap_or(0.0) + step;
                ip.set_var(var, v)?;
                if for_continues(v, end, step) {
                    return Ok(Some(body));
                } else {
                    self.stack.pop();
                }
            }
            _ => return Err(stray(c)),
        }
        Ok(None)
    }

    /// `$WHILE`, `$DO` and `$REPEAT` loops.
    fn exec_loop(
        &mut self,
        c: &Control,
        meta: LineMeta,
        next: LinePos,
        ip: &impl Env,
    ) -> Res<Option<LinePos>> {
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
            Control::EndWhile => match self.stack.last().cloned() {
                Some(FlowEntry::While { head }) => {
                    // Back to the $WHILE line, which evaluates and pushes again.
                    self.stack.pop();
                    return Ok(Some(head));
                }
                _ => return Err(stray(c)),
            },
            Control::Do | Control::Repeat => {
                let body = next;
                let entry = match c {
                    Control::Do => FlowEntry::Do { body },
                    _ => FlowEntry::Repeat { body },
                };
                self.stack.push(entry);
            }
            // `$ENDDO cond` loops while cond holds, `$UNTIL cond` until it holds.
            Control::EndDo(e) | Control::Until(e) => {
                let (body, again_if) = match (c, self.stack.last()) {
                    (Control::EndDo(_), Some(FlowEntry::Do { body })) => (*body, true),
                    (Control::Until(_), Some(FlowEntry::Repeat { body })) => (*body, false),
                    _ => return Err(stray(c)),
                };
                if is_true(ip.eval(e)?) == again_if {
                    return Ok(Some(body));
                } else {
                    self.stack.pop();
                }
            }
            _ => {}
        }
        Ok(None)
    }

    /// Continue at a label: its structural depth decides which open structures the jump
    /// leaves.
    pub(super) fn leave_to_depth(&mut self, depth: usize) {
        let top = self;
        top.stack.truncate(depth);
        while top.stack.len() < depth {
            top.stack.push(FlowEntry::If { taken: true });
        }
    }

    /// M30/M02 in the main program or M17/M29 in a subroutine with control blocks still open
    /// whose branch ran (no `$ENDIF` after a true `$IF`): the warning 20375, and the program
    /// or subroutine ends as programmed (TF5200 diagnosis ID 20375 "There are valid open
    /// control blocks at program end.", class 1: processing continues).
    pub(super) fn warn_open_flow(&self, notes: &mut Vec<Note>) {
        if let Some(innermost) = self.stack.last() {
            let (open, close) = innermost.keywords();
            notes.push(Note::Warning {
                code: codes::OPEN_CONTROL_BLOCK,
                msg: format!(
                    "{} open control block(s) at program end: {open} without its {close}",
                    self.stack.len()
                ),
            });
        }
    }

    /// The end of a file reached while a false branch (or a skipped case or loop) waits for
    /// its structure's end: an invalid control block still open, `code` for the kind of
    /// program whose `end` it is (TF5200 diagnosis IDs 21500, 21501, 21502: "There are
    /// pending invalid control blocks at local subroutine / main program / global subroutine
    /// end."). `None` when no such skip is under way.
    pub(super) fn open_invalid_block(&self, code: u32, end: &str) -> Option<DecodeError> {
        if !self.skips_structure() {
            return None;
        }
        let (open, close) = self.stack.last().map_or(("$", "end"), FlowEntry::keywords);
        Some(DecodeError::new(
            code,
            format!(
                "{} pending invalid control block(s) at {end} end: {open} whose condition is \
                 false without its {close}",
                self.stack.len().max(1)
            ),
        ))
    }
}

pub(super) fn for_continues(v: f64, end: f64, step: f64) -> bool {
    if step > 0.0 {
        v <= end + 1e-9
    } else {
        v >= end - 1e-9
    }
}
