//! The soak's invariants: every streamed block executed exactly once and in order between
//! resets, no channel error but the expected ones, positions within the soft limits, memory
//! steady. Checked as the run goes, at the cost of a few comparisons per block.

use std::collections::VecDeque;

use serde::Serialize;

use super::feed::Owed;
use crate::channel::ExecutedBlock;

/// Violation messages kept per invariant; the count goes on.
const MAX_DETAILS: usize = 8;

/// One invariant's verdict.
#[derive(Debug, Clone, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct Verdict {
    pub name: String,
    pub held: bool,
    pub violations: u64,
    /// The first few violations, or what was measured when it held.
    pub details: Vec<String>,
}

/// A running tally of one invariant.
#[derive(Debug, Clone, Default)]
pub struct Tally {
    pub violations: u64,
    pub details: Vec<String>,
}

impl Tally {
    pub(crate) fn violate(&mut self, msg: impl FnOnce() -> String) {
        self.violations += 1;
        if self.details.len() < MAX_DETAILS {
            self.details.push(msg());
        }
    }

    pub fn verdict(&self, name: &str, note: Option<String>) -> Verdict {
        let mut details = self.details.clone();
        if self.violations == 0 {
            details.extend(note);
        }
        Verdict {
            name: name.into(),
            held: self.violations == 0,
            violations: self.violations,
            details,
        }
    }
}

/// FNV-1a, 64 bit: the running checksum over executed blocks (N and stream offset), equal for
/// equal runs, so two runs of one seed can be compared by one number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Checksum(pub u64);

impl Default for Checksum {
    fn default() -> Self {
        Checksum(0xcbf2_9ce4_8422_2325)
    }
}

impl Checksum {
    pub fn add(&mut self, v: u64) {
        for b in v.to_le_bytes() {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// Check executed stream blocks against what the channel owes. Each block must be the next
/// owed line (lines that yield no block, like a file's comments, may be passed over); a block
/// nobody wrote, one out of order or one run twice is a violation.
pub(crate) fn check_blocks(
    channel: u32,
    owed: &mut VecDeque<Owed>,
    executed: impl Iterator<Item = ExecutedBlock>,
    tally: &mut Tally,
    sum: &mut Checksum,
) -> u64 {
    let mut count = 0;
    for b in executed {
        count += 1;
        sum.add(b.offset);
        sum.add(b.n.map_or(u64::MAX, u64::from));
        loop {
            let Some(front) = owed.pop_front() else {
                tally.violate(|| {
                    format!(
                        "channel {channel}: block N{} at offset {} executed but not owed (never written, or run twice)",
                        b.n.unwrap_or(0),
                        b.offset
                    )
                });
                break;
            };
            if front.offset == b.offset {
                if front.n.is_some() && front.n != b.n {
                    tally.violate(|| {
                        format!(
                            "channel {channel}: at offset {} N{:?} was written, N{:?} executed",
                            b.offset, front.n, b.n
                        )
                    });
                }
                break;
            }
            if front.offset > b.offset {
                // Behind the owed line: an old block again. Keep what is owed.
                owed.push_front(front);
                tally.violate(|| {
                    format!(
                        "channel {channel}: block at offset {} executed again or out of order (next owed offset {})",
                        b.offset, front.offset
                    )
                });
                break;
            }
            if front.must_run {
                tally.violate(|| {
                    format!(
                        "channel {channel}: block N{} at offset {} skipped (offset {} executed next)",
                        front.n.unwrap_or(0),
                        front.offset,
                        b.offset
                    )
                });
            }
        }
    }
    count
}

/// Resident set size of this process, KiB (`VmRSS` of /proc/self/status); `None` where there
/// is no /proc.
pub(crate) fn resident_kib() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn owed(v: &[(u64, u32)]) -> VecDeque<Owed> {
        v.iter()
            .map(|&(o, n)| Owed {
                offset: o,
                n: Some(n),
                must_run: true,
            })
            .collect()
    }
    fn ex(o: u64, n: u32) -> ExecutedBlock {
        ExecutedBlock {
            offset: o,
            n: Some(n),
        }
    }

    #[test]
    fn in_order_exactly_once_holds() {
        let mut q = owed(&[(0, 1), (10, 2), (20, 3)]);
        let mut t = Tally::default();
        let mut s = Checksum::default();
        let n = check_blocks(1, &mut q, [ex(0, 1), ex(10, 2)].into_iter(), &mut t, &mut s);
        assert_eq!((n, t.violations, q.len()), (2, 0, 1));
    }

    #[test]
    fn skipped_repeated_and_unwritten_blocks_are_violations() {
        let mut t = Tally::default();
        let mut s = Checksum::default();
        let mut q = owed(&[(0, 1), (10, 2), (20, 3)]);
        check_blocks(1, &mut q, [ex(0, 1), ex(20, 3)].into_iter(), &mut t, &mut s);
        assert_eq!(t.violations, 1, "N2 skipped");
        let mut q = owed(&[(0, 1), (10, 2)]);
        let mut t = Tally::default();
        check_blocks(1, &mut q, [ex(0, 1), ex(0, 1)].into_iter(), &mut t, &mut s);
        assert_eq!(t.violations, 1, "N1 twice");
        assert_eq!(q.len(), 1, "N2 still owed");
        let mut q = owed(&[]);
        let mut t = Tally::default();
        check_blocks(1, &mut q, [ex(5, 9)].into_iter(), &mut t, &mut s);
        assert_eq!(t.violations, 1, "never written");
        let mut q = owed(&[(0, 1)]);
        let mut t = Tally::default();
        check_blocks(1, &mut q, [ex(0, 4)].into_iter(), &mut t, &mut s);
        assert_eq!(t.violations, 1, "wrong N");
    }

    #[test]
    fn checksum_depends_on_order() {
        let (mut a, mut b) = (Checksum::default(), Checksum::default());
        a.add(1);
        a.add(2);
        b.add(2);
        b.add(1);
        assert_ne!(a, b);
    }
}
