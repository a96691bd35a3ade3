//! The one entry point: read runtime.toml, the start-up list, each channel's list, the axis
//! lists and the error text file, combine them into a [`Config`], or refuse with every
//! problem found.
//!
//! Relative paths in lists are joined to the CNC's working directory, as the kernel does:
//! runtime.toml's `cnc_dir` if set, else the start-up list's folder — or, when that folder is
//! called `listen` (the installation layout: `listen/`, `prg/`, `error/` side by side), its
//! parent.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::axes::{interpret_axis, is_axis_list, tally_axis_list, AxisList};
use super::catalog::ListSummary;
use super::channel::{interpret_channel, ChannelList, ImplicitSubroutines};
use super::decoder::{DecoderParams, DecoderSettings};
use super::error::ParamError;
use super::error_texts::{read_error_texts, ErrorTexts};
use super::ext_vars::{interpret_ext_vars, is_ext_var_list, read_ext_vars, ExtVarTable};
use super::list::{parse_list, read_list, read_list_text, Entry, ParamList};
use super::runtime::{read_runtime, AxisConfig, RuntimeConfig};
use super::search_path::{list_folder, SearchPath};
use super::startup::{interpret_startup, is_startup_list, ListRef, StartupList};
use super::tools::{read_tools, ToolFormat, ToolTable};
use super::zero_offsets::{
    interpret_zero_offsets, is_zero_offset_list, read_zero_offsets, ZeroOffsetTable,
};
use crate::diag::{Diagnostic, Severity};
use crate::vocab::techno::TechnoTable;

/// The file name runtime settings are read from, in the start-up list's folder.
pub const RUNTIME_FILE: &str = "runtime.toml";
/// The folder name of an installation's lists; the CNC's working directory is its parent.
pub(crate) const LIST_FOLDER: &str = "listen";

/// Everything the emulator starts from.
#[derive(Debug, Clone)]
pub struct Config {
    /// The start-up list as given.
    pub startup_list: PathBuf,
    /// The start-up list's entries, unknown ones included (look them up with `get`).
    pub startup: ParamList,
    /// The CNC's working directory: relative paths in the lists are joined to it.
    pub cnc_dir: PathBuf,
    /// The runtime.toml read, or `None` when absent (built-in defaults).
    pub runtime_file: Option<PathBuf>,
    pub runtime: RuntimeConfig,
    /// One per channel, in channel order (index 0 = channel 1).
    pub channels: Vec<ChannelConfig>,
    /// `tools.lis` next to the start-up list, if present and the start-up list names no
    /// `werkz_data[i]` (ncchannel's older tool file, the fallback).
    pub tools_file: Option<PathBuf>,
    /// Its tool data by D number (empty without it); every channel without a `werkz_data[i]`
    /// uses it.
    pub tools: ToolTable,
    /// The error text file the start-up list names (`error_text_of_id`, P-STUP-00168).
    pub error_text_file: Option<PathBuf>,
    /// Its texts by error id; `None`: ncchannel's own texts.
    pub(crate) error_texts: Option<Arc<ErrorTexts>>,
    /// Every list read, with how many entries were used, inert and unknown.
    pub lists: Vec<ListSummary>,
    /// Warnings found on the way (unknown entries, values without effect).
    pub warnings: Vec<Diagnostic>,
}

/// One channel's settings from start-up list and channel list combined.
#[derive(Debug, Clone)]
pub struct ChannelConfig {
    /// 0-based channel index.
    pub index: usize,
    pub list_path: PathBuf,
    /// Name of the virtual streaming program (P-CHAN-00158); `None` = streaming off.
    pub streaming_prog_file: Option<String>,
    /// The subroutines called at program start and end and at M6.
    pub implicit: ImplicitSubroutines,
    /// The channel's axes: from the axis lists where the start-up list names any, else from
    /// runtime.toml. Motion, the 21897 limit check and the ADS axis objects read this table.
    pub axes: Vec<AxisConfig>,
    /// Program search paths, highest priority (0) first.
    pub search_paths: Vec<SearchPath>,
    /// `true` when the channel list's `path[j].*` replaced the start-up list's paths.
    pub paths_from_channel_list: bool,
    pub decoder: DecoderSettings,
    /// The zero-offset list named by the start-up list (`None`: all offsets 0).
    pub zero_offset_list: Option<PathBuf>,
    /// G54 … G59 offsets by group and axis, mm.
    pub(crate) zero_offsets: ZeroOffsetTable,
    /// The tool list this channel's D words select from: `werkz_data[i]` (P-STUP-00010), else
    /// `tools.lis`; `None`: no tool data (only D0).
    pub tool_list: Option<PathBuf>,
    /// Its tool data by D number, mm.
    pub tools: ToolTable,
    /// `einrechnen_mit_t` (P-CHAN-00014): a T word also selects the D data set of the same
    /// number.
    pub t_selects_d: bool,
    /// M/H/S/T functions: synchronisation types, process times, pre-outputs.
    pub techno: TechnoTable,
    /// The V.E. list the start-up list names (`ve_var[i]`, P-STUP-00146) and its leaves;
    /// `None`: V.E. variables are free (made by whoever writes them first).
    pub ext_vars: Option<Arc<ExtVarTable>>,
    /// The channel list's entries, unknown ones included.
    pub list: ParamList,
}

impl ChannelConfig {
    /// Folders searched for main programs, in search order.
    pub fn main_program_paths(&self) -> impl Iterator<Item = &Path> {
        self.search_paths
            .iter()
            .filter(|p| p.serves_main_programs())
            .map(|p| p.dir.as_path())
    }

    /// Folders searched for global subroutines and cycles, in search order.
    pub fn subroutine_paths(&self) -> impl Iterator<Item = &Path> {
        self.search_paths
            .iter()
            .filter(|p| p.serves_subroutines())
            .map(|p| p.dir.as_path())
    }
}

/// Load the start-up list, its channel lists and runtime.toml (from the start-up list's
/// folder; built-in defaults when absent). Any error refuses the whole configuration.
pub fn load(startup_list: &Path) -> Result<Config, ParamError> {
    let (list, mut diags) = read_list(startup_list).map_err(ParamError::File)?;
    let mut lists = Vec::new();
    let config = build(list, &mut diags, &mut lists);
    let has_errors = diags.iter().any(|d| d.severity == Severity::Error);
    match config {
        Some(c) if !has_errors => Ok(Config {
            warnings: diags,
            lists,
            ..c
        }),
        _ => Err(ParamError::Invalid(diags)),
    }
}

/// Check a start-up list (with every list and file it names, and runtime.toml), a channel
/// list, an axis list, a tool or zero-offset list, or a runtime.toml, returning every error
/// and warning.
pub fn check_list_file(path: &Path) -> Vec<Diagnostic> {
    check_list_file_summarized(path).0
}

/// [`check_list_file`], with the used/inert/unknown counts of every list read. The list kind
/// is decided by content: a start-up list names `kanal_anzahl` or `sda_mds[…]`, a zero-offset
/// list `np_grp[…]`, a tool list `wz[…]`, an axis list `kopf.*`, `kenngr.*` or `getriebe[…]`.
pub(crate) fn check_list_file_summarized(path: &Path) -> (Vec<Diagnostic>, Vec<ListSummary>) {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
    {
        return (read_runtime(path).err().unwrap_or_default(), Vec::new());
    }
    let text = match read_list_text(path) {
        Ok(t) => t,
        Err(d) => return (vec![d], Vec::new()),
    };
    let (list, mut diags) = parse_list(path, &text);
    let mut lists = Vec::new();
    if is_startup_list(&list) {
        build(list, &mut diags, &mut lists);
    } else if is_zero_offset_list(&list) {
        lists.push(interpret_zero_offsets(&list, &mut diags).1);
    } else if super::tools::is_tool_list(&list) {
        lists.push(super::tools::interpret_tools(&list, ToolFormat::Kernel, &mut diags).1);
    } else if is_ext_var_list(&list) {
        lists.push(interpret_ext_vars(&list, &mut diags).1);
    } else if is_axis_list(&list) {
        lists.push(tally_axis_list(&list, &mut diags));
        interpret_axis(None, &list, &mut diags);
    } else {
        // Cache values are not finished here: the start-up list may switch caching on.
        let folder = list_folder(path);
        lists.push(interpret_channel(list, &folder, &mut diags).summary);
    }
    (diags, lists)
}

/// The CNC's working directory: `cnc_dir` of runtime.toml (joined to runtime.toml's folder),
/// else the start-up list's folder, or its parent when that folder is `listen`.
pub fn cnc_dir(startup_list: &Path, runtime: Option<&RuntimeConfig>) -> PathBuf {
    let folder = list_folder(startup_list);
    if let Some(dir) = runtime.and_then(|r| r.cnc_dir.as_deref()) {
        return super::search_path::resolve(&folder, &dir.to_string_lossy());
    }
    let is_listen = folder
        .file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n.eq_ignore_ascii_case(LIST_FOLDER));
    match folder.parent() {
        Some(p) if is_listen && !p.as_os_str().is_empty() => p.to_path_buf(),
        Some(_) if is_listen => PathBuf::from("."),
        _ => folder,
    }
}

/// Interpret everything; `None` when an error made a channel impossible to set up.
fn build(
    list: ParamList,
    diags: &mut Vec<Diagnostic>,
    lists: &mut Vec<ListSummary>,
) -> Option<Config> {
    let startup_path = list.file.clone();
    let runtime_path = list_folder(&startup_path).join(RUNTIME_FILE);
    let (runtime_file, runtime) = if runtime_path.exists() {
        match read_runtime(&runtime_path) {
            Ok(r) => (Some(runtime_path), Some(r)),
            Err(errs) => {
                diags.extend(errs);
                (Some(runtime_path), None)
            }
        }
    } else {
        (None, Some(RuntimeConfig::default()))
    };
    let cnc_dir = cnc_dir(&startup_path, runtime.as_ref());
    let startup = interpret_startup(list, &cnc_dir, diags);
    lists.push(startup.summary.clone());

    let tools_path = list_folder(&startup_path).join(super::tools::TOOLS_FILE);
    let (tools_file, tools) = if startup.tool_lists.is_empty() && tools_path.exists() {
        match read_tools(&tools_path, ToolFormat::Ncchannel, diags) {
            Ok((t, summary)) => {
                lists.push(summary);
                (Some(tools_path), t)
            }
            Err(e) => {
                diags.push(e);
                (Some(tools_path), Vec::new())
            }
        }
    } else {
        (None, Vec::new())
    };
    let (error_text_file, error_texts) = match &startup.error_texts {
        Some(r) => match read_error_texts(&r.path) {
            Ok(t) => (Some(r.path.clone()), Some(Arc::new(t))),
            Err(e) => {
                diags.push(cannot_read(
                    &startup.list,
                    &r.entry,
                    "error text file",
                    &r.path,
                    &e,
                ));
                (Some(r.path.clone()), None)
            }
        },
        None => (None, None),
    };
    let axis_lists = axis_lists(&startup, diags, lists);
    if let (false, Some(rt), Some(file)) = (axis_lists.is_empty(), &runtime, &runtime_file) {
        if rt.axes != RuntimeConfig::default().axes {
            diags.push(Diagnostic::warning(
                file,
                1,
                1,
                None,
                "[[axes]] is not used: the start-up list names axis lists (achs_mds[i]), \
                 and the axes come from them",
            ));
        }
    }
    let channels = match &runtime {
        Some(rt) => channels(&startup, &axis_lists, rt, &cnc_dir, diags, lists),
        None => None,
    }
    .map(|mut c| {
        channel_tools(
            &startup,
            &mut c,
            tools_file.as_deref(),
            &tools,
            diags,
            lists,
        );
        c
    });
    Some(Config {
        startup_list: startup_path,
        startup: startup.list,
        cnc_dir,
        runtime_file,
        runtime: runtime?,
        channels: channels?,
        tools_file,
        tools,
        error_text_file,
        error_texts,
        lists: Vec::new(),
        warnings: Vec::new(),
    })
}

/// A file named by `entry` could not be read: the error at the entry's value.
/// A list the start-up list names for a channel (`r`), read once however many channels name
/// its file (`tables`, by path) and reported once; `None` when it cannot be read (the error,
/// at the naming entry, is in `diags`).
fn read_once<T: Clone>(
    tables: &mut HashMap<PathBuf, Option<T>>,
    startup: &StartupList,
    r: &ListRef,
    what: &str,
    diags: &mut Vec<Diagnostic>,
    lists: &mut Vec<ListSummary>,
    read: impl FnOnce(&Path, &mut Vec<Diagnostic>) -> Result<(T, ListSummary), Diagnostic>,
) -> Option<T> {
    tables
        .entry(r.path.clone())
        .or_insert_with(|| match read(&r.path, diags) {
            Ok((t, summary)) => {
                lists.push(summary);
                Some(t)
            }
            Err(e) => {
                diags.push(cannot_read(&startup.list, &r.entry, what, &r.path, &e));
                None
            }
        })
        .clone()
}

fn cannot_read(
    list: &ParamList,
    entry: &Entry,
    what: &str,
    path: &Path,
    e: &Diagnostic,
) -> Diagnostic {
    list.error_at(
        entry,
        entry.value_pos,
        format!(
            "{}: {what} {} cannot be read: {}",
            entry.name.text,
            path.display(),
            e.message
        ),
    )
}

/// Step: the axis lists (`achs_mds[i]` over `default_achs_mds`), in index order, each read
/// once; a logical axis number given twice is an error.
fn axis_lists(
    startup: &StartupList,
    diags: &mut Vec<Diagnostic>,
    lists: &mut Vec<ListSummary>,
) -> Vec<AxisList> {
    if startup.axis_lists.is_empty() {
        return Vec::new();
    }
    let default = startup
        .default_axis_list
        .as_ref()
        .and_then(|r| match read_list(&r.path) {
            Ok((list, errs)) => {
                diags.extend(errs);
                lists.push(tally_axis_list(&list, diags));
                Some(list)
            }
            Err(e) => {
                diags.push(cannot_read(
                    &startup.list,
                    &r.entry,
                    "default axis list",
                    &r.path,
                    &e,
                ));
                None
            }
        });
    let mut out: Vec<AxisList> = Vec::new();
    for r in startup.axis_lists.values() {
        let list = match read_list(&r.path) {
            Ok((list, errs)) => {
                diags.extend(errs);
                list
            }
            Err(e) => {
                diags.push(cannot_read(
                    &startup.list,
                    &r.entry,
                    "axis list",
                    &r.path,
                    &e,
                ));
                continue;
            }
        };
        lists.push(tally_axis_list(&list, diags));
        let axis = interpret_axis(default.as_ref(), &list, diags);
        if let Some(first) = out.iter().find(|a| a.logical_number == axis.logical_number) {
            diags.push(startup.list.error_at(
                &r.entry,
                r.entry.value_pos,
                format!(
                    "{}: kopf.achs_nr {} is also the logical number of {} (P-AXIS-00016: unique)",
                    r.entry.name.text,
                    axis.logical_number,
                    first.file.display()
                ),
            ));
            continue;
        }
        out.push(axis);
    }
    out
}

fn channels(
    startup: &StartupList,
    axis_lists: &[AxisList],
    runtime: &RuntimeConfig,
    cnc_dir: &Path,
    diags: &mut Vec<Diagnostic>,
    lists: &mut Vec<ListSummary>,
) -> Option<Vec<ChannelConfig>> {
    let count = startup.channel_count?;
    let mut out = Vec::new();
    // Channels may share one list; read and report it once.
    let mut seen: HashMap<PathBuf, ChannelList> = HashMap::new();
    for i in 0..count {
        // A missing sda_mds[i] was reported by interpret_startup.
        let Some(r) = startup.channel_lists.get(&i) else {
            continue;
        };
        let chan = match seen.get(&r.path) {
            Some(chan) => chan.clone(),
            None => match read_list(&r.path) {
                Ok((list, errs)) => {
                    diags.extend(errs);
                    let chan = interpret_channel(list, cnc_dir, diags);
                    lists.push(chan.summary.clone());
                    seen.insert(r.path.clone(), chan.clone());
                    chan
                }
                Err(e) => {
                    diags.push(cannot_read(
                        &startup.list,
                        &r.entry,
                        "channel list",
                        &r.path,
                        &e,
                    ));
                    continue;
                }
            },
        };
        let axes = super::axes::channel_axes(&chan, axis_lists, runtime, diags)?;
        out.push(combine(startup, i, chan, axes, diags));
    }
    // Zero-offset lists; channels may share one: read and report it once.
    let mut tables = HashMap::new();
    for c in &mut out {
        let Some(r) = startup.zero_offset_list(c.index as u32) else {
            continue;
        };
        if let Some(t) = read_once(
            &mut tables,
            startup,
            r,
            "zero-offset list",
            diags,
            lists,
            read_zero_offsets,
        ) {
            c.zero_offset_list = Some(r.path.clone());
            c.zero_offsets = t;
        }
    }
    ext_var_lists(startup, &mut out, diags, lists);
    (out.len() == count as usize).then_some(out)
}

/// Step: each channel's tool list, `werkz_data[i]` (channels may share one: read and reported
/// once), else the `tools.lis` fallback.
fn channel_tools(
    startup: &StartupList,
    channels: &mut [ChannelConfig],
    fallback_file: Option<&Path>,
    fallback: &ToolTable,
    diags: &mut Vec<Diagnostic>,
    lists: &mut Vec<ListSummary>,
) {
    let mut tables = HashMap::new();
    for c in channels {
        let Some(r) = startup.tool_lists.get(&(c.index as u32)) else {
            c.tool_list = fallback_file.map(Path::to_path_buf);
            c.tools = fallback.clone();
            continue;
        };
        if let Some(t) = read_once(
            &mut tables,
            startup,
            r,
            "tool list",
            diags,
            lists,
            |p, d| read_tools(p, ToolFormat::Kernel, d),
        ) {
            c.tool_list = Some(r.path.clone());
            c.tools = t;
        }
    }
}

fn combine(
    startup: &StartupList,
    i: u32,
    chan: ChannelList,
    axes: Vec<AxisConfig>,
    diags: &mut Vec<Diagnostic>,
) -> ChannelConfig {
    let start_decoder = startup.decoder.get(&i).cloned().unwrap_or_default();
    let decoder: DecoderParams = start_decoder.overlay(chan.decoder);
    let paths_from_channel_list = chan.search_paths.is_some();
    let search_paths = chan
        .search_paths
        .or_else(|| startup.search_paths.get(&i).cloned())
        .unwrap_or_default();
    ChannelConfig {
        index: i as usize,
        list_path: chan.list.file.clone(),
        streaming_prog_file: chan.streaming_prog_file,
        implicit: chan.implicit,
        axes,
        search_paths,
        paths_from_channel_list,
        decoder: decoder.finish(diags),
        zero_offset_list: None,
        zero_offsets: Default::default(),
        tool_list: None,
        tools: Vec::new(),
        t_selects_d: chan.t_selects_d,
        techno: chan.techno,
        ext_vars: None,
        list: chan.list,
    }
}

/// Step: each channel's V.E. list (`ve_var[i]`); channels may share one: read and report it
/// once, and share its table.
fn ext_var_lists(
    startup: &StartupList,
    out: &mut [ChannelConfig],
    diags: &mut Vec<Diagnostic>,
    lists: &mut Vec<ListSummary>,
) {
    let mut tables = HashMap::new();
    for c in out {
        let Some(r) = startup.ext_var_lists.get(&(c.index as u32)) else {
            continue;
        };
        c.ext_vars = read_once(
            &mut tables,
            startup,
            r,
            "external variable list",
            diags,
            lists,
            |p, d| read_ext_vars(p, d).map(|(t, summary)| (Arc::new(t), summary)),
        );
    }
}
