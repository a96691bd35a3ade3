//! Errors of the receive path: bad marker configuration and file-system failures.

use std::path::PathBuf;

/// Everything that can stop a receive. Data problems inside a transfer (unsafe names,
/// a cut-off program, no start marker) are not errors: they are reported per program so
/// the rest of the transfer is still filed.
#[derive(Debug, thiserror::Error)]
pub enum DncError {
    /// MMP offers three start and three end strings; more is a configuration mistake.
    #[error("at most {max} {kind} markers are allowed, {given} given")]
    TooManyMarkers {
        kind: &'static str,
        given: usize,
        max: usize,
    },
    /// An empty marker would match every line.
    #[error("{kind} marker {index} is empty")]
    EmptyMarker { kind: &'static str, index: usize },
    /// Markers are matched per line, so a line end inside one could never match.
    #[error("{kind} marker {index} contains a line end (CR or LF)")]
    MarkerWithLineEnd { kind: &'static str, index: usize },
    /// A marker longer than the matching window of a line could never be found.
    #[error("{kind} marker {index} is longer than {max} bytes")]
    MarkerTooLong {
        kind: &'static str,
        index: usize,
        max: usize,
    },
    /// The numbering template must contain `{n}` and must name a plain file.
    #[error("bad name template `{template}`: {reason}")]
    BadTemplate {
        template: String,
        reason: &'static str,
    },
    /// The disk refused a program (full, file too large): it is lost, and the transfer stops
    /// after it, so its sender learns that the rest was not taken.
    #[error(
        "{path} lost: {source}; the rest of the transfer, from line {next_line}, was not taken"
    )]
    ProgramLost {
        path: PathBuf,
        next_line: u64,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl DncError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        DncError::Io {
            path: path.into(),
            source,
        }
    }
}
