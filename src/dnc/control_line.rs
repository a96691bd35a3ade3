//! Name lines in received data: SINUMERIK `%_N_<NAME>_<TYPE>` and `;$PATH=…` control lines
//! and the ISG program start `%name`, turned into a safe file name inside the program directory.
//!
//! Every name comes from outside, so a name is accepted only when it is one plain path
//! component (letters, digits, `_`, `-`, `.`, not starting with `.`, at most
//! [`MAX_NAME_LEN`] bytes). Anything else (`..`, `/`, `\`, a drive letter, NUL, spaces) is
//! refused and the program falls back to the numbered name, with a note for the operator.

/// Longest program or workpiece name accepted from the data.
pub(crate) const MAX_NAME_LEN: usize = 100;

/// Rejected names kept per program for the operator message; further ones are dropped.
const MAX_REJECTED: usize = 4;

/// Longest excerpt of a rejected name kept for the message.
const REJECTED_EXCERPT: usize = 60;

/// A SINUMERIK program name and type from `%_N_<NAME>_<TYPE>`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SinumerikName {
    /// Program name as sent, e.g. `PART_1`.
    pub name: String,
    /// File type as sent, e.g. `MPF` (main program) or `SPF` (subprogram); `None` when the
    /// line carries no type.
    pub kind: Option<String>,
}

/// What a refused name from the data would have named.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NameKind {
    /// The program's own file name (`%_N_<NAME>_<TYPE>`, ISG `%name`): the program is
    /// numbered instead, unless another name line of it names it.
    Program,
    /// The workpiece folder (`;$PATH=/_N_WKS_DIR/_N_<WP>_WPD`): the program is filed at the top
    /// of the program directory under its own name, as `/_N_MPF_DIR` would file it.
    Workpiece,
}

/// A name from the data refused as unsafe: what it named, and an excerpt (lossy UTF-8,
/// escaped) for the operator message.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RejectedName {
    pub kind: NameKind,
    pub text: String,
}

/// What the name lines of one program said.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct NameInfo {
    /// From the first `%_N_` line of the program.
    pub(crate) sinumerik: Option<SinumerikName>,
    /// Workpiece from the first `;$PATH=` line, `SHAFT` for `/_N_WKS_DIR/_N_SHAFT_WPD`.
    pub workpiece: Option<String>,
    /// From the first ISG `%name` line (not `%L`, not `%_N_`).
    pub isg: Option<String>,
    /// Names refused as unsafe, for the operator message.
    pub rejected: Vec<RejectedName>,
    path_seen: bool,
    /// A `%_N_` line was seen, accepted or refused: the next one starts another program.
    sinumerik_seen: bool,
}

/// Does this line begin a SINUMERIK program (`%_N_…`)? Such a line inside an already named
/// program starts the next file: MMP interprets every control line in the data.
pub(crate) fn is_sinumerik_start(head: &[u8]) -> bool {
    head.starts_with(b"%_N_")
}

/// Could this line be a name line at all? A one-byte test so ordinary blocks cost nothing.
#[inline]
pub(crate) fn may_name(head: &[u8]) -> bool {
    matches!(head.first(), Some(b'%') | Some(b';'))
}

impl NameInfo {
    /// Record what a line of this program says about its name; first of each kind wins.
    pub fn note(&mut self, head: &[u8]) {
        let line = trim_line(head);
        if let Some(rest) = line.strip_prefix(b"%_N_") {
            if !self.sinumerik_seen {
                self.sinumerik_seen = true;
                match parse_sinumerik(rest) {
                    Some(n) => self.sinumerik = Some(n),
                    None => self.reject(NameKind::Program, rest),
                }
            }
        } else if let Some(path) = line.strip_prefix(b";$PATH=") {
            if !self.path_seen {
                self.path_seen = true;
                if let Some(wp) = workpiece_of(path) {
                    match safe_name(wp) {
                        Some(w) => self.workpiece = Some(w),
                        None => self.reject(NameKind::Workpiece, wp),
                    }
                }
            }
        } else if let Some(rest) = line.strip_prefix(b"%") {
            if self.isg.is_none() {
                let rest = trim_start(rest);
                // `%L name` is a local subroutine inside the file, not the file's name.
                let local = rest.len() > 1
                    && (rest[0] == b'L' || rest[0] == b'l')
                    && (rest[1] == b' ' || rest[1] == b'\t');
                let word_end = rest
                    .iter()
                    .position(|&b| b == b' ' || b == b'\t' || b == b'(' || b == b';')
                    .unwrap_or(rest.len());
                let word = &rest[..word_end];
                if !local && !word.is_empty() {
                    match safe_name(word) {
                        Some(w) => self.isg = Some(w),
                        None => self.reject(NameKind::Program, word),
                    }
                }
            }
        }
    }

    /// Did this program have a `%_N_` line, even one whose name was refused? Then a further
    /// `%_N_` line begins the next program: a refused name must never merge its program into
    /// the next one's file.
    pub(crate) fn has_sinumerik_line(&self) -> bool {
        self.sinumerik_seen
    }

    /// The file name inside the program directory, with the workpiece directory when the
    /// data named one: `(Some("SHAFT.wpd"), "PART1.mpf")`. `None`: number the file.
    pub fn file_name(&self) -> Option<(Option<String>, String)> {
        if let Some(s) = &self.sinumerik {
            let ext = match s.kind.as_deref() {
                Some(k) => k.to_ascii_lowercase(),
                None => "nc".to_string(),
            };
            let dir = self.workpiece.as_ref().map(|w| format!("{w}.wpd"));
            return Some((dir, format!("{}.{ext}", s.name)));
        }
        self.isg.as_ref().map(|n| {
            if n.contains('.') {
                (None, n.clone())
            } else {
                (None, format!("{n}.nc"))
            }
        })
    }

    fn reject(&mut self, kind: NameKind, raw: &[u8]) {
        if self.rejected.len() < MAX_REJECTED {
            let cut = &raw[..raw.len().min(REJECTED_EXCERPT)];
            self.rejected.push(RejectedName {
                kind,
                text: String::from_utf8_lossy(cut).escape_debug().to_string(),
            });
        }
    }
}

/// `PART_1_MPF` → name `PART_1`, type `MPF`. The type is the part after the last `_` when it
/// is 1–8 letters or digits; otherwise the whole text is the name.
fn parse_sinumerik(rest: &[u8]) -> Option<SinumerikName> {
    let (name, kind) = match rest.iter().rposition(|&b| b == b'_') {
        Some(i)
            if i > 0
                && (1..=8).contains(&(rest.len() - i - 1))
                && rest[i + 1..].iter().all(u8::is_ascii_alphanumeric) =>
        {
            (&rest[..i], Some(&rest[i + 1..]))
        }
        _ => (rest, None),
    };
    Some(SinumerikName {
        name: safe_name(name)?,
        kind: kind.map(|k| String::from_utf8_lossy(k).into_owned()),
    })
}

/// `/_N_WKS_DIR/_N_SHAFT_WPD` → `SHAFT`; paths without a `_WPD` component (`/_N_MPF_DIR`,
/// `/_N_SPF_DIR`) file the program at the top of the program directory.
fn workpiece_of(path: &[u8]) -> Option<&[u8]> {
    path.split(|&b| b == b'/')
        .filter_map(|c| c.strip_prefix(b"_N_")?.strip_suffix(b"_WPD"))
        .next_back()
}

/// One plain path component or nothing.
pub(crate) fn safe_name(raw: &[u8]) -> Option<String> {
    let ok = !raw.is_empty()
        && raw.len() <= MAX_NAME_LEN
        && raw[0] != b'.'
        && raw
            .iter()
            .all(|&b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-' || b == b'.');
    if ok {
        // All ASCII, so this cannot fail.
        std::str::from_utf8(raw).ok().map(str::to_string)
    } else {
        None
    }
}

fn trim_line(head: &[u8]) -> &[u8] {
    let end = head
        .iter()
        .rposition(|&b| !matches!(b, b'\r' | b'\n' | b' ' | b'\t'))
        .map_or(0, |i| i + 1);
    &head[..end]
}

fn trim_start(s: &[u8]) -> &[u8] {
    let start = s
        .iter()
        .position(|&b| b != b' ' && b != b'\t')
        .unwrap_or(s.len());
    &s[start..]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn info(lines: &[&str]) -> NameInfo {
        let mut n = NameInfo::default();
        for l in lines {
            n.note(l.as_bytes());
        }
        n
    }

    #[test]
    fn sinumerik_main_and_subprogram() {
        let n = info(&["%_N_PART_1_MPF\r\n", ";$PATH=/_N_WKS_DIR/_N_SHAFT_WPD\r\n"]);
        assert_eq!(
            n.file_name(),
            Some((Some("SHAFT.wpd".into()), "PART_1.mpf".into()))
        );
        let n = info(&["%_N_CONTOUR_SPF\n", ";$PATH=/_N_SPF_DIR\n"]);
        assert_eq!(n.file_name(), Some((None, "CONTOUR.spf".into())));
        let n = info(&["%_N_TOOLS_INI\n"]);
        assert_eq!(n.file_name(), Some((None, "TOOLS.ini".into())));
    }

    #[test]
    fn isg_program_start_names_the_file() {
        assert_eq!(
            info(&["%demo\n"]).file_name(),
            Some((None, "demo.nc".into()))
        );
        assert_eq!(
            info(&["% part.nc (comment)\n"]).file_name(),
            Some((None, "part.nc".into()))
        );
        assert_eq!(info(&["%L sub1\n"]).file_name(), None);
        assert_eq!(info(&["%\n"]).file_name(), None);
        // The SINUMERIK name wins over the ISG one.
        let n = info(&["%isg\n", "%_N_SIN_MPF\n"]);
        assert_eq!(n.file_name(), Some((None, "SIN.mpf".into())));
    }

    #[test]
    fn names_cannot_leave_the_program_directory() {
        for bad in [
            "%_N_.._MPF",
            "%_N_../../etc/passwd_MPF",
            "%_N_/abs_MPF",
            "%_N_a\\b_MPF",
            "%_N_C:x_MPF",
            "%_N_A\0B_MPF",
            "%..",
            "%/etc/passwd",
            "%.hidden",
        ] {
            let n = info(&[bad]);
            assert_eq!(n.file_name(), None, "{bad:?}");
            assert_eq!(n.rejected.len(), 1, "{bad:?}");
        }
        let n = info(&["%_N_P_MPF", ";$PATH=/_N_WKS_DIR/_N_.._WPD"]);
        assert_eq!(n.file_name(), Some((None, "P.mpf".into())));
        assert_eq!(n.rejected.len(), 1);
        assert_eq!(n.rejected[0].kind, NameKind::Workpiece);
        assert_eq!(safe_name(&[b'A'; MAX_NAME_LEN + 1]), None);
    }
}
