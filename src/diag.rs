//! Diagnostics: one error or warning pinned to file, line and column, rendered like a compiler.
//!
//! Every room that reads text from outside (parameter lists, NC programs, received data)
//! reports through this one type, so `ncchannel check` prints them all the same way.

use std::fmt;
use std::path::{Path, PathBuf};

/// Longest source line a diagnostic shows under its message, bytes (an NC block is at most
/// 4000 characters). A longer line (a 5 MB "name" in a list) is not echoed: the message
/// names the place, with an [`excerpt`] of what is there.
const MAX_SOURCE_LINE_BYTES: usize = 16 * 1024;

/// Characters of outside text a message quotes at most: [`excerpt`].
pub(crate) const EXCERPT_CHARS: usize = 64;

/// `text` for a message: whole when it has at most [`EXCERPT_CHARS`] characters, else its
/// first ones, `…` and its length (`AAAA…(5000000 bytes)`), so that text from outside costs a
/// message a bounded number of bytes.
pub(crate) fn excerpt(text: &str) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(EXCERPT_CHARS) {
        None => std::borrow::Cow::Borrowed(text),
        Some((cut, _)) => {
            std::borrow::Cow::Owned(format!("{}…({} bytes)", &text[..cut], text.len()))
        }
    }
}

/// How bad a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Severity {
    Error,
    Warning,
}

/// One finding in a text file. `line` and `col` are 1-based; `col` counts characters.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    pub severity: Severity,
    pub file: PathBuf,
    pub line: usize,
    pub col: usize,
    /// ISG error number (TF5200 diagnosis list, `lang::codes`) where one exists.
    pub code: Option<u32>,
    pub message: String,
    /// The offending line's text, for the caret display (without line end).
    pub(crate) source_line: Option<String>,
}

impl Diagnostic {
    pub fn error(
        file: &Path,
        line: usize,
        col: usize,
        code: Option<u32>,
        message: impl Into<String>,
    ) -> Self {
        Diagnostic {
            severity: Severity::Error,
            file: file.to_path_buf(),
            line,
            col,
            code,
            message: message.into(),
            source_line: None,
        }
    }

    pub fn warning(
        file: &Path,
        line: usize,
        col: usize,
        code: Option<u32>,
        message: impl Into<String>,
    ) -> Self {
        Diagnostic {
            severity: Severity::Warning,
            ..Diagnostic::error(file, line, col, code, message)
        }
    }

    /// Attach the offending line so `render` can show it with a caret (not one longer than
    /// [`MAX_SOURCE_LINE_BYTES`]: the message alone then says what is wrong).
    pub(crate) fn with_source(mut self, line_text: &str) -> Self {
        let line = line_text.trim_end_matches(['\r', '\n']);
        if line.len() <= MAX_SOURCE_LINE_BYTES {
            self.source_line = Some(line.to_string());
        }
        self
    }

    /// `file:line:col: error <id>: message`, then the line and a caret under the column.
    pub fn render(&self) -> String {
        let mut out = self.to_string();
        if let Some(src) = &self.source_line {
            out.push('\n');
            out.push_str("  ");
            out.push_str(src);
            out.push('\n');
            out.push_str("  ");
            // Tabs stay tabs so the caret lines up in a terminal.
            for c in src.chars().take(self.col.saturating_sub(1)) {
                out.push(if c == '\t' { '\t' } else { ' ' });
            }
            out.push('^');
        }
        out
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let sev = match self.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        write!(
            f,
            "{}:{}:{}: {}",
            self.file.display(),
            self.line,
            self.col,
            sev
        )?;
        if let Some(code) = self.code {
            write!(f, " {code}")?;
        }
        write!(f, ": {}", self.message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn excerpts_are_bounded_and_say_the_length() {
        assert_eq!(excerpt("kenngr.swe_pos"), "kenngr.swe_pos");
        let long = "é".repeat(100);
        let e = excerpt(&long);
        assert_eq!(e, format!("{}…(200 bytes)", "é".repeat(EXCERPT_CHARS)));
    }

    #[test]
    fn render_puts_caret_under_column() {
        let d = Diagnostic::error(Path::new("a.nc"), 3, 5, Some(20131), "unknown G function")
            .with_source("N10 G999 X1\r\n");
        assert_eq!(
            d.render(),
            "a.nc:3:5: error 20131: unknown G function\n  N10 G999 X1\n      ^"
        );
    }
}
