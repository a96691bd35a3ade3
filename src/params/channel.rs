//! A channel list: the streaming program name (P-CHAN-00158), the implicitly called
//! subroutines (at program start P-CHAN-00119, at program end P-CHAN-00252, at M6
//! P-CHAN-00118, for G800–G819 P-CHAN-00187), the channel's axes (`gruppe[0].achse[j].*`, P-CHAN-00006 / -00035), the
//! channel's own program search paths (`path[j].*`, replacing the start-up list's),
//! decoder overrides, and the technology functions' synchronisation types, process times and
//! pre-outputs (`m_synch[i]` P-CHAN-00041, `h_synch[i]` P-CHAN-00027, `spindel[0].*_synch`,
//! `tool.synch` P-CHAN-00086 …; read by `techno.rs`, TF5200 "M and H functions").

use std::collections::BTreeMap;
use std::path::Path;

use super::catalog::{ListKind, ListSummary, Tally};
use super::decoder::{DecoderField, DecoderParams};
use super::list::{Entry, ParamList};
use super::search_path::{PathCollector, PathField, SearchPath};
use super::startup::{shape, warn_duplicates};
use super::techno::TechnoCollector;
use super::value::{string_value, uint_value};
use crate::diag::Diagnostic;
use crate::vocab::techno::TechnoTable;

/// Longest `streaming_prog_file` (ISG FCT-C19 Data streaming: a string of up to 83 characters);
/// the implicit subroutine names have the same limit (P-CHAN-00118/-00119/-00252: at most 83
/// characters).
pub(crate) const MAX_STREAMING_PROG_CHARS: usize = 83;
/// Longest axis name (P-CHAN-00006: at most 16 characters).
pub(crate) const MAX_AXIS_NAME_CHARS: usize = 16;

/// The global subroutines the channel calls by itself; `None` = no call.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ImplicitSubroutines {
    /// `start_init_prog_file` (P-CHAN-00119): called as the first action of a program.
    pub at_start: Option<String>,
    /// `final_prog_file` (P-CHAN-00252): called at the main program's M02/M30, before it.
    pub at_end: Option<String>,
    /// `m6_prog_file` (P-CHAN-00118): called for M6, as the last action of its block.
    pub at_m6: Option<String>,
    /// `g800_prog_file[i]` (P-CHAN-00187, TF5200 channel parameter "Additional implicit
    /// calls with G8xx"): called for G800 + i, i = 0…19, as the last action of its block.
    pub g800: [Option<String>; G800_CALLS],
}

/// G800–G819: the implicit calls `g800_prog_file[0…19]` configures (P-CHAN-00187).
pub(crate) const G800_CALLS: usize = 20;

/// One axis of the channel's axis group, as the channel list names it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ChannelAxisRef {
    /// `gruppe[0].achse[j].bezeichnung` (P-CHAN-00006) with its line.
    pub name: Option<(String, Entry)>,
    /// `gruppe[0].achse[j].log_achs_nr` (P-CHAN-00035) with its line.
    pub(crate) logical_number: Option<(u16, Entry)>,
}

/// A channel list, checked.
#[derive(Debug, Clone)]
pub(crate) struct ChannelList {
    pub list: ParamList,
    /// `None`: streaming is off (parameter missing or empty).
    pub streaming_prog_file: Option<String>,
    pub implicit: ImplicitSubroutines,
    /// The axes of axis group 0 by index `j`, as written (joined to the axis lists later).
    pub axes: BTreeMap<u32, ChannelAxisRef>,
    /// `Some` when the list names any `path[j].*`: these replace the start-up list's paths.
    pub search_paths: Option<Vec<SearchPath>>,
    pub decoder: DecoderParams,
    /// M/H/S/T synchronisation types, process times and pre-outputs (`params/techno.rs`).
    pub techno: TechnoTable,
    /// `einrechnen_mit_t` (P-CHAN-00014): `T80` also selects `D80`.
    pub t_selects_d: bool,
    /// Entries used, inert and unknown.
    pub summary: ListSummary,
}

/// A program name of at most 83 characters; empty means none.
fn program_name(list: &ParamList, e: &Entry, diags: &mut Vec<Diagnostic>) -> Option<String> {
    match string_value(list, e, MAX_STREAMING_PROG_CHARS) {
        Ok(s) if s.is_empty() => None,
        Ok(s) => Some(s),
        Err(d) => {
            diags.push(d);
            None
        }
    }
}

/// Check a channel list's entries; relative paths are joined to `cnc_dir`, the CNC's working
/// directory. Problems go to `diags`.
pub(crate) fn interpret_channel(
    list: ParamList,
    cnc_dir: &Path,
    diags: &mut Vec<Diagnostic>,
) -> ChannelList {
    warn_duplicates(&list, diags);
    let mut streaming_prog_file = None;
    let mut implicit = ImplicitSubroutines::default();
    let mut axes: BTreeMap<u32, ChannelAxisRef> = BTreeMap::new();
    let mut decoder = DecoderParams::default();
    let mut paths = PathCollector::default();
    let mut tally = Tally::new(ListKind::Channel);
    let mut techno = TechnoCollector::default();
    let (mut start_mode, mut final_mode) = (CallMode::Automatic, CallMode::Automatic);

    for e in &list.entries {
        match shape(e).as_slice() {
            [("streaming_prog_file", None)] => {
                streaming_prog_file = program_name(&list, e, diags);
            }
            [("start_init_prog_file", None)] => implicit.at_start = program_name(&list, e, diags),
            [("final_prog_file", None)] => implicit.at_end = program_name(&list, e, diags),
            [("m6_prog_file", None)] => implicit.at_m6 = program_name(&list, e, diags),
            [("g800_prog_file", Some(i))] if (*i as usize) < G800_CALLS => {
                implicit.g800[*i as usize] = program_name(&list, e, diags);
            }
            [("start_init_prog_file_mode", None)] => start_mode = call_mode(&list, e, diags),
            [("einrechnen_mit_t", None)] => {} // read below
            [("final_prog_file_mode", None)] => final_mode = call_mode(&list, e, diags),
            [("gruppe", Some(0)), ("achse", Some(j)), ("bezeichnung", None)] => {
                match string_value(&list, e, MAX_AXIS_NAME_CHARS) {
                    Ok(s) => axes.entry(*j).or_insert_with(empty_axis).name = Some((s, e.clone())),
                    Err(d) => diags.push(d),
                }
            }
            [("gruppe", Some(0)), ("achse", Some(j)), ("log_achs_nr", None)] => {
                if let Some(n) = logical_axis_number(&list, e, diags) {
                    axes.entry(*j).or_insert_with(empty_axis).logical_number = Some((n, e.clone()));
                }
            }
            [("path", Some(j)), (field, None)] => {
                let field = match *field {
                    "dir" => PathField::Dir,
                    "type" => PathField::Kinds,
                    "priority" => PathField::Priority,
                    "id" => {
                        // Logical path number: the kernel's, meaningless here; checked, not used.
                        if let Err(d) = uint_value(&list, e, u64::from(u16::MAX)) {
                            diags.push(d);
                        }
                        continue;
                    }
                    _ => {
                        tally.not_read(&list, e, diags);
                        continue;
                    }
                };
                paths.add(&list, e, *j, field, diags);
            }
            [("configuration", None), ("decoder", None), (field, None)] => {
                let field = match *field {
                    "function" => DecoderField::Function,
                    "max_cache_number" => DecoderField::MaxCacheNumber,
                    "max_cache_size" => DecoderField::MaxCacheSize,
                    _ => {
                        tally.not_read(&list, e, diags);
                        continue;
                    }
                };
                decoder.set(&list, e, field, diags);
            }
            _ if techno.add(&list, e, diags) => {}
            _ => tally.not_read(&list, e, diags),
        }
    }
    let techno = techno.finish(&list, diags);

    let search_paths = if paths.is_empty() {
        None
    } else {
        Some(paths.finish(&list, cnc_dir, diags))
    };
    let summary = tally.finish(&list);
    // ncchannel has no MDI: a call configured for MDI only is never made.
    if start_mode == CallMode::MdiOnly {
        implicit.at_start = None;
    }
    if final_mode == CallMode::MdiOnly {
        implicit.at_end = None;
    }
    ChannelList {
        // P-CHAN-00014: "T80" then corresponds to "T80 D80" (TF5200 channel parameter).
        t_selects_d: list
            .get("einrechnen_mit_t")
            .is_some_and(|e| flag(&list, e, diags)),
        list,
        streaming_prog_file,
        implicit,
        axes,
        search_paths,
        decoder,
        techno,
        summary,
    }
}

/// When an implicit subroutine is called (P-CHAN-00260 `start_init_prog_file_mode`,
/// P-CHAN-00433 `final_prog_file_mode`): `AUTOMATIC` (the default), `MDI`, or both with `|`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum CallMode {
    /// At NC program start / end (with or without MDI).
    Automatic,
    /// Only in MDI, which ncchannel does not have.
    MdiOnly,
}

fn call_mode(list: &ParamList, e: &Entry, diags: &mut Vec<Diagnostic>) -> CallMode {
    let mut words = e
        .value
        .as_str()
        .split(['|', ' ', '\t'])
        .filter(|w| !w.is_empty())
        .peekable();
    // No name given: AUTOMATIC, the kernel's basic setting.
    let mut automatic = words.peek().is_none();
    for word in words {
        match word {
            "AUTOMATIC" => automatic = true,
            "MDI" => {}
            other => diags.push(list.error_at(
                e,
                e.value_pos,
                format!(
                    "{}: `{other}` is not a call mode (AUTOMATIC, MDI, or both with `|`)",
                    e.name.text
                ),
            )),
        }
    }
    if automatic {
        CallMode::Automatic
    } else {
        CallMode::MdiOnly
    }
}

/// `gruppe[0].achse[j].log_achs_nr` (P-CHAN-00035): 1 … 65535.
fn logical_axis_number(list: &ParamList, e: &Entry, diags: &mut Vec<Diagnostic>) -> Option<u16> {
    match uint_value(list, e, u64::from(u16::MAX)) {
        Ok(0) => {
            diags.push(list.error_at(
                e,
                e.value_pos,
                format!("{}: logical axis number 0 is not allowed", e.name.text),
            ));
            None
        }
        Ok(n) => Some(n as u16),
        Err(d) => {
            diags.push(d);
            None
        }
    }
}

/// A BOOLEAN entry, 0 or 1 (`false` when it is neither: an error).
fn flag(list: &ParamList, e: &Entry, diags: &mut Vec<Diagnostic>) -> bool {
    match uint_value(list, e, 1) {
        Ok(v) => v == 1,
        Err(d) => {
            diags.push(d);
            false
        }
    }
}

fn empty_axis() -> ChannelAxisRef {
    ChannelAxisRef {
        name: None,
        logical_number: None,
    }
}
