//! A block's technology functions (M, H, S, T) against the channel's table: which are
//! defined (else the kernel's 20157 / 20162), which go to the PLC, and where they meet the
//! block's motion (TF5200 "M and H functions", "Synchronisation types" and their examples).

use super::block_words::Words;
use crate::decoder::error::{DecodeError, Res};
use crate::lang::codes;
use crate::lang::range::whole_u32 as whole;
use crate::queue::{Action, TechnoStep};
use crate::vocab::techno::{
    FunctionDef, OutputGroup, SyncSpec, SyncType, TechnoFn, TechnoKind, TechnoSeq, TechnoTable,
    PLC_INFO,
};

/// The decoder's technology state: the table (which `V.G.M_FCT[n].SYNCH` may change), the
/// next sequence number and the late-synchronised functions not yet synchronised.
#[derive(Debug)]
pub(in crate::decoder) struct TechnoState {
    table: TechnoTable,
    /// M6 calls the tool-change subroutine (P-CHAN-00118) instead of going to the PLC.
    m6_calls_subroutine: bool,
    next_seq: TechnoSeq,
    /// MVS_SLM functions output and waiting for the next feed motion block.
    late_at_feed: Vec<TechnoSeq>,
    /// MVS_SLP functions output and waiting for `#EXPL SYN`.
    late_explicit: Vec<TechnoSeq>,
    /// Bit n: M n (`quiet_h`: H n) is defined and never goes to the PLC (NO_SYNCH), so a
    /// block of only such functions needs no step of its own: one bit test per function
    /// (65,536 bits each, 8 KiB).
    quiet_m: Box<[u64]>,
    quiet_h: Box<[u64]>,
    /// S and T words that do not go to the PLC.
    quiet_s: bool,
    quiet_t: bool,
}

/// Words of the quiet bit sets: one bit per M or H number 0 … 65,535.
const QUIET_WORDS: usize = (codes::MAX_M_H as usize + 1) / 64;

fn quiet(def: Option<FunctionDef>) -> bool {
    def.is_some_and(|d| !d.sync.outputs())
}

fn set_bit(bits: &mut [u64], n: u32, on: bool) {
    if let Some(w) = bits.get_mut(n as usize / 64) {
        let b = 1u64 << (n % 64);
        if on {
            *w |= b;
        } else {
            *w &= !b;
        }
    }
}

#[inline]
fn bit(bits: &[u64], n: u32) -> bool {
    bits.get(n as usize / 64)
        .is_some_and(|w| w & (1u64 << (n % 64)) != 0)
}

/// What a block adds around its motion, in execution order: outputs and waits before it,
/// outputs and waits after it.
#[derive(Debug, Default)]
pub(in crate::decoder) struct BlockTechno {
    before: Vec<TechnoFn>,
    wait_before: Vec<TechnoSeq>,
    after: Vec<TechnoFn>,
    wait_after: Vec<TechnoSeq>,
}

impl BlockTechno {
    /// Nothing to output and nothing to wait for (only NO_SYNCH functions).
    pub(in crate::decoder) fn is_empty(&self) -> bool {
        self.before.is_empty()
            && self.wait_before.is_empty()
            && self.after.is_empty()
            && self.wait_after.is_empty()
    }

    /// The queue actions before the block's motion.
    pub(in crate::decoder) fn actions_before(
        &mut self,
        block_nr: u32,
        line: u32,
    ) -> impl Iterator<Item = Action> {
        steps(
            std::mem::take(&mut self.before),
            std::mem::take(&mut self.wait_before),
            block_nr,
            line,
        )
    }

    /// The queue actions after the block's motion.
    pub(in crate::decoder) fn actions_after(
        &mut self,
        block_nr: u32,
        line: u32,
    ) -> impl Iterator<Item = Action> {
        steps(
            std::mem::take(&mut self.after),
            std::mem::take(&mut self.wait_after),
            block_nr,
            line,
        )
    }
}

fn steps(
    fns: Vec<TechnoFn>,
    waits: Vec<TechnoSeq>,
    block_nr: u32,
    line: u32,
) -> impl Iterator<Item = Action> {
    let output = (!fns.is_empty()).then(|| {
        Action::Techno(TechnoStep::Output(Box::new(OutputGroup {
            fns,
            block_nr,
            line,
        })))
    });
    let wait =
        (!waits.is_empty()).then(|| Action::Techno(TechnoStep::Wait(waits.into_boxed_slice())));
    output.into_iter().chain(wait)
}

impl TechnoState {
    pub(in crate::decoder) fn new(table: TechnoTable, m6_calls_subroutine: bool) -> Self {
        let mut quiet_m = vec![0u64; QUIET_WORDS].into_boxed_slice();
        let mut quiet_h = vec![0u64; QUIET_WORDS].into_boxed_slice();
        let ms = table.m.iter().map(|(n, _)| *n);
        let internal = crate::vocab::techno::INTERNAL_M.iter().copied();
        let spindle = table.spindle_m.iter().map(|(n, _)| *n);
        for n in ms.chain(internal).chain(spindle) {
            set_bit(&mut quiet_m, n, quiet(table.m_def(n)));
        }
        if m6_calls_subroutine {
            set_bit(&mut quiet_m, 6, true);
        }
        for (n, d) in &table.h {
            set_bit(&mut quiet_h, *n, quiet(Some(*d)));
        }
        TechnoState {
            quiet_s: quiet(Some(table.s)),
            quiet_t: quiet(Some(table.t)),
            table,
            m6_calls_subroutine,
            next_seq: 0,
            late_at_feed: Vec::new(),
            late_explicit: Vec::new(),
            quiet_m,
            quiet_h,
        }
    }

    /// Channel reset: late functions waiting are dropped with everything else.
    pub(in crate::decoder) fn reset(&mut self) {
        self.late_at_feed.clear();
        self.late_explicit.clear();
    }

    /// `V.G.M_FCT[n].SYNCH` (`h` false) / `V.G.H_FCT[n].SYNCH` read: the kernel's value of
    /// the function's synchronisation type; `None` for a function the table does not define.
    pub(in crate::decoder) fn sync_value(&self, h: bool, n: u32) -> Option<f64> {
        let def = if h {
            self.table.h_def(n)
        } else {
            self.table.m_def(n)
        }?;
        Some(f64::from(def.sync.value()))
    }

    /// `V.G.M_FCT[n].SYNCH = v`: from the next block on, function n has the type of value
    /// `v` (a modelled type's value, `PLC_INFO` added or not); anything else is refused.
    pub(in crate::decoder) fn set_sync(&mut self, h: bool, n: f64, v: f64) -> Res {
        let letter = if h { 'H' } else { 'M' };
        let number = whole(n).filter(|n| *n <= codes::MAX_M_H).ok_or_else(|| {
            DecodeError::new(
                codes::BAD_VALUE,
                format!(
                    "V.G.{letter}_FCT[{n}]: a function number is 0 … {}",
                    codes::MAX_M_H
                ),
            )
        })?;
        let spec = whole(v)
            .and_then(|v| {
                let sync = SyncType::from_value(v & !PLC_INFO)?;
                Some(SyncSpec {
                    sync,
                    plc_info: v & PLC_INFO != 0,
                })
            })
            .ok_or_else(|| {
                DecodeError::new(
                    codes::BAD_VALUE,
                    format!(
                        "V.G.{letter}_FCT[{number}].SYNCH = {v}: not a synchronisation type \
                         ncchannel models (NO_SYNCH 0, MOS 1, MVS_SVS 2, MVS_SNS 4, MNS_SNS 8, \
                         MVS_SLM 0x4000, MVS_SLP 0x8000, MEP_SVS 0x1000000, MET_SVS 0x2000000, \
                         with PLC_INFO 0x20000 or not)"
                    ),
                )
            })?;
        if h {
            self.table.set_h_sync(number, spec);
            set_bit(&mut self.quiet_h, number, quiet(self.table.h_def(number)));
        } else {
            self.table.set_m_sync(number, spec);
            let m6 = number == 6 && self.m6_calls_subroutine;
            set_bit(
                &mut self.quiet_m,
                number,
                m6 || quiet(self.table.m_def(number)),
            );
        }
        Ok(())
    }

    /// `#EXPL SYN`: the MVS_SLP functions output since the last one are waited for here.
    pub(in crate::decoder) fn explicit_sync(&mut self) -> Option<Action> {
        (!self.late_explicit.is_empty()).then(|| {
            Action::Techno(TechnoStep::Wait(
                std::mem::take(&mut self.late_explicit).into_boxed_slice(),
            ))
        })
    }

    /// Does the block program anything this step looks at? (Most blocks do not: one test.)
    #[inline]
    pub(in crate::decoder) fn concerns(&self, w: &Words, feed_move: bool) -> bool {
        w.ms().iter().any(|m| !bit(&self.quiet_m, *m))
            || w.hs().iter().any(|h| !bit(&self.quiet_h, *h))
            || (w.spindle_rpm.is_some() && !self.quiet_s)
            || (w.tool.is_some() && !self.quiet_t)
            || (feed_move && !self.late_at_feed.is_empty())
    }

    /// STEP 1–3 for one block: check every function against the table, give the output ones
    /// their sequence numbers, and place them and their waits around the motion.
    /// `feed_move`: the block moves at feed (G01/G02/G03), which synchronises MVS_SLM.
    pub(in crate::decoder) fn plan(&mut self, w: &Words, feed_move: bool) -> Res<BlockTechno> {
        let mut out = BlockTechno::default();
        // STEP 1: the late functions a feed move synchronises wait before its motion.
        if feed_move {
            out.wait_before.append(&mut self.late_at_feed);
        }
        // STEP 2: each function with its definition, in the order M, H, S, T.
        for (&m, &value) in w.ms().iter().zip(&w.m_values) {
            if m == 6 && self.m6_calls_subroutine {
                continue;
            }
            let def = self.table.m_def(m).ok_or_else(|| {
                if codes::unknown_m(m) == codes::UNKNOWN_INTERNAL_M {
                    // Above the self-defined M functions the kernel looks for an internal
                    // one (TF5200 diagnosis ID 20160, whose example is `M1001`).
                    return DecodeError::new(
                        codes::UNKNOWN_INTERNAL_M,
                        format!(
                            "M{m} is above the self-defined M functions (M0 to M{}) and no \
                             internal M function",
                            codes::MAX_SELF_DEFINED_M
                        ),
                    );
                }
                DecodeError::new(
                    codes::UNKNOWN_M,
                    format!("M{m} is not defined in the channel parameters (m_synch[{m}])"),
                )
            })?;
            self.place(&mut out, TechnoKind::M, m, value, def);
        }
        for (&h, &value) in w.hs().iter().zip(&w.h_values) {
            let def = self.table.h_def(h).ok_or_else(|| {
                DecodeError::new(
                    codes::UNKNOWN_H,
                    format!("H{h} is not defined in the channel parameters (h_synch[{h}])"),
                )
            })?;
            self.place(&mut out, TechnoKind::H, h, value, def);
        }
        if let Some(rpm) = w.spindle_rpm {
            let number = rpm.abs().round().min(f64::from(u32::MAX)) as u32;
            self.place(&mut out, TechnoKind::S, number, Some(rpm), self.table.s);
        }
        if let Some(t) = w.tool {
            self.place(&mut out, TechnoKind::T, t, None, self.table.t);
        }
        Ok(out)
    }

    /// STEP 3: one function's place: output before or after the motion, waited for before,
    /// after, or late.
    fn place(
        &mut self,
        out: &mut BlockTechno,
        kind: TechnoKind,
        number: u32,
        value: Option<f64>,
        def: FunctionDef,
    ) {
        if !def.sync.outputs() {
            return;
        }
        let seq = self.next_seq;
        self.next_seq += 1;
        let f = TechnoFn {
            seq,
            kind,
            number,
            value,
            def,
        };
        let timing = def.sync.timing();
        if timing.outputs_before_motion() {
            out.before.push(f);
        } else {
            out.after.push(f);
        }
        if timing.waits_before_motion() {
            out.wait_before.push(seq);
        } else if timing.waits_after_motion() {
            out.wait_after.push(seq);
        } else if timing == SyncType::MvsSlm {
            self.late_at_feed.push(seq);
        } else if timing == SyncType::MvsSlp {
            self.late_explicit.push(seq);
        }
    }
}
