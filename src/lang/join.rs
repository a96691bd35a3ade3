//! `\` at the end of a line: the block goes on in the next line (TF5200 programming manual,
//! "Line break in NC block '\'"). DIN blocks, `L CYCLE [...]` parameter lists and `#VAR`
//! array initialisers may be written over several lines this way; a continuation line may
//! start with a block number of its own ("N20 X100 Y150"), which is not part of the block.
//!
//! [`continuation`] tells whether a line is continued; a [`Joiner`] collects the lines of one
//! block into one text, as `check` and the decoder (files and stream packets alike) both do,
//! and maps a column of that text back to the line and column it was written at.

use super::codes::MAX_BLOCK_CHARS;
use super::parse::gap;

/// Byte index of the `\` that continues `line`, if it is continued: the last character of the
/// line outside comments and quoted text. Blanks and comments may follow it (`X10 \ (note)`);
/// a `\` inside a comment (`X10 ; note \`) continues nothing.
pub fn continuation(line: &str) -> Option<usize> {
    let b = line.as_bytes();
    // Most lines have no backslash at all: one word-at-a-time search answers for them.
    if !super::bytes::has_byte(b, b'\\') {
        return None;
    }
    let mut last: Option<usize> = None;
    let mut depth = 0usize;
    let mut quoted = false;
    for (k, &c) in b.iter().enumerate() {
        if quoted {
            quoted = c != b'"';
            last = Some(k);
            continue;
        }
        if depth > 0 {
            match c {
                b'(' => depth += 1,
                b')' => depth -= 1,
                _ => {}
            }
            continue;
        }
        match c {
            b';' => break,
            b'(' => depth = 1,
            b' ' | b'\t' | b'\r' | b'\n' => {}
            b'"' => {
                quoted = true;
                last = Some(k);
            }
            _ => last = Some(k),
        }
    }
    last.filter(|&k| b[k] == b'\\')
}

/// One block written over several lines, joined. Each `\` becomes a blank and the lines'
/// text keeps its columns, so a column of the joined text maps back exactly.
#[derive(Debug, Default, Clone)]
pub struct Joiner {
    text: String,
    /// Per line that added text: the joined text's column (1-based, characters) where it
    /// starts and the line's distance from the block's first line.
    parts: Vec<(u32, u32)>,
    /// Characters in `text`.
    chars: usize,
    /// Lines taken so far, blank and comment lines included.
    lines: u32,
    /// The last line taken ended with `\`: the block is not complete.
    open: bool,
}

impl Joiner {
    /// A block has begun and waits for its next line.
    pub(crate) fn is_open(&self) -> bool {
        self.open
    }

    /// Lines the block has taken so far.
    pub fn lines(&self) -> u32 {
        self.lines
    }

    /// The joined text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Take the next line (without its line end). Returns true when the block is complete:
    /// the line did not end with `\`. A complete block is forgotten at the next call. Lines
    /// that are blank or comments only, between continued lines, add nothing. Text beyond
    /// [`MAX_BLOCK_CHARS`] is not kept: the parser refuses the block at that column anyway.
    pub fn push(&mut self, line: &str) -> bool {
        if !self.open {
            self.text.clear();
            self.parts.clear();
            self.chars = 0;
            self.lines = 0;
        }
        let first = self.lines == 0;
        self.lines = self.lines.saturating_add(1);
        if !first && gap(line).is_empty() {
            self.open = true;
            return false;
        }
        let cont = continuation(line);
        self.open = cont.is_some();
        if self.chars <= MAX_BLOCK_CHARS {
            let body = cont.map_or(line, |k| &line[..k]);
            let start = self.text.len();
            let (numbered, rest) = if first { (0, body) } else { block_number(body) };
            self.parts.push((self.chars as u32 + 1, self.lines - 1));
            self.text.extend(std::iter::repeat_n(' ', numbered));
            self.text.push_str(rest);
            if cont.is_some() {
                self.text.push(' ');
            }
            self.chars += self.text[start..].chars().count();
        }
        !self.open
    }

    /// End the block with what it has (the text ended in a continued line); the next line
    /// starts a new block.
    pub fn close(&mut self) {
        self.open = false;
    }

    /// The line (counted from the block's first, 0-based) and column of column `col` of the
    /// joined text.
    pub fn position(&self, col: u32) -> (u32, u32) {
        let k = self.parts.partition_point(|&(start, _)| start <= col);
        match k.checked_sub(1).and_then(|k| self.parts.get(k)) {
            Some(&(start, line)) => (line, col - start + 1),
            None => (0, col),
        }
    }
}

/// A continuation line's own block number (`N20 X100`: blanks, `N`, digits, no `:`): its
/// length in characters, and the rest of the line.
fn block_number(line: &str) -> (usize, &str) {
    let t = line.trim_start_matches([' ', '\t']);
    let lead = line.len() - t.len();
    let Some(d) = t.strip_prefix(['N', 'n']) else {
        return (0, line);
    };
    let digits = d.bytes().take_while(u8::is_ascii_digit).count();
    if digits == 0 || d[digits..].starts_with(':') {
        return (0, line);
    }
    let len = lead + 1 + digits;
    (len, &line[len..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_backslash_outside_comments_and_quotes_continues() {
        assert_eq!(continuation("G01 X10 \\"), Some(8));
        assert_eq!(continuation("G01 X10\\  (more) ; note"), Some(7));
        assert_eq!(continuation("G01 X10 ; note \\"), None);
        assert_eq!(continuation("G01 X10 (note \\)"), None);
        assert_eq!(continuation("L C:\\ISG\\test.nc"), None);
        assert_eq!(continuation("#MSG [\"a \\\"]"), None);
        assert_eq!(continuation("N10 G01 X12.345"), None);
    }

    #[test]
    fn lines_join_with_columns_kept() {
        let mut j = Joiner::default();
        assert!(!j.push("N10 G01 \\"));
        assert!(j.is_open());
        assert!(!j.push("   ; a comment line"));
        assert!(!j.push(""));
        assert!(j.push("N20 X100 Y150"));
        assert_eq!(j.text(), "N10 G01      X100 Y150");
        assert_eq!(j.lines(), 4);
        assert_eq!(j.position(5), (0, 5));
        assert_eq!(j.position(9), (0, 9));
        assert_eq!(j.position(14), (3, 5));
        // The next line starts a new block.
        assert!(j.push("X1"));
        assert_eq!((j.text(), j.lines()), ("X1", 1));
    }

    #[test]
    fn a_joined_block_keeps_little_more_than_the_block_limit() {
        let mut j = Joiner::default();
        let line = format!("{} \\", "X1".repeat(500));
        for _ in 0..100 {
            assert!(!j.push(&line));
        }
        assert!(j.push("Y1"));
        assert!(j.text().len() <= MAX_BLOCK_CHARS + line.len() + 1);
        let (line_no, col) = j.position(MAX_BLOCK_CHARS as u32 + 1);
        assert_eq!((line_no, col), (3, 4001 - 3 * 1002));
    }
}
