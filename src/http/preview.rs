//! The whole-program preview as the page gets it: a program's recorded path, and the
//! function that computes one (`cli/preview.rs` runs the program on a private copy of the
//! channels; the web view only serves its answer).

use std::sync::Arc;

use serde::Serialize;

use super::path::PathUpdate;

/// Channel time a preview runs at most, s: a longer program's preview is cut there (and says
/// so).
pub const PREVIEW_MAX_S: f64 = 600.0;

/// A preview of one program on one channel.
#[derive(Debug, Serialize)]
pub struct Preview {
    pub program: String,
    #[serde(flatten)]
    pub path: PathUpdate,
    /// The program ran to its end (else it was cut at [`PREVIEW_MAX_S`] or stopped by an
    /// error, given in `error`).
    pub complete: bool,
    /// Channel time the program took, s (to the cut).
    pub seconds: f64,
    pub error: Option<String>,
}

/// What computes a preview: channel number and program name to the preview, or the reason.
pub type Previewer = Arc<dyn Fn(u16, &str) -> Result<Preview, String> + Send + Sync>;
