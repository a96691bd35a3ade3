//! The soak's invariants: every streamed block executed exactly once and in order between
//! resets, no channel error but the expected ones, positions within the soft limits, memory
//! steady. Checked as the run goes, at the cost of a few comparisons per block.

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::time::Duration;

use serde::Serialize;

use super::feed::Owed;
use crate::channel::techno::TechnoSeen;
use crate::channel::ExecutedBlock;
use crate::vocab::techno::{TechnoKind, TechnoSeq};

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

/// Finished sequence numbers kept for the "output once" check; beyond, the oldest half is
/// folded into a floor (everything below it counts as seen).
const MAX_FINISHED: usize = 4096;

/// What the technology check counted of one channel.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct TechnoFigures {
    pub output: u64,
    pub acknowledged: u64,
    /// Output, then dropped by a reset or an error.
    pub dropped: u64,
    /// Dropped before they were output (waiting for a unit).
    pub dropped_unoutput: u64,
    /// Blocks that started after functions they waited for (MVS_SVS).
    pub waited_starts: u64,
    /// Longest channel time from a waited-for function's output to its block's start, ms.
    pub max_output_to_start_ms: u64,
}

/// A function output and not yet finished, as the check knows it.
#[derive(Debug, Clone, Copy)]
struct OpenFn {
    kind: TechnoKind,
    number: u32,
    at: Duration,
    /// Its block's motion waits for it (MVS_SVS).
    before_motion: bool,
}

/// The technology functions of one channel against the rules: each output once, then
/// acknowledged once or dropped by a reset; a block that waits for its functions (MVS_SVS)
/// starts only after they are acknowledged. Fed with the channel's observations
/// ([`TechnoSeen`], `Op::DrainTechno`), in their order.
#[derive(Debug, Default)]
pub(crate) struct TechnoCheck {
    open: BTreeMap<TechnoSeq, OpenFn>,
    /// Acknowledged, waiting for their block's start: output time.
    acknowledged: BTreeMap<TechnoSeq, Duration>,
    finished: BTreeSet<TechnoSeq>,
    /// Every number below is finished.
    floor: TechnoSeq,
    pub figures: TechnoFigures,
}

impl TechnoCheck {
    fn seen(&self, seq: TechnoSeq) -> bool {
        seq < self.floor || self.finished.contains(&seq) || self.open.contains_key(&seq)
    }

    fn finish(&mut self, seq: TechnoSeq) {
        self.finished.insert(seq);
        if self.finished.len() > MAX_FINISHED {
            let keep = self.finished.split_off(
                &self
                    .finished
                    .iter()
                    .nth(MAX_FINISHED / 2)
                    .copied()
                    .unwrap_or(0),
            );
            if let Some(&last) = self.finished.iter().next_back() {
                self.floor = self.floor.max(last + 1);
            }
            self.finished = keep;
        }
    }

    /// Check one observation: `order` is the "once" rule's tally, `motion` the wait rule's.
    pub(crate) fn see(
        &mut self,
        channel: u32,
        s: TechnoSeen,
        order: &mut Tally,
        motion: &mut Tally,
    ) {
        match s {
            TechnoSeen::Output {
                seq,
                kind,
                number,
                at,
                sync,
            } => {
                if self.seen(seq) {
                    order.violate(|| {
                        format!("channel {channel}: {}{number} (#{seq}) output twice", kind.letter())
                    });
                    return;
                }
                self.figures.output += 1;
                self.open.insert(
                    seq,
                    OpenFn {
                        kind,
                        number,
                        at,
                        before_motion: sync.waits_before_motion(),
                    },
                );
            }
            TechnoSeen::Acknowledged { seq, .. } => match self.open.remove(&seq) {
                Some(f) => {
                    self.figures.acknowledged += 1;
                    if f.before_motion {
                        self.acknowledged.insert(seq, f.at);
                    }
                    self.finish(seq);
                }
                None => order.violate(|| {
                    format!("channel {channel}: function #{seq} acknowledged but not open (not output, or acknowledged twice)")
                }),
            },
            TechnoSeen::Dropped { seq } => {
                if self.open.remove(&seq).is_some() {
                    self.figures.dropped += 1;
                } else if self.seen(seq) {
                    order.violate(|| {
                        format!("channel {channel}: function #{seq} dropped after it was finished")
                    });
                    return;
                } else {
                    self.figures.dropped_unoutput += 1;
                }
                self.finish(seq);
            }
            TechnoSeen::BlockStarted { at, waited } => {
                self.figures.waited_starts += 1;
                for seq in waited {
                    if let Some(out) = self.acknowledged.remove(&seq) {
                        let ms = at.saturating_sub(out).as_millis() as u64;
                        self.figures.max_output_to_start_ms =
                            self.figures.max_output_to_start_ms.max(ms);
                    } else if let Some(f) = self.open.get(&seq) {
                        let (k, n) = (f.kind.letter(), f.number);
                        motion.violate(|| {
                            format!("channel {channel}: a block started at {:.3} s while {k}{n} (#{seq}) waited for its acknowledgement", at.as_secs_f64())
                        });
                    } else {
                        motion.violate(|| {
                            format!("channel {channel}: a block started at {:.3} s before function #{seq} it waits for was output", at.as_secs_f64())
                        });
                    }
                }
                // Acknowledged functions whose block never came (a reset) are forgotten.
                self.acknowledged.clear();
            }
        }
    }

    /// Functions output and not finished.
    pub(crate) fn open(&self) -> usize {
        self.open.len()
    }
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

    fn out(seq: u64, ms: u64) -> TechnoSeen {
        TechnoSeen::Output {
            seq,
            kind: TechnoKind::M,
            number: 8,
            sync: crate::vocab::techno::SyncType::MvsSvs,
            at: Duration::from_millis(ms),
        }
    }
    fn ack(seq: u64, ms: u64) -> TechnoSeen {
        TechnoSeen::Acknowledged {
            seq,
            at: Duration::from_millis(ms),
        }
    }

    #[test]
    fn techno_check_holds_for_output_ack_start_and_reset() {
        let (mut c, mut o, mut m) = (TechnoCheck::default(), Tally::default(), Tally::default());
        for s in [
            out(0, 0),
            ack(0, 300),
            TechnoSeen::BlockStarted {
                at: Duration::from_millis(301),
                waited: vec![0],
            },
            out(1, 400),
            TechnoSeen::Dropped { seq: 1 },
            TechnoSeen::Dropped { seq: 2 },
            out(3, 500),
        ] {
            c.see(1, s, &mut o, &mut m);
        }
        assert_eq!((o.violations, m.violations), (0, 0), "{:?} {:?}", o, m);
        let f = c.figures;
        assert_eq!(
            (
                f.output,
                f.acknowledged,
                f.dropped,
                f.dropped_unoutput,
                c.open()
            ),
            (3, 1, 1, 1, 1)
        );
        assert_eq!(f.max_output_to_start_ms, 301);
    }

    #[test]
    fn techno_check_fails_when_a_rule_is_broken() {
        let (mut c, mut o, mut m) = (TechnoCheck::default(), Tally::default(), Tally::default());
        for s in [out(0, 0), ack(0, 10), ack(0, 20), out(0, 30)] {
            c.see(1, s, &mut o, &mut m);
        }
        assert_eq!(
            o.violations, 2,
            "acknowledged twice, output twice: {:?}",
            o.details
        );
        let (mut c, mut o, mut m) = (TechnoCheck::default(), Tally::default(), Tally::default());
        for s in [
            out(5, 0),
            TechnoSeen::BlockStarted {
                at: Duration::from_millis(1),
                waited: vec![5, 6],
            },
        ] {
            c.see(1, s, &mut o, &mut m);
        }
        assert_eq!(m.violations, 2, "{:?}", m.details);
        assert!(m.details[0].contains("M8 (#5) waited"), "{:?}", m.details);
    }

    #[test]
    fn techno_check_forgets_old_numbers_but_still_sees_them() {
        let (mut c, mut o, mut m) = (TechnoCheck::default(), Tally::default(), Tally::default());
        for seq in 0..10_000u64 {
            c.see(1, out(seq, seq), &mut o, &mut m);
            c.see(1, ack(seq, seq), &mut o, &mut m);
        }
        assert!(c.finished.len() <= MAX_FINISHED);
        c.see(1, out(3, 0), &mut o, &mut m);
        assert_eq!(o.violations, 1);
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
