//! The progress bar of long commands (`soak`, `stream`): one look for all, drawn by indicatif
//! on stderr only when it is a terminal, so a log or a pipe gets no progress line.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A bar of `len` steps drawn with indicatif's `template` (`{bar:30}` is the bar itself).
pub(crate) fn bar(len: u64, template: &str) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template(template)
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("#>."),
    );
    bar
}
