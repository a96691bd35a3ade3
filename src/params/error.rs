//! `ParamError`: why the parameters could not be loaded, as diagnostics pinned to file, line
//! and column so `ncchannel check` and `run` print them the same way.

use crate::diag::{Diagnostic, Severity};

/// Loading the parameters failed; nothing may start.
#[derive(Debug, thiserror::Error)]
pub enum ParamError {
    /// A file could not be read at all: missing, unreadable, too large.
    #[error("{}", .0.render())]
    File(Diagnostic),
    /// One or more entries are malformed or implausible. Holds every diagnostic found,
    /// errors and warnings, in the order found, so the user fixes all of them in one go.
    #[error("{}", render_all(.0))]
    Invalid(Vec<Diagnostic>),
}

impl ParamError {
    /// Every diagnostic this error carries.
    pub fn diagnostics(&self) -> Vec<Diagnostic> {
        match self {
            ParamError::File(d) => vec![d.clone()],
            ParamError::Invalid(ds) => ds.clone(),
        }
    }

    /// Only the errors (not the warnings gathered on the way).
    pub fn errors(&self) -> Vec<Diagnostic> {
        self.diagnostics()
            .into_iter()
            .filter(|d| d.severity == Severity::Error)
            .collect()
    }
}

fn render_all(ds: &[Diagnostic]) -> String {
    ds.iter()
        .map(Diagnostic::render)
        .collect::<Vec<_>>()
        .join("\n")
}
