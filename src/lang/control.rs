//! Facts about `$` statements and labels that depend only on their text: how a statement
//! changes nesting, which statements are loops, how a label or jump target is written, and
//! whether a block ends the program (TF5200 programming manual, "Control structures").

use super::block::{Block, Body, Control, GotoTarget, Item, Label, Value};
use super::range::whole_u32 as whole;

/// How a `$` statement changes nesting, for skipping and for the label index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Nesting {
    Open,
    Close,
    Neither,
}

pub(crate) fn nesting(c: &Control) -> Nesting {
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

/// Statements that are loops: not allowed in a stream (codes::STREAM_LOOP).
pub(crate) fn is_loop_statement(c: &Control) -> bool {
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

pub(crate) fn items_have_m(items: &[Item], codes: &[u32]) -> bool {
    items.iter().any(|i| match i {
        Item::Word(w) if w.letter == b'M' => match w.value {
            Value::Num(v) => whole(v).is_some_and(|m| codes.contains(&m)),
            Value::Expr(_) => false,
        },
        _ => false,
    })
}

pub(crate) fn block_ends_program(b: &Block) -> bool {
    matches!(&b.body, Body::Items(items) if items_have_m(items, &[2, 30]))
}

pub(crate) fn goto_label(t: &GotoTarget) -> Label {
    match t {
        GotoTarget::Number(n) => Label::Number(*n),
        GotoTarget::Name(s) => Label::Name(s.clone()),
    }
}

pub(crate) fn label_matches(l: &Label, t: &GotoTarget) -> bool {
    *l == goto_label(t)
}

pub(crate) fn label_text(l: &Label) -> String {
    match l {
        Label::Number(n) => format!("N{n}"),
        Label::Name(s) => format!("[{s}]"),
    }
}

pub(crate) fn goto_text(t: &GotoTarget) -> String {
    label_text(&goto_label(t))
}

pub(crate) fn control_name(c: &Control) -> &'static str {
    match c {
        Control::If(_) => "$IF",
        Control::IfGoto(..) => "$IF … $GOTO",
        Control::ElseIf(_) => "$ELSEIF",
        Control::Else => "$ELSE",
        Control::EndIf => "$ENDIF",
        Control::Switch(_) => "$SWITCH",
        Control::Case(_) => "$CASE",
        Control::Default => "$DEFAULT",
        Control::Break => "$BREAK",
        Control::EndSwitch => "$ENDSWITCH",
        Control::For { .. } => "$FOR",
        Control::EndFor => "$ENDFOR",
        Control::While(_) => "$WHILE",
        Control::EndWhile => "$ENDWHILE",
        Control::Do => "$DO",
        Control::EndDo(_) => "$ENDDO",
        Control::Repeat => "$REPEAT",
        Control::Until(_) => "$UNTIL",
        Control::Continue => "$CONTINUE",
        Control::Goto(_) => "$GOTO",
    }
}
