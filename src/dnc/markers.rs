//! Start and end marker strings, the three split modes, and matching a marker in one line.
//!
//! Markers are matched per line, **anywhere in the line** by default: MMP's description speaks
//! of "the lines in which the marker string was recognised", and the usual end markers (`M30`,
//! `M02`, `M17`) stand after a block number (`N999 M30`), not at the line start. A marker
//! matches byte for byte (case-sensitive), so `M30` also matches inside `M300`: choose markers
//! that cannot occur elsewhere, or ask for [`Anchor::LineStart`] (`--at-line-start`).
//!
//! Only the first [`LINE_WINDOW`] bytes of a line are searched, so a line of any length costs
//! bounded memory; a marker that would end beyond that window is not seen.

use memchr::memmem;

use super::error::DncError;

/// MMP offers three start strings and three end strings.
pub const MAX_MARKERS: usize = 3;

/// How many bytes at the head of a line are searched for markers and name lines. NC blocks
/// are at most 4000 characters (TF5200 programming manual), so real lines always fit.
pub const LINE_WINDOW: usize = 64 * 1024;

/// Which markers were configured decides how the data is cut (SINUMERIK "Manage MyPrograms").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// A start line opens a program; the program runs to the next start line or the end of data.
    StartOnly,
    /// From the data start (or after an end line) up to and including the next end line.
    /// Also the mode with no markers at all: the whole transfer is one program, split only by
    /// SINUMERIK `%_N_` control lines.
    EndOnly,
    /// From a start line to an end line, both included; the search alternates between the two.
    StartEnd,
}

/// Where in a line a marker may stand.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Anchor {
    /// Anywhere in the line (MMP behaviour, the default).
    #[default]
    Anywhere,
    /// Only at the very beginning of the line.
    LineStart,
}

/// One marker string with its precomputed substring searcher.
#[derive(Debug, Clone)]
pub(crate) struct Marker {
    bytes: Vec<u8>,
    finder: memmem::Finder<'static>,
}

/// The configured start and end strings.
#[derive(Debug, Clone)]
pub struct Markers {
    pub(crate) start: Vec<Marker>,
    pub(crate) end: Vec<Marker>,
    pub(crate) anchor: Anchor,
}

impl Markers {
    /// Up to three start and three end strings; none may be empty, contain CR or LF, or be
    /// longer than the line window.
    pub fn new<S, E>(start: S, end: E, anchor: Anchor) -> Result<Self, DncError>
    where
        S: IntoIterator,
        S::Item: AsRef<[u8]>,
        E: IntoIterator,
        E::Item: AsRef<[u8]>,
    {
        Ok(Markers {
            start: build("start", start)?,
            end: build("end", end)?,
            anchor,
        })
    }

    /// The split mode these markers select.
    pub fn mode(&self) -> Mode {
        match (self.start.is_empty(), self.end.is_empty()) {
            (false, true) => Mode::StartOnly,
            (false, false) => Mode::StartEnd,
            (true, _) => Mode::EndOnly,
        }
    }

    pub fn anchor(&self) -> Anchor {
        self.anchor
    }

    /// Does any start marker stand in this line head?
    pub(crate) fn start_in(&self, head: &[u8]) -> bool {
        any_in(&self.start, self.anchor, head)
    }

    /// Does any end marker stand in this line head?
    pub(crate) fn end_in(&self, head: &[u8]) -> bool {
        any_in(&self.end, self.anchor, head)
    }
}

fn build<I>(kind: &'static str, list: I) -> Result<Vec<Marker>, DncError>
where
    I: IntoIterator,
    I::Item: AsRef<[u8]>,
{
    let mut out = Vec::new();
    for (i, m) in list.into_iter().enumerate() {
        let index = i + 1;
        if index > MAX_MARKERS {
            // Count the rest only for the message.
            return Err(DncError::TooManyMarkers {
                kind,
                given: index,
                max: MAX_MARKERS,
            });
        }
        let bytes = m.as_ref();
        if bytes.is_empty() {
            return Err(DncError::EmptyMarker { kind, index });
        }
        if bytes.iter().any(|&b| b == b'\r' || b == b'\n') {
            return Err(DncError::MarkerWithLineEnd { kind, index });
        }
        if bytes.len() > LINE_WINDOW {
            return Err(DncError::MarkerTooLong {
                kind,
                index,
                max: LINE_WINDOW,
            });
        }
        out.push(Marker {
            bytes: bytes.to_vec(),
            finder: memmem::Finder::new(bytes).into_owned(),
        });
    }
    Ok(out)
}

fn any_in(markers: &[Marker], anchor: Anchor, head: &[u8]) -> bool {
    markers.iter().any(|m| match anchor {
        Anchor::LineStart => head.starts_with(&m.bytes),
        Anchor::Anywhere => m.finder.find(head).is_some(),
    })
}

/// Marker search over a whole chunk instead of line by line: each marker's next occurrence is
/// found once with a vectorised search and reused for every line before it, which keeps the
/// splitter at memory speed when lines are short. Gives exactly the answer of [`any_in`] on
/// the line head.
pub(crate) struct ChunkScan {
    /// Offset in the chunk of each marker's next occurrence at or after the last line that
    /// asked; `usize::MAX` when the rest of the chunk holds none.
    next: [usize; MAX_MARKERS],
    valid: [bool; MAX_MARKERS],
}

impl ChunkScan {
    pub(crate) fn new() -> Self {
        ChunkScan {
            next: [usize::MAX; MAX_MARKERS],
            valid: [false; MAX_MARKERS],
        }
    }

    /// Is one of `markers` inside `buf[line_start..head_end]`?
    pub(crate) fn hit(
        &mut self,
        markers: &[Marker],
        anchor: Anchor,
        buf: &[u8],
        line_start: usize,
        head_end: usize,
    ) -> bool {
        if anchor == Anchor::LineStart {
            return any_in(markers, anchor, &buf[line_start..head_end]);
        }
        for (i, m) in markers.iter().enumerate() {
            if !self.valid[i] || self.next[i] < line_start {
                self.next[i] = m
                    .finder
                    .find(&buf[line_start..])
                    .map_or(usize::MAX, |p| p + line_start);
                self.valid[i] = true;
            }
            let at = self.next[i];
            if at != usize::MAX && at + m.bytes.len() <= head_end {
                return true;
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mode_follows_the_configured_markers() {
        let none: [&str; 0] = [];
        assert_eq!(
            Markers::new(["%"], none, Anchor::Anywhere).unwrap().mode(),
            Mode::StartOnly
        );
        assert_eq!(
            Markers::new(none, ["M30"], Anchor::Anywhere)
                .unwrap()
                .mode(),
            Mode::EndOnly
        );
        assert_eq!(
            Markers::new(["%"], ["M30"], Anchor::Anywhere)
                .unwrap()
                .mode(),
            Mode::StartEnd
        );
        assert_eq!(
            Markers::new(none, none, Anchor::Anywhere).unwrap().mode(),
            Mode::EndOnly
        );
    }

    #[test]
    fn bad_markers_are_refused() {
        let none: [&str; 0] = [];
        assert!(matches!(
            Markers::new(["a", "b", "c", "d"], none, Anchor::Anywhere),
            Err(DncError::TooManyMarkers { given: 4, .. })
        ));
        assert!(matches!(
            Markers::new(none, ["M30", ""], Anchor::Anywhere),
            Err(DncError::EmptyMarker { index: 2, .. })
        ));
        assert!(matches!(
            Markers::new(["%\n"], none, Anchor::Anywhere),
            Err(DncError::MarkerWithLineEnd { .. })
        ));
    }

    #[test]
    fn anywhere_and_line_start() {
        let none: [&str; 0] = [];
        let any = Markers::new(none, ["M30"], Anchor::Anywhere).unwrap();
        let start = Markers::new(none, ["M30"], Anchor::LineStart).unwrap();
        assert!(any.end_in(b"N90 M30\n"));
        assert!(!start.end_in(b"N90 M30\n"));
        assert!(start.end_in(b"M30\n"));
    }

    #[test]
    fn chunk_scan_agrees_with_per_line_search() {
        let none: [&str; 0] = [];
        let m = Markers::new(none, ["M30", "M2 ", "%"], Anchor::Anywhere).unwrap();
        let buf = b"N1 G0\nN2 M30\nM2 \r\nx\n%%\nM3\nM30";
        let mut scan = ChunkScan::new();
        let mut pos = 0;
        while pos < buf.len() {
            let end = buf[pos..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(buf.len(), |i| pos + i + 1);
            // Short windows too: the answer must match the head-only search.
            for w in [end - pos, 2, 3] {
                let he = (pos + w).min(end);
                let mut fresh = ChunkScan::new();
                assert_eq!(
                    fresh.hit(&m.end, m.anchor, buf, pos, he),
                    m.end_in(&buf[pos..he]),
                    "line at {pos} window {w}"
                );
            }
            assert_eq!(
                scan.hit(&m.end, m.anchor, buf, pos, end),
                m.end_in(&buf[pos..end])
            );
            pos = end;
        }
    }
}
