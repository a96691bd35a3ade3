//! Control flow as a forward skip machine: `$IF`, `$SWITCH`, loops and `$GOTO`, line by line.
//!
//! Nothing here ever looks ahead in the program text: a false branch, a non-matching `$CASE`
//! or a forward jump only sets a skip state, and the lines that follow are examined one by one
//! as they arrive — which is what makes these statements work across stream packets.

use crate::lang::block::{Control, GotoTarget};

use super::frame::LinePos;
use super::vars::VarSlot;

/// One open control structure of a frame.
#[derive(Debug, Clone, PartialEq)]
pub enum FlowEntry {
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
    pub fn is_loop(&self) -> bool {
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
pub enum SkipUntil {
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
    /// A `%L name` section met while running the main program: up to its M17/M29.
    LocalSubroutine,
}

/// Skip state: what we look for and how deep inside skipped structures we are.
#[derive(Debug, Clone, PartialEq)]
pub struct Skip {
    pub until: SkipUntil,
    /// Structures opened inside the skipped region and not yet closed.
    pub depth: u32,
}

impl Skip {
    pub fn new(until: SkipUntil) -> Self {
        Skip { until, depth: 0 }
    }
}

/// How a `$` statement changes nesting, for skipping and for the label index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Nesting {
    Open,
    Close,
    Neither,
}

pub fn nesting(c: &Control) -> Nesting {
    match c {
        Control::If(_)
        | Control::Switch(_)
        | Control::For { .. }
        | Control::While(_)
        | Control::Do
        | Control::Repeat => Nesting::Open,
        Control::EndIf
        | Control::EndSwitch
        | Control::EndFor
        | Control::EndWhile
        | Control::EndDo(_)
        | Control::Until(_) => Nesting::Close,
        _ => Nesting::Neither,
    }
}

/// Statements that are loops: not allowed in a stream (21478).
pub fn is_loop_statement(c: &Control) -> bool {
    matches!(
        c,
        Control::For { .. }
            | Control::EndFor
            | Control::While(_)
            | Control::EndWhile
            | Control::Do
            | Control::EndDo(_)
            | Control::Repeat
            | Control::Until(_)
    )
}

/// Whether `c` closes the loop `e`.
pub fn closes_loop(e: &FlowEntry, c: &Control) -> bool {
    matches!(
        (e, c),
        (FlowEntry::For { .. }, Control::EndFor)
            | (FlowEntry::While { .. }, Control::EndWhile)
            | (FlowEntry::Do { .. }, Control::EndDo(_))
            | (FlowEntry::Repeat { .. }, Control::Until(_))
    )
}
