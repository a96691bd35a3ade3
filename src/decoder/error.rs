//! A decoding error with its ISG number, and the result type of the decoder's steps.

use std::fmt;

use super::vars;

/// A decoding error: the ISG number, the message and the column when the parser knows it.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodeError {
    pub code: u32,
    pub msg: String,
    pub col: Option<u32>,
}

impl DecodeError {
    pub fn new(code: u32, msg: impl Into<String>) -> Self {
        DecodeError {
            code,
            msg: msg.into(),
            col: None,
        }
    }
    pub(crate) fn at(mut self, col: u32) -> Self {
        self.col = Some(col);
        self
    }
}

/// A parser error keeps its number, message and column.
impl From<crate::lang::SyntaxError> for DecodeError {
    fn from(e: crate::lang::SyntaxError) -> Self {
        DecodeError::new(e.code, e.message).at(e.col)
    }
}

/// Each error type that carries an ISG (or our) number converts with its number and text.
macro_rules! numbered_error {
    ($($t:ty),*) => {$(
        impl From<$t> for DecodeError {
            fn from(e: $t) -> Self {
                DecodeError::new(e.code(), e.to_string())
            }
        }
    )*};
}
numbered_error!(
    crate::source::store::StoreError,
    crate::source::cache::CacheError,
    crate::lang::EvalError
);

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {}", self.code, self.msg)
    }
}

/// The result of a decoder step: an error carries its ISG number.
pub(crate) type Res<T = ()> = Result<T, DecodeError>;

/// The variable store's refusal with its number (20967, 21928, 20974, `codes::EVAL_UNDEFINED`).
pub(super) fn var_error(e: vars::VarError) -> DecodeError {
    DecodeError::new(e.code(), e.to_string())
}
