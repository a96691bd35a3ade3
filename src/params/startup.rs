//! The start-up list (`startup.lis`, `hochlauf.lis` in German installations): channel count,
//! each channel's list, tool list (`werkz_data[i]`, P-STUP-00010) and zero-offset list
//! (`nullp_data[i]`, P-STUP-00011), the axis lists, program search paths and decoder settings
//! per channel, and the kernel's error text file.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use super::catalog::{ListKind, ListSummary, Tally};
use super::decoder::{DecoderField, DecoderParams};
use super::list::{Entry, ParamList};
use super::search_path::{resolve, PathCollector, PathField, SearchPath};
use super::value::{string_value, uint_value};
use crate::diag::Diagnostic;

/// Channels one kernel runs (ISG: `pfad[i]` with i = 0 ... 11, "maximum number of channels: 12").
pub(crate) const MAX_CHANNELS: u32 = 12;
/// Axis lists one kernel reads (P-STUP-00015: `achs_mds[i]`, i = 0 … 31).
pub(crate) const MAX_AXIS_LISTS: u32 = 32;
/// Longest list path we accept.
const MAX_PATH_CHARS: usize = 256;

/// Where a list (or other file) the start-up list names is and which line named it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ListRef {
    /// Absolute as written, or joined to the CNC's working directory.
    pub path: PathBuf,
    /// The `sda_mds[i]` line, so a missing file is reported there.
    pub entry: Entry,
}

/// The start-up list, checked.
#[derive(Debug, Clone)]
pub(crate) struct StartupList {
    pub list: ParamList,
    /// `kanal_anzahl`; `None` when missing or bad (an error was reported).
    pub(crate) channel_count: Option<u32>,
    pub(crate) channel_lists: BTreeMap<u32, ListRef>,
    /// `pfad[i].*` per channel, sorted by priority.
    pub search_paths: BTreeMap<u32, Vec<SearchPath>>,
    /// `configuration.channel[i].decoder.*` per channel.
    pub decoder: BTreeMap<u32, DecoderParams>,
    /// `nullp_data[i]` (P-STUP-00011) or `zero_offset_list[i]`: channel i's zero-offset list.
    pub(crate) zero_offset_lists: BTreeMap<u32, ListRef>,
    /// `werkz_data[i]` (P-STUP-00010): channel i's tool list.
    pub(crate) tool_lists: BTreeMap<u32, ListRef>,
    /// `zero_offset_list`: the zero-offset list of every channel without its own.
    pub(crate) zero_offset_default: Option<ListRef>,
    /// `achs_mds[i]` (P-STUP-00015): the axis lists, by index.
    pub(crate) axis_lists: BTreeMap<u32, ListRef>,
    /// `default_achs_mds` (P-STUP-00035): the list under every axis list.
    pub(crate) default_axis_list: Option<ListRef>,
    /// `error_text_of_id` (P-STUP-00168): the kernel's error text file.
    pub(crate) error_texts: Option<ListRef>,
    /// `ve_var[i]` (P-STUP-00146): channel i's list of external variables.
    pub(crate) ext_var_lists: BTreeMap<u32, ListRef>,
    /// Entries used, inert and unknown.
    pub summary: ListSummary,
}

/// Does this list look like a start-up list? (It names `kanal_anzahl` or `sda_mds[…]`.)
pub(crate) fn is_startup_list(list: &ParamList) -> bool {
    list.entries.iter().any(|e| {
        matches!(
            e.name.segments.as_slice(),
            [s] if (s.ident == "kanal_anzahl" && s.index.is_none())
                || (s.ident == "sda_mds" && s.index.is_some())
        )
    })
}

/// A name as `(ident, index)` pairs, for slice patterns.
pub(crate) fn shape(e: &Entry) -> Vec<(&str, Option<u32>)> {
    e.name
        .segments
        .iter()
        .map(|s| (s.ident.as_str(), s.index))
        .collect()
}

/// Warn about a name seen before: the later line wins, as in the kernel's list reader.
pub(crate) fn warn_duplicates(list: &ParamList, diags: &mut Vec<Diagnostic>) {
    let mut seen: HashMap<&str, usize> = HashMap::new();
    for e in &list.entries {
        if let Some(first) = seen.insert(e.name.text.as_str(), e.name_pos.line) {
            diags.push(list.warning_at(
                e,
                e.name_pos,
                format!(
                    "{} is set again (first on line {first}); this later value is used",
                    e.name.text
                ),
            ));
        }
    }
}

/// Check the start-up list's entries; relative paths are joined to `cnc_dir`, the CNC's
/// working directory. Problems go to `diags`; the result holds what was good.
pub(crate) fn interpret_startup(
    list: ParamList,
    cnc_dir: &Path,
    diags: &mut Vec<Diagnostic>,
) -> StartupList {
    warn_duplicates(&list, diags);
    let base = cnc_dir.to_path_buf();
    let channel_count = read_channel_count(&list, diags);
    // Without a valid count, indices are still checked against the kernel's maximum.
    let bound = channel_count.unwrap_or(MAX_CHANNELS);

    let mut g = Gathered {
        tally: Some(Tally::new(ListKind::Startup)),
        ..Gathered::default()
    };
    for e in &list.entries {
        let s = shape(e);
        if channel_out_of_range(&list, e, &s, bound, channel_count, diags) {
            continue;
        }
        g.take(&list, &base, e, &s, diags);
    }
    let Gathered {
        channel_lists,
        zero_offset_lists,
        zero_offset_default,
        tool_lists,
        axis_lists,
        default_axis_list,
        error_texts,
        ext_var_lists,
        decoder,
        collectors,
        tally,
    } = g;
    let summary = tally
        .unwrap_or_else(|| Tally::new(ListKind::Startup))
        .finish(&list);

    let search_paths = collectors
        .into_iter()
        .map(|(i, c)| (i, c.finish(&list, &base, diags)))
        .collect();
    check_channel_lists(&list, channel_count, &channel_lists, diags);

    StartupList {
        list,
        channel_count,
        channel_lists,
        search_paths,
        decoder,
        zero_offset_lists,
        zero_offset_default,
        tool_lists,
        axis_lists,
        default_axis_list,
        error_texts,
        ext_var_lists,
        summary,
    }
}

/// Step 1: `kanal_anzahl`, which must be there and name at least one channel.
fn read_channel_count(list: &ParamList, diags: &mut Vec<Diagnostic>) -> Option<u32> {
    match list.get("kanal_anzahl") {
        None => {
            diags.push(Diagnostic::error(
                &list.file,
                1,
                1,
                None,
                "kanal_anzahl (number of channels) is missing from the start-up list",
            ));
            None
        }
        Some(e) => match uint_value(list, e, u64::from(MAX_CHANNELS)) {
            Ok(0) => {
                diags.push(list.error_at(
                    e,
                    e.value_pos,
                    "kanal_anzahl: at least one channel is needed",
                ));
                None
            }
            Ok(n) => Some(n as u32),
            Err(d) => {
                diags.push(d);
                None
            }
        },
    }
}

/// Step 2a: a known per-channel name whose channel index is not below the count (or the
/// kernel's maximum) is an error and the entry is skipped (`true`).
fn channel_out_of_range(
    list: &ParamList,
    e: &Entry,
    s: &[(&str, Option<u32>)],
    bound: u32,
    channel_count: Option<u32>,
    diags: &mut Vec<Diagnostic>,
) -> bool {
    if let [("achs_mds", Some(i))] = s {
        if *i >= MAX_AXIS_LISTS {
            diags.push(list.error_at(
                e,
                e.name_pos,
                format!(
                    "{}: axis list index {i} is not below the maximum of {MAX_AXIS_LISTS}",
                    e.name.text
                ),
            ));
            return true;
        }
    }
    let channel = match s {
        [("sda_mds" | "zero_offset_list" | "nullp_data" | "werkz_data" | "ve_var", Some(i))]
        | [("pfad", Some(i)), (_, Some(_))]
        | [("configuration", None), ("channel", Some(i)), ..] => Some(*i),
        _ => None,
    };
    if let Some(i) = channel {
        if i >= bound {
            let why = match channel_count {
                Some(n) => format!("not below kanal_anzahl {n}"),
                None => format!("not below the maximum of {MAX_CHANNELS} channels"),
            };
            // Only indices of names we know; an unknown name is a warning below.
            if is_known_startup_name(s) {
                diags.push(list.error_at(
                    e,
                    e.name_pos,
                    format!("{}: channel index {i} is {why}", e.name.text),
                ));
                return true;
            }
        }
    }
    false
}

/// What the entries of a start-up list name, gathered entry by entry (step 2).
#[derive(Default)]
struct Gathered<'l> {
    channel_lists: BTreeMap<u32, ListRef>,
    zero_offset_lists: BTreeMap<u32, ListRef>,
    zero_offset_default: Option<ListRef>,
    tool_lists: BTreeMap<u32, ListRef>,
    axis_lists: BTreeMap<u32, ListRef>,
    default_axis_list: Option<ListRef>,
    error_texts: Option<ListRef>,
    ext_var_lists: BTreeMap<u32, ListRef>,
    decoder: BTreeMap<u32, DecoderParams>,
    collectors: BTreeMap<u32, PathCollector<'l>>,
    tally: Option<Tally>,
}

impl<'l> Gathered<'l> {
    /// Step 2b: one entry (its channel index already checked) read into what it names;
    /// a name the emulator does not know is warned about and kept out.
    fn take(
        &mut self,
        list: &ParamList,
        base: &Path,
        e: &'l Entry,
        s: &[(&str, Option<u32>)],
        diags: &mut Vec<Diagnostic>,
    ) {
        match s {
            [("kanal_anzahl", None)] => {}
            [("sda_mds", Some(i))] => {
                if let Some(r) = file_ref(list, base, e, "channel list", diags) {
                    self.channel_lists.insert(*i, r);
                }
            }
            [("zero_offset_list", index)] => self.zero_offset_list(list, base, e, *index, diags),
            // P-STUP-00011: "Name of the list file for the zero point data", per channel.
            [("nullp_data", Some(i))] => self.zero_offset_list(list, base, e, Some(*i), diags),
            // P-STUP-00010: "Name of the list file for the tool data", per channel.
            [("werkz_data", Some(i))] => {
                if let Some(r) = file_ref(list, base, e, "tool list", diags) {
                    self.tool_lists.insert(*i, r);
                }
            }
            [("achs_mds", Some(i))] => {
                if let Some(r) = file_ref(list, base, e, "axis list", diags) {
                    self.axis_lists.insert(*i, r);
                }
            }
            [("default_achs_mds", None)] => {
                self.default_axis_list = file_ref(list, base, e, "default axis list", diags);
            }
            // P-STUP-00168; `error_message_texts` is the name some installations write.
            [("error_text_of_id" | "error_message_texts", None)] => {
                self.error_texts = file_ref(list, base, e, "error text file", diags);
            }
            // P-STUP-00146's default is a blank string: no list, V.E. stay free.
            [("ve_var", Some(_))] if matches!(e.value.text.trim(), "" | "\"\"") => {}
            [("ve_var", Some(i))] => {
                if let Some(r) = file_ref(list, base, e, "external variable list", diags) {
                    self.ext_var_lists.insert(*i, r);
                }
            }
            [("pfad", Some(i)), (field, Some(j))] => self.path(list, e, *i, field, *j, diags),
            [("configuration", None), ("channel", Some(i)), ("decoder", None), (field, None)] => {
                let field = match *field {
                    "function" => DecoderField::Function,
                    "max_cache_number" => DecoderField::MaxCacheNumber,
                    "max_cache_size" => DecoderField::MaxCacheSize,
                    _ => return self.not_read(list, e, diags),
                };
                self.decoder
                    .entry(*i)
                    .or_default()
                    .set(list, e, field, diags);
            }
            _ => self.not_read(list, e, diags),
        }
    }

    fn not_read(&mut self, list: &ParamList, e: &Entry, diags: &mut Vec<Diagnostic>) {
        if let Some(t) = &mut self.tally {
            t.not_read(list, e, diags);
        }
    }

    /// `nullp_data[i]` / `zero_offset_list[i]` (channel i's) or `zero_offset_list` (every
    /// other channel's).
    fn zero_offset_list(
        &mut self,
        list: &ParamList,
        base: &Path,
        e: &Entry,
        index: Option<u32>,
        diags: &mut Vec<Diagnostic>,
    ) {
        let Some(r) = file_ref(list, base, e, "zero-offset list", diags) else {
            return;
        };
        match index {
            Some(i) => {
                self.zero_offset_lists.insert(i, r);
            }
            None => self.zero_offset_default = Some(r),
        }
    }

    /// `pfad[i].<field>[j]`: channel i's search path j (folder, types, priority).
    fn path(
        &mut self,
        list: &ParamList,
        e: &'l Entry,
        i: u32,
        field: &str,
        j: u32,
        diags: &mut Vec<Diagnostic>,
    ) {
        let field = match field {
            "prg" => Some(PathField::Dir),
            "typ" => Some(PathField::Kinds),
            "prioritaet" => Some(PathField::Priority),
            "log_nr" => None,
            _ => return self.not_read(list, e, diags),
        };
        match field {
            Some(f) => self
                .collectors
                .entry(i)
                .or_default()
                .add(list, e, j, f, diags),
            // Logical path number: the kernel's, meaningless here; checked, not used.
            None => {
                if let Err(d) = uint_value(list, e, u64::from(u16::MAX)) {
                    diags.push(d);
                }
            }
        }
    }
}

/// A file the start-up list names: a non-empty path, joined to the CNC's working directory.
fn file_ref(
    list: &ParamList,
    base: &Path,
    e: &Entry,
    what: &str,
    diags: &mut Vec<Diagnostic>,
) -> Option<ListRef> {
    match string_value(list, e, MAX_PATH_CHARS) {
        Ok(p) if p.is_empty() => {
            diags.push(list.error_at(
                e,
                e.value_pos,
                format!("{}: empty {what} path", e.name.text),
            ));
            None
        }
        Ok(p) => Some(ListRef {
            path: resolve(base, &p),
            entry: e.clone(),
        }),
        Err(d) => {
            diags.push(d);
            None
        }
    }
}

/// Step 3: with a valid count, every channel below it needs its channel list.
fn check_channel_lists(
    list: &ParamList,
    channel_count: Option<u32>,
    channel_lists: &BTreeMap<u32, ListRef>,
    diags: &mut Vec<Diagnostic>,
) {
    if let (Some(n), Some(count_entry)) = (channel_count, list.get("kanal_anzahl")) {
        for i in 0..n {
            if !channel_lists.contains_key(&i) {
                diags.push(list.error_at(
                    count_entry,
                    count_entry.value_pos,
                    format!(
                        "kanal_anzahl {n}: channel {} has no channel list (sda_mds[{i}] is missing)",
                        i + 1
                    ),
                ));
            }
        }
    }
}

impl StartupList {
    /// The zero-offset list of channel `i` (0-based), if the start-up list names one.
    pub fn zero_offset_list(&self, i: u32) -> Option<&ListRef> {
        self.zero_offset_lists
            .get(&i)
            .or(self.zero_offset_default.as_ref())
    }
}

fn is_known_startup_name(s: &[(&str, Option<u32>)]) -> bool {
    matches!(
        s,
        [(
            "sda_mds" | "zero_offset_list" | "nullp_data" | "werkz_data" | "ve_var" | "achs_mds",
            Some(_)
        )] | [
            ("pfad", Some(_)),
            ("prg" | "typ" | "prioritaet" | "log_nr", Some(_))
        ] | [
            ("configuration", None),
            ("channel", Some(_)),
            ("decoder", None),
            ("function" | "max_cache_number" | "max_cache_size", None)
        ]
    )
}
