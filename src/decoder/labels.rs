//! The label index of a program file (labels and `%L` sections), built a slice per tick.
//!
//! A `$GOTO` or `LL` in a file needs to know where every label stands. Scanning a whole file
//! in the tick that meets the jump made one tick's work grow with the file (4 M labels: one
//! tick of 2.6 s). So the scan is a resumable [`LabelScan`]: each tick it reads at most
//! [`LABEL_SCAN_LINES_PER_TICK`] lines and [`LABEL_SCAN_BYTES_PER_TICK`] bytes, and the jump
//! waits for it as the decoder waits for a simulated file-system read (motion runs on).
//!
//! The index holds at most [`MAX_INDEXED_LABELS`] labels of each kind, as the kernel's jump
//! table does (TF5200 diagnosis ID 20829 "Number of string labels too big for optimised program
//! execution": the program goes on, and a jump to a label that found no room is searched
//! again, which "lengthens the program runtime"). A jump to such a label runs a targeted scan,
//! under the same per-tick budget, from the top of the file.

use std::collections::BTreeMap;
use std::sync::Arc;

use crate::lang::block::{Body, Command, GotoTarget, Label};
use crate::lang::{continuation, is_comment_end, parse_block, Joiner};

use super::error::DecodeError;
use super::line::{cut_line, LinePos};
use crate::lang::codes;
use crate::lang::control::{goto_label, label_text, nesting, Nesting};

/// Labels of one kind (block-number labels `N10:`, string labels `[NAME]`) the index holds;
/// `%L` sections likewise. Memory stays proportional to this, not to the file: a label
/// beyond it is found by a targeted scan when a jump names it.
pub const MAX_INDEXED_LABELS: usize = 65_536;

/// Lines the label scan reads per tick at most (each one may be parsed).
pub const LABEL_SCAN_LINES_PER_TICK: usize = 256;

/// Bytes the label scan reads per tick at most.
pub const LABEL_SCAN_BYTES_PER_TICK: usize = 64 * 1024;

/// Where a label stands and how many structures are open around it.
pub(crate) type LabelAt = (LinePos, usize);

/// All labels of a file (up to [`MAX_INDEXED_LABELS`] of each kind) with where they stand
/// and how deeply nested they are, and the `%L` sections.
///
/// B-trees, not hash maps: a hash map doubles by rehashing every key in the insert that fills
/// it, and at 32,768 labels that one insert cost its tick some 20 ms; a B-tree insert splits
/// at most one node per level. A finished index is freed by the loader thread
/// (`Frame`'s `Drop`), since freeing 65,536 labels costs a tick milliseconds too.
#[derive(Debug, Default)]
pub(crate) struct LabelIndex {
    labels: BTreeMap<Label, LabelAt>,
    number_labels: usize,
    string_labels: usize,
    /// `%L NAME` (upper-case) → the line after the head.
    local_subs: BTreeMap<String, LinePos>,
    /// Some label or section found no room: one missing from the index may still exist.
    pub(crate) overflowed: bool,
}

impl LabelIndex {
    /// Labels and sections held.
    pub(crate) fn len(&self) -> usize {
        self.labels.len() + self.local_subs.len()
    }

    pub(crate) fn find(&self, t: &GotoTarget) -> Option<LabelAt> {
        self.labels.get(&goto_label(t)).copied()
    }

    pub(crate) fn local_sub(&self, name: &str) -> Option<LinePos> {
        self.local_subs.get(&name.to_ascii_uppercase()).copied()
    }

    /// Record a label; `false` when its kind has no room left.
    fn insert_label(&mut self, l: &Label, at: LabelAt) -> bool {
        let count = match l {
            Label::Number(_) => &mut self.number_labels,
            Label::Name(_) => &mut self.string_labels,
        };
        if *count >= MAX_INDEXED_LABELS {
            self.overflowed = true;
            return false;
        }
        *count += 1;
        self.labels.insert(l.clone(), at);
        true
    }

    /// Record a `%L` section; `false` when there is no room left.
    fn insert_local_sub(&mut self, name: &str, at: LinePos) -> bool {
        if self.local_subs.len() >= MAX_INDEXED_LABELS {
            self.overflowed = true;
            return false;
        }
        self.local_subs.insert(name.to_ascii_uppercase(), at);
        true
    }
}

/// What a scan looks for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum ScanGoal {
    /// Every label and section, for the index.
    Index,
    /// One label the full index had no room for.
    Label(Label),
    /// One `%L` section (upper-case name) the full index had no room for.
    LocalSub(String),
}

/// What a finished scan found.
#[derive(Debug)]
pub(crate) enum ScanFound {
    Index(LabelIndex),
    Label(Option<LabelAt>),
    LocalSub(Option<LinePos>),
}

/// A warning the scan raises (the index is full), reported once per kind and scan.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ScanWarning {
    pub(crate) code: u32,
    pub(crate) msg: String,
}

/// One slice of a scan.
#[derive(Debug)]
pub(crate) enum ScanStep {
    /// The budget ran out; go on next tick.
    Pending,
    Done(ScanFound),
}

/// What one tick's slice of a scan read, for the decoder's statistics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct ScanWork {
    pub(crate) lines: usize,
    pub(crate) bytes: usize,
}

/// A scan of one program text, resumable between ticks. It reads lines exactly as the
/// decoder does (comment blocks, blocks continued with `\`) so depths agree.
#[derive(Debug)]
pub(crate) struct LabelScan {
    text: Arc<Vec<u8>>,
    goal: ScanGoal,
    index: LabelIndex,
    pos: usize,
    line_no: u32,
    depth: usize,
    comment: bool,
    line: String,
    joiner: Joiner,
    /// Where the block being read (maybe over several lines) starts.
    at: LinePos,
    /// Warnings raised when the index filled up, not yet taken.
    warnings: Vec<ScanWarning>,
    /// Kinds already warned about (string labels; block-number labels and sections).
    warned_string: bool,
    warned_other: bool,
}

impl LabelScan {
    /// Whether dropping the scan could cost a tick: it outlived its frame (a reset during the
    /// scan) holding the last reference to a large text, or its index grew large. The reader
    /// then lets the loader thread free it.
    pub(crate) fn is_heavy(&self) -> bool {
        crate::source::loader::is_heavy_text(&self.text)
            || crate::source::loader::is_heavy_table(self.index.len())
    }

    pub(crate) fn new(text: Arc<Vec<u8>>, goal: ScanGoal) -> Self {
        LabelScan {
            text,
            goal,
            index: LabelIndex::default(),
            pos: 0,
            line_no: 0,
            depth: 0,
            comment: false,
            line: String::new(),
            joiner: Joiner::default(),
            at: LinePos { pos: 0, line_no: 0 },
            warnings: Vec::new(),
            warned_string: false,
            warned_other: false,
        }
    }

    pub(crate) fn goal(&self) -> &ScanGoal {
        &self.goal
    }

    /// The index-full warnings raised since the last call.
    pub(crate) fn take_warnings(&mut self) -> Vec<ScanWarning> {
        std::mem::take(&mut self.warnings)
    }

    /// The first item of a kind that found no room: warn once per kind (string labels have
    /// the kernel's id, block-number labels and `%L` sections ours). `what` names the item;
    /// it is only called for the warning, not for every later item without room (4 M labels
    /// past a full index built 4 M names a tick for nothing).
    fn no_room(&mut self, string: bool, what: impl FnOnce() -> String) {
        let (warned, code) = if string {
            (&mut self.warned_string, codes::STRING_LABEL_INDEX_FULL)
        } else {
            (&mut self.warned_other, codes::LABEL_INDEX_FULL)
        };
        if std::mem::replace(warned, true) {
            return;
        }
        self.warnings.push(ScanWarning {
            code,
            msg: format!(
                "more than {MAX_INDEXED_LABELS} for the label index: {} (line {}) and later ones are searched at each jump or call",
                what(),
                self.line_no
            ),
        });
    }

    /// Read on while `work` (what label scans read in this tick so far, added to here) is
    /// within the tick's budget.
    pub(crate) fn advance(&mut self, work: &mut ScanWork) -> Result<ScanStep, DecodeError> {
        while work.lines < LABEL_SCAN_LINES_PER_TICK && work.bytes < LABEL_SCAN_BYTES_PER_TICK {
            if !self.joiner.is_open() {
                self.at = LinePos {
                    pos: self.pos,
                    line_no: self.line_no,
                };
            }
            let start = self.pos;
            let next = match cut_line(&self.text, start, &mut self.line, true) {
                Ok(Some(next)) => next,
                Ok(None) => return Ok(ScanStep::Done(self.finish())),
                Err(e) => return Err(e.error(self.line_no + 1)),
            };
            self.pos = next;
            self.line_no += 1;
            work.lines += 1;
            work.bytes += next - start;
            if let Some(found) = self.scan_line(next)? {
                return Ok(ScanStep::Done(found));
            }
        }
        Ok(ScanStep::Pending)
    }

    /// One line read: `Some` when a targeted scan found what it looked for.
    fn scan_line(&mut self, next: usize) -> Result<Option<ScanFound>, DecodeError> {
        if self.comment {
            if is_comment_end(&self.line) {
                self.comment = false;
            }
            return Ok(None);
        }
        // A block written over several lines (`\`) is read as the decoder reads it.
        let joined = self.joiner.is_open() || continuation(&self.line).is_some();
        if joined && !self.joiner.push(&self.line) && next < self.text.len() {
            return Ok(None);
        }
        if !joined && !may_matter(&self.line) {
            return Ok(None);
        }
        let text = if joined {
            self.joiner.text()
        } else {
            &self.line
        };
        let Ok(block) = parse_block(text) else {
            if joined {
                self.joiner.close();
            }
            return Ok(None);
        };
        if joined {
            self.joiner.close();
        }
        let at = (self.at, self.depth);
        if let Some(l) = &block.label {
            if let Some(found) = self.label_met(l, at)? {
                return Ok(Some(found));
            }
        }
        match &block.body {
            Body::Command(c) if **c == Command::CommentBegin => self.comment = true,
            Body::ProgramHead(head) if head.local => {
                let name = &head.name;
                let after = LinePos {
                    pos: self.pos,
                    line_no: self.line_no,
                };
                let indexed = match &self.goal {
                    ScanGoal::Index => self.index.insert_local_sub(name, after),
                    ScanGoal::LocalSub(want) if name.eq_ignore_ascii_case(want) => {
                        return Ok(Some(ScanFound::LocalSub(Some(after))));
                    }
                    _ => true,
                };
                if !indexed {
                    self.no_room(false, || format!("%L {name}"));
                }
            }
            Body::Control(c) => match nesting(c) {
                Nesting::Open => self.depth += 1,
                Nesting::Close => self.depth = self.depth.saturating_sub(1),
                Nesting::Neither => {}
            },
            _ => {}
        }
        Ok(None)
    }

    /// A label line: indexed (a second definition is 20836), or the one a targeted scan seeks.
    fn label_met(&mut self, l: &Label, at: LabelAt) -> Result<Option<ScanFound>, DecodeError> {
        match &self.goal {
            ScanGoal::Index => {
                if self.index.labels.contains_key(l) {
                    return Err(DecodeError::new(
                        codes::LABEL_TWICE,
                        format!(
                            "label {} defined twice (line {})",
                            label_text(l),
                            self.line_no
                        ),
                    ));
                }
                if !self.index.insert_label(l, at) {
                    let string = matches!(l, Label::Name(_));
                    self.no_room(string, || format!("label {}", label_text(l)));
                }
                Ok(None)
            }
            ScanGoal::Label(want) if want == l => Ok(Some(ScanFound::Label(Some(at)))),
            _ => Ok(None),
        }
    }

    /// The end of the text: what the scan found.
    fn finish(&mut self) -> ScanFound {
        match &self.goal {
            ScanGoal::Index => ScanFound::Index(std::mem::take(&mut self.index)),
            ScanGoal::Label(_) => ScanFound::Label(None),
            ScanGoal::LocalSub(_) => ScanFound::LocalSub(None),
        }
    }
}

/// Whether a line can hold a label, a `$` statement, a `#` command or a `%` head: only such
/// lines are parsed (a motion block like `G01 X10` is passed over without parsing).
fn may_matter(line: &str) -> bool {
    line.bytes()
        .any(|b| matches!(b, b'[' | b':' | b'$' | b'#' | b'%'))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Past a full index only the first item of a kind is named (the warning's text); every
    /// later one costs no string.
    #[test]
    fn only_the_first_item_without_room_is_named() {
        let mut scan = LabelScan::new(Arc::new(Vec::new()), ScanGoal::Index);
        scan.no_room(true, || "label [L65537]".to_string());
        scan.no_room(true, || panic!("a second string label named"));
        scan.no_room(false, || "label N70000".to_string());
        scan.no_room(false, || panic!("a second block-number label named"));
        let w = scan.take_warnings();
        assert_eq!(w.len(), 2);
        assert_eq!(w[0].code, codes::STRING_LABEL_INDEX_FULL);
        assert!(w[0].msg.contains("label [L65537] (line 0)"), "{}", w[0].msg);
        assert_eq!(w[1].code, codes::LABEL_INDEX_FULL);
    }
}
