//! The NC language: one NC line → `Block`, expressions and their evaluation, and a static
//! checker for whole programs.
//!
//! Everything here is pure: no I/O, no state between lines. The decoder keeps the
//! `#COMMENT` and `#VAR` block state itself and asks [`is_comment_end`] /
//! [`parse_var_declaration`] for lines inside them.

pub(crate) mod block;
mod bytes;
pub mod check;
pub mod codes;
pub(crate) mod control;
pub mod dialect;
mod display;
pub(crate) mod error;
pub(crate) mod eval;
pub mod expr;
pub mod gcall;
pub(crate) mod join;
pub mod msg;
mod number;
pub mod parse;
pub mod range;
pub(crate) mod transform;

pub use block::*;
pub use check::{check_program, check_program_counted, ProgramDiag, MAX_PROGRAM_DIAGS};
pub use error::SyntaxError;
pub use eval::{
    case_matches, eval, eval_value, is_true, resolve, AxisId, EvalError, ToolFieldId, Val, VarKey,
    Vars,
};
pub use expr::parse_expr;
pub use join::{continuation, Joiner};
pub use parse::{
    is_blank_line, is_comment_end, parse_block, parse_block_reusing, parse_var_declaration,
    parse_var_line, VarLine, ITEM_LIST_CAPACITY,
};
