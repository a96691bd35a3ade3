//! The channel list's technology-function parameters, read into a [`TechnoTable`] (TF5200
//! "M and H functions"; TF5200 channel parameters):
//!
//! - `m_synch[i]` (P-CHAN-00041), `h_synch[i]` (P-CHAN-00027): the synchronisation type of M
//!   / H function i (0 … 65535);
//! - `m_prozess_zeit[i]` (P-CHAN-00040), `h_prozess_zeit[i]` (P-CHAN-00026): its process
//!   time, µs;
//! - `m_pre_outp[i]` (P-CHAN-00070), `h_pre_outp[i]` (P-CHAN-00107): its pre-output for
//!   MEP_SVS (0.1 µm) or MET_SVS (µs);
//! - `spindel[0].s_synch` (P-CHAN-00081), `spindel[0].s_prozess_zeit` (P-CHAN-00080), and
//!   `spindel[0].m3_synch` … `m19_synch` (TF5200 "Spindle-specific synchronisation types",
//!   `m4_synch` P-CHAN-00047) with `m3_prozess_zeit` (P-CHAN-00044), `m4_prozess_zeit`
//!   (P-CHAN-00046), `m5_prozess_zeit` (P-CHAN-00048), `m19_prozess_zeit` (P-CHAN-00042);
//! - `tool.synch` (P-CHAN-00086), `tool.prozess_zeit` (P-CHAN-00072).
//!
//! A synchronisation type is written as the kernel's symbol (`MVS_SVS`), as its value
//! (`0x00000002`, also decimal: "for downward compatibility an UNS32 is allowed", P-CHAN-00086),
//! or as symbols joined by `|` (`PLC_INFO | MVS_SVS`). The kernel's own lists write the symbol
//! and the value side by side (`spindel[0].m3_synch PLC_INFO | MVS_SVS 0x00020002`,
//! `m_synch[96] 0x01000000 MEP_SVS`); when the second column reads as the other form, it must
//! say the same, else the entry is refused (one of the two is a typo).

use std::collections::BTreeMap;

use super::list::{Entry, ParamList, Pos, ValueKind};
use super::startup::shape;
use super::value::uint_value;
use crate::diag::Diagnostic;
use crate::vocab::techno::{
    FunctionDef, SyncSpec, SyncType, TechnoTable, PLC_INFO, UNMODELLED_SYNC,
};

/// The spindle M functions, in [`TechnoTable::spindle_m`]'s order, with the name part of
/// their `spindel[0].m<n>_*` entries.
const SPINDLE_M: [(u32, &str, &str); 4] = [
    (3, "m3_synch", "m3_prozess_zeit"),
    (4, "m4_synch", "m4_prozess_zeit"),
    (5, "m5_synch", "m5_prozess_zeit"),
    (19, "m19_synch", "m19_prozess_zeit"),
];

/// Which value of an M/H function an entry sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Field {
    Sync,
    ProcessTime,
    PreOutput,
}

/// What the list says of M or H functions by number, each value with the entry that set it
/// (a later entry replaces an earlier one, as in the kernel's list reader).
#[derive(Debug, Default)]
struct Numbered {
    sync: BTreeMap<u32, (SyncSpec, Entry)>,
    process_time: BTreeMap<u32, (u32, Entry)>,
    pre_output: BTreeMap<u32, (u32, Entry)>,
}

/// Gathers the technology entries of one channel list; [`TechnoCollector::finish`] joins
/// them into the channel's [`TechnoTable`].
#[derive(Debug, Default)]
pub(crate) struct TechnoCollector {
    m: Numbered,
    h: Numbered,
    /// S, the spindle M functions and T, set directly (from `TechnoTable::default`, the
    /// kernel's defaults).
    table: TechnoTable,
}

impl TechnoCollector {
    /// Read `e` if it is a technology parameter; `false` leaves it to the caller (to be
    /// tallied as not read).
    pub(crate) fn add(&mut self, list: &ParamList, e: &Entry, diags: &mut Vec<Diagnostic>) -> bool {
        match shape(e).as_slice() {
            [(name, Some(i))] => {
                let (numbered, field) = match *name {
                    "m_synch" => (&mut self.m, Field::Sync),
                    "h_synch" => (&mut self.h, Field::Sync),
                    "m_prozess_zeit" => (&mut self.m, Field::ProcessTime),
                    "h_prozess_zeit" => (&mut self.h, Field::ProcessTime),
                    "m_pre_outp" => (&mut self.m, Field::PreOutput),
                    "h_pre_outp" => (&mut self.h, Field::PreOutput),
                    _ => return false,
                };
                match field {
                    Field::Sync => {
                        if let Some(s) = sync_value(list, e, diags) {
                            numbered.sync.insert(*i, (s, e.clone()));
                        }
                    }
                    Field::ProcessTime => {
                        if let Some(v) = u32_value(list, e, diags) {
                            numbered.process_time.insert(*i, (v, e.clone()));
                        }
                    }
                    Field::PreOutput => {
                        if let Some(v) = u32_value(list, e, diags) {
                            numbered.pre_output.insert(*i, (v, e.clone()));
                        }
                    }
                }
                true
            }
            [("spindel", Some(k)), (field, None)] => {
                let Some(slot) = self.spindle_slot(field) else {
                    // bezeichnung, log_achs_nr, range_way …: not read.
                    return false;
                };
                if *k != 0 {
                    diags.push(list.warning_at(
                        e,
                        e.name_pos,
                        format!("{}: only spindle 0 is modelled; not read", e.name.text),
                    ));
                    return false;
                }
                if field.ends_with("_synch") {
                    if let Some(s) = sync_value(list, e, diags) {
                        slot.sync = s;
                    }
                } else if let Some(v) = u32_value(list, e, diags) {
                    slot.process_time_us = v;
                }
                true
            }
            [("tool", None), ("synch", None)] => {
                if let Some(s) = sync_value(list, e, diags) {
                    self.table.t.sync = s;
                }
                true
            }
            [("tool", None), ("prozess_zeit", None)] => {
                if let Some(v) = u32_value(list, e, diags) {
                    self.table.t.process_time_us = v;
                }
                true
            }
            _ => false,
        }
    }

    /// The function a `spindel[k].<field>` entry configures, if it is a technology one.
    fn spindle_slot(&mut self, field: &str) -> Option<&mut FunctionDef> {
        if field == "s_synch" || field == "s_prozess_zeit" {
            return Some(&mut self.table.s);
        }
        let i = SPINDLE_M
            .iter()
            .position(|(_, sync, time)| field == *sync || field == *time)?;
        Some(&mut self.table.spindle_m[i].1)
    }

    /// The channel's table: the M and H functions sorted by number, each with its process
    /// time and pre-output.
    pub(crate) fn finish(self, list: &ParamList, diags: &mut Vec<Diagnostic>) -> TechnoTable {
        let TechnoCollector { m, h, mut table } = self;
        table.m = join(list, 'M', m, diags);
        table.h = join(list, 'H', h, diags);
        table
    }
}

/// The functions of one letter, sorted by number (a `BTreeMap` iterates in key order).
fn join(
    list: &ParamList,
    letter: char,
    n: Numbered,
    diags: &mut Vec<Diagnostic>,
) -> Vec<(u32, FunctionDef)> {
    let Numbered {
        sync,
        mut process_time,
        mut pre_output,
    } = n;
    let spindle = |k: u32| {
        if letter == 'M' {
            SPINDLE_M.iter().find(|(m, _, _)| *m == k)
        } else {
            None
        }
    };
    let mut out = Vec::with_capacity(sync.len());
    for (k, (spec, e)) in sync {
        let time = process_time.remove(&k);
        let pre = pre_output.remove(&k);
        if let Some((_, sync_name, _)) = spindle(k) {
            // TechnoTable::m_def answers M3/M4/M5/M19 from the spindle's entries.
            for entry in std::iter::once(&e).chain(time.as_ref().map(|t| &t.1)) {
                diags.push(spindle_shadowed(list, entry, k, sync_name));
            }
            if let Some((_, pe)) = &pre {
                diags.push(spindle_shadowed(list, pe, k, sync_name));
            }
            continue;
        }
        let mut def = FunctionDef::new(spec);
        if let Some((t, _)) = time {
            def.process_time_us = t;
        }
        let pre_outputs = matches!(spec.sync, SyncType::MepSvs | SyncType::MetSvs);
        match pre {
            Some((v, _)) if pre_outputs && v > 0 => def.pre_output = v,
            Some((v, pe)) if !pre_outputs && v > 0 => diags.push(list.warning_at(
                &pe,
                pe.value_pos,
                format!(
                    "{}: {letter}{k} is {}; ncchannel pre-outputs MEP_SVS and MET_SVS functions only, so this value is not used",
                    pe.name.text, spec.sync
                ),
            )),
            _ if pre_outputs => diags.push(list.warning_at(
                &e,
                e.value_pos,
                format!(
                    "{}: {} without a pre-output ({}_pre_outp[{k}] missing or 0): {letter}{k} is output at the synchronisation point",
                    e.name.text,
                    spec.sync,
                    letter.to_ascii_lowercase()
                ),
            )),
            _ => {}
        }
        out.push((k, def));
    }
    // Values for a number without a synchronisation type: the function stays undefined.
    let strays = process_time
        .into_iter()
        .chain(pre_output)
        .map(|(k, (_, e))| (e.name_pos.line, k, e));
    let mut strays: Vec<_> = strays.collect();
    strays.sort_by_key(|(line, k, _)| (*line, *k));
    let prefix = letter.to_ascii_lowercase();
    for (_, k, e) in strays {
        let msg = match spindle(k) {
            Some((_, sync_name, _)) => {
                diags.push(spindle_shadowed(list, &e, k, sync_name));
                continue;
            }
            None => format!(
                "{} without {prefix}_synch[{k}]: {letter}{k} stays undefined; not used",
                e.name.text
            ),
        };
        diags.push(list.warning_at(&e, e.name_pos, msg));
    }
    out
}

/// `m_synch[3]` and its kin: M3/M4/M5/M19 are the spindle's, configured by `spindel[0].*`.
fn spindle_shadowed(list: &ParamList, e: &Entry, k: u32, sync_name: &str) -> Diagnostic {
    list.warning_at(
        e,
        e.name_pos,
        format!(
            "{}: M{k} is a spindle function, configured by spindel[0].{sync_name} (and its process time); this entry is not used",
            e.name.text
        ),
    )
}

/// A UNS32 value (process times, pre-outputs).
fn u32_value(list: &ParamList, e: &Entry, diags: &mut Vec<Diagnostic>) -> Option<u32> {
    match uint_value(list, e, u64::from(u32::MAX)) {
        Ok(v) => u32::try_from(v).ok(),
        Err(d) => {
            diags.push(d);
            None
        }
    }
}

/// A problem with a synchronisation value: the message, and the character offset into the
/// value text it points at.
struct SyncError {
    offset: usize,
    message: String,
}

/// The synchronisation type an entry gives, with the check of a second column; an error
/// diagnostic (and `None`) when it is not one ncchannel models.
fn sync_value(list: &ParamList, e: &Entry, diags: &mut Vec<Diagnostic>) -> Option<SyncSpec> {
    let name = &e.name.text;
    let at = |offset: usize| Pos {
        line: e.value_pos.line,
        col: e.value_pos.col + offset,
    };
    let parsed = match e.value.kind {
        ValueKind::Word => parse_symbols(&e.value.text),
        ValueKind::Int(v) => match u32::try_from(v) {
            Ok(v) => parse_number(v),
            Err(_) => Err(SyncError {
                offset: 0,
                message: format!("{v} is not a synchronisation type value"),
            }),
        },
        ValueKind::Hex(v) => match u32::try_from(v) {
            Ok(v) => parse_number(v),
            Err(_) => Err(SyncError {
                offset: 0,
                message: format!("{} is larger than a UNS32", e.value.text),
            }),
        },
        _ => Err(SyncError {
            offset: 0,
            message: format!(
                "expected a synchronisation type ({}, PLC_INFO, `|` between them) or its value, found `{}`",
                symbol_names(),
                e.value.text
            ),
        }),
    };
    let spec = match parsed {
        Ok(s) => s,
        Err(err) => {
            diags.push(list.error_at(e, at(err.offset), format!("{name}: {}", err.message)));
            return None;
        }
    };
    // The second column: a value after symbols, symbols after a value. Anything else there
    // is a comment.
    let Some((offset, tail)) = tail_after_value(e) else {
        return Some(spec);
    };
    let other = match e.value.kind {
        ValueKind::Word => hex_token(tail).map(|(text, v)| (text.to_string(), v)),
        _ => parse_symbols(tail.trim_end())
            .ok()
            .map(|s| (tail.trim_end().to_string(), Some(s.value()))),
    };
    match other {
        Some((_, Some(v))) if v == spec.value() => Some(spec),
        Some((text, v)) => {
            let says = match v {
                Some(_) if text.starts_with("0x") || text.starts_with("0X") => {
                    format!("the value after it is {text}")
                }
                Some(v) => format!("`{text}` after it is 0x{v:08X}"),
                None => format!("the value after it, {text}, is larger than a UNS32"),
            };
            diags.push(list.error_at(
                e,
                at(offset),
                format!(
                    "{name}: `{}` is 0x{:08X}, but {says}; the two columns must agree",
                    e.value.text,
                    spec.value()
                ),
            ));
            None
        }
        None => Some(spec),
    }
}

/// The text after the value on the entry's line up to a `(` comment, with its character
/// offset from the value's start; `None` when there is none.
fn tail_after_value(e: &Entry) -> Option<(usize, &str)> {
    let line = e.line_text.as_str();
    let start = line
        .char_indices()
        .nth(e.value_pos.col.checked_sub(1)?)
        .map(|(b, _)| b)?;
    let rest = line.get(start..)?.strip_prefix(e.value.text.as_str())?;
    let trimmed = rest.trim_start_matches([' ', '\t']);
    let tail = trimmed.split('(').next().unwrap_or("");
    if tail.trim().is_empty() {
        return None;
    }
    let skipped = e.value.text.chars().count() + (rest.len() - trimmed.len());
    Some((skipped, tail))
}

/// A `0x…` token at the start of `tail`: its text and its value (`None` past UNS32).
fn hex_token(tail: &str) -> Option<(&str, Option<u32>)> {
    let token = tail.split([' ', '\t']).next()?;
    let digits = token
        .strip_prefix("0x")
        .or_else(|| token.strip_prefix("0X"))?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    Some((token, u32::from_str_radix(digits, 16).ok()))
}

/// `MVS_SVS`, `PLC_INFO | MVS_SVS`: symbols joined by `|`, at most one synchronisation type.
fn parse_symbols(text: &str) -> Result<SyncSpec, SyncError> {
    let mut sync: Option<SyncType> = None;
    let mut plc_info = false;
    let mut offset = 0;
    for part in text.split('|') {
        let lead = part.len() - part.trim_start().len();
        let word = part.trim();
        let here = offset + part[..lead].chars().count();
        offset += part.chars().count() + 1;
        let err = |message: String| SyncError {
            offset: here,
            message,
        };
        if word.is_empty() {
            return Err(err("a name is missing around `|`".to_string()));
        }
        if word.eq_ignore_ascii_case("PLC_INFO") {
            plc_info = true;
            continue;
        }
        if let Some((t, _, _)) = SyncType::ALL
            .iter()
            .find(|(_, n, _)| word.eq_ignore_ascii_case(n))
        {
            match sync {
                Some(first) if first != *t => {
                    return Err(err(format!(
                        "{first} and {t}: two synchronisation types for one function"
                    )))
                }
                _ => sync = Some(*t),
            }
            continue;
        }
        if let Some((n, _)) = UNMODELLED_SYNC
            .iter()
            .find(|(n, _)| word.eq_ignore_ascii_case(n))
        {
            return Err(err(unmodelled(n)));
        }
        return Err(err(format!(
            "`{word}` is not a synchronisation type ({}, PLC_INFO)",
            symbol_names()
        )));
    }
    Ok(SyncSpec {
        sync: sync.unwrap_or(SyncType::NoSynch),
        plc_info,
    })
}

/// `0x00020002`: a type's value, `PLC_INFO` (0x20000) added or not.
fn parse_number(v: u32) -> Result<SyncSpec, SyncError> {
    let rest = v & !PLC_INFO;
    if let Some(sync) = SyncType::from_value(rest) {
        return Ok(SyncSpec {
            sync,
            plc_info: v & PLC_INFO != 0,
        });
    }
    let message = match UNMODELLED_SYNC.iter().find(|(_, x)| *x == Some(rest)) {
        Some((n, _)) => unmodelled(n),
        None => format!(
            "0x{v:08X} is not a synchronisation type ncchannel models ({})",
            SyncType::ALL
                .iter()
                .map(|(_, n, x)| format!("{n} 0x{x:X}"))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    Err(SyncError { offset: 0, message })
}

fn unmodelled(name: &str) -> String {
    format!("{name} is a synchronisation type ncchannel does not model")
}

/// The modelled symbols, for messages.
fn symbol_names() -> String {
    SyncType::ALL
        .iter()
        .map(|(_, n, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}
