//! The kernel's error text file (`err_text_version_eng.txt`, named by the start-up list's
//! `error_text_of_id`, P-STUP-00168): one line per error id, `<id> TAB <text>`. Where a
//! configuration names one, a channel reports these texts for those ids.

use std::collections::HashMap;
use std::path::Path;

use super::list::{file_error, read_list_text};
use crate::diag::Diagnostic;

/// Longest text kept per id; the kernel's are one line of well under 200 characters.
pub(crate) const MAX_TEXT_CHARS: usize = 512;

/// Error texts by ISG error id.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ErrorTexts {
    texts: HashMap<u32, String>,
}

impl ErrorTexts {
    /// The text of `id`, if the file has one.
    pub fn get(&self, id: u32) -> Option<&str> {
        self.texts.get(&id).map(String::as_str)
    }

    pub fn len(&self) -> usize {
        self.texts.len()
    }

    pub fn is_empty(&self) -> bool {
        self.texts.is_empty()
    }

    /// Parse the file's text: `<id>` TAB (or blanks) `<text>` lines. Lines that do not start
    /// with an id (headers, comments, blank lines) are skipped, as the kernel skips them;
    /// a later line for the same id wins.
    pub fn parse(text: &str) -> Self {
        let mut texts = HashMap::new();
        for line in text.lines() {
            let line = line.trim_end_matches('\r');
            let digits = line.bytes().take_while(u8::is_ascii_digit).count();
            if digits == 0 || digits > 10 {
                continue;
            }
            let (id, rest) = line.split_at(digits);
            if !rest.starts_with(['\t', ' ']) {
                continue;
            }
            let (Ok(id), t) = (id.parse::<u32>(), rest.trim()) else {
                continue;
            };
            if t.is_empty() {
                continue;
            }
            texts.insert(id, t.chars().take(MAX_TEXT_CHARS).collect());
        }
        ErrorTexts { texts }
    }
}

/// Read an error text file (same size bound and Latin-1 rule as the lists).
pub(crate) fn read_error_texts(path: &Path) -> Result<ErrorTexts, Diagnostic> {
    let text = read_list_text(path)?;
    let t = ErrorTexts::parse(&text);
    if t.is_empty() {
        return Err(file_error(
            path,
            "error text file holds no `<id> TAB <text>` line",
        ));
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn id_tab_text_lines() {
        let t = ErrorTexts::parse(
            "Error texts V3.1\r\n21897\tAxis position is out of permissible range.\r\n\
             20000 \tfirst\n20000\tsecond\n123abc\tno\n99\n",
        );
        assert_eq!(t.len(), 2);
        assert_eq!(
            t.get(21897),
            Some("Axis position is out of permissible range.")
        );
        assert_eq!(t.get(20000), Some("second"));
        assert_eq!(t.get(99), None);
    }
}
