//! Pre-output of MEP_SVS and MET_SVS technology functions (TwinCAT CNC channel parameters,
//! "Synchronization types MET_SVS, MEP_SVS", P-CHAN-00070 `m_pre_outp`): the functions of a
//! block go to the PLC a path distance (MEP_SVS, 0.1 µm) or a time (MET_SVS, µs) before the
//! synchronisation point at the block's start, while the blocks before it still move, so the
//! PLC's time overlaps the motion. The wait at the synchronisation point stays a planned stop.

use super::entry::EntryKind;
use super::window::Window;
use crate::vocab::techno::{OutputGroup, SyncType};

/// mm per 0.1 µm (MEP_SVS's unit).
const MM_PER_PRE_UNIT: f64 = 1e-4;
/// s per µs (MET_SVS's unit).
const S_PER_PRE_UNIT: f64 = 1e-6;

/// How far before its synchronisation point a group goes out: the largest pre-output of its
/// MEP_SVS functions (mm) and of its MET_SVS functions (s). In one block overlapping ranges
/// change nothing; the earliest decides.
pub(super) fn lead(g: &OutputGroup) -> (f64, f64) {
    g.fns.iter().fold((0.0, 0.0), |(mm, s), f| {
        let v = f64::from(f.def.pre_output);
        match f.def.sync.timing() {
            SyncType::MepSvs => (f64::max(mm, v * MM_PER_PRE_UNIT), s),
            SyncType::MetSvs => (mm, f64::max(s, v * S_PER_PRE_UNIT)),
            _ => (mm, s),
        }
    })
}

/// Does this entry output a group with a pre-output?
pub(super) fn has_lead(kind: &EntryKind) -> bool {
    matches!(kind, EntryKind::TechnoOutput(g) if lead(g) != (0.0, 0.0))
}

/// The first group with a pre-output ahead of the front move whose point has come: the front
/// has `to_go_mm` (`to_go_s` at its cruise velocity) left, and every move between it and the
/// group adds its length (and its length over its cruise velocity). A stop on the way (a
/// wait, a dwell, a program stop) ends the look: nothing beyond it goes out early. The taken
/// entry becomes plain, so it does not go out a second time. The window bounds the look.
pub(super) fn take_due(
    window: &mut Window,
    to_go_mm: f64,
    to_go_s: f64,
    override_pct: f64,
) -> Option<Box<OutputGroup>> {
    let (mut mm, mut s) = (to_go_mm, to_go_s);
    for e in window.iter_mut().skip(1) {
        match &e.kind {
            EntryKind::Move(seg) => {
                mm += seg.length_mm;
                s += seg.length_mm / seg.cruise_mm_per_s(override_pct).max(1e-9);
            }
            EntryKind::TechnoOutput(g) => {
                let (lead_mm, lead_s) = lead(g);
                if (lead_mm > 0.0 && mm <= lead_mm) || (lead_s > 0.0 && s <= lead_s) {
                    return match std::mem::replace(&mut e.kind, EntryKind::Plain) {
                        EntryKind::TechnoOutput(g) => Some(g),
                        _ => None,
                    };
                }
            }
            k if k.is_barrier() => return None,
            _ => {}
        }
    }
    None
}
