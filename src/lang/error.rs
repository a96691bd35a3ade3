//! The parser's error: an ISG error number and the column of the offending token.

/// A syntax error in one NC line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("error {code} at column {col}: {message}")]
pub struct SyntaxError {
    /// ISG error number (`super::codes`), e.g. 20131 unknown G function.
    pub code: u32,
    /// 1-based character column of the offending token.
    pub col: u32,
    pub message: String,
}

impl SyntaxError {
    pub fn new(code: u32, col: u32, message: impl Into<String>) -> Self {
        SyntaxError {
            code,
            col,
            message: message.into(),
        }
    }
}
