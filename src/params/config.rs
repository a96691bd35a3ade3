//! The one entry point: read the start-up list, each channel's list and runtime.toml, combine
//! them into a [`Config`], or refuse with every problem found.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::channel::{interpret_channel, ChannelList};
use super::decoder::{DecoderParams, DecoderSettings};
use super::error::ParamError;
use super::list::{parse_list, read_list, read_list_text, ParamList};
use super::runtime::{read_runtime, RuntimeConfig};
use super::search_path::{list_folder, SearchPath};
use super::startup::{interpret_startup, is_startup_list, StartupList};
use super::zero_offsets::{
    interpret_zero_offsets, is_zero_offset_list, read_zero_offsets, ZeroOffsetTable,
};
use crate::diag::{Diagnostic, Severity};

/// The file name runtime settings are read from, in the start-up list's folder.
pub const RUNTIME_FILE: &str = "runtime.toml";

/// Everything the emulator starts from.
#[derive(Debug, Clone)]
pub struct Config {
    /// The start-up list as given.
    pub startup_list: PathBuf,
    /// The start-up list's entries, unknown ones included (look them up with `get`).
    pub startup: ParamList,
    /// The runtime.toml read, or `None` when absent (built-in defaults).
    pub runtime_file: Option<PathBuf>,
    pub runtime: RuntimeConfig,
    /// One per channel, in channel order (index 0 = channel 1).
    pub channels: Vec<ChannelConfig>,
    /// `tools.lis` next to the start-up list, if present.
    pub tools_file: Option<PathBuf>,
    /// Tool radii by D number, mm (empty without a tool list).
    pub tools: super::tools::ToolRadii,
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
    /// Program search paths, highest priority (0) first.
    pub search_paths: Vec<SearchPath>,
    /// `true` when the channel list's `path[j].*` replaced the start-up list's paths.
    pub paths_from_channel_list: bool,
    pub decoder: DecoderSettings,
    /// The zero-offset list named by the start-up list (`None`: all offsets 0).
    pub zero_offset_list: Option<PathBuf>,
    /// G54 … G59 offsets by group and axis, mm.
    pub zero_offsets: ZeroOffsetTable,
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
    let config = build(list, &mut diags);
    let has_errors = diags.iter().any(|d| d.severity == Severity::Error);
    match config {
        Some(c) if !has_errors => Ok(Config {
            warnings: diags,
            ..c
        }),
        _ => Err(ParamError::Invalid(diags)),
    }
}

/// Check a start-up list (with its channel lists and runtime.toml), a channel list, or a
/// runtime.toml, returning every error and warning. The list kind is decided by content:
/// a start-up list names `kanal_anzahl` or `sda_mds[…]`, a zero-offset list `np_grp[…]`, a
/// tool list `wz[…]`.
pub fn check_list_file(path: &Path) -> Vec<Diagnostic> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
    {
        return read_runtime(path).err().unwrap_or_default();
    }
    let text = match read_list_text(path) {
        Ok(t) => t,
        Err(d) => return vec![d],
    };
    let (list, mut diags) = parse_list(path, &text);
    if is_startup_list(&list) {
        build(list, &mut diags);
    } else if is_zero_offset_list(&list) {
        interpret_zero_offsets(&list, &mut diags);
    } else if super::tools::is_tool_list(&list) {
        super::tools::interpret_tools(&list, &mut diags);
    } else {
        // Cache values are not finished here: the start-up list may switch caching on.
        interpret_channel(list, &mut diags);
    }
    diags
}

/// Interpret everything; `None` when an error made a channel impossible to set up.
fn build(list: ParamList, diags: &mut Vec<Diagnostic>) -> Option<Config> {
    let startup_path = list.file.clone();
    let startup = interpret_startup(list, diags);
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

    let tools_path = list_folder(&startup_path).join(super::tools::TOOLS_FILE);
    let (tools_file, tools) = if tools_path.exists() {
        match super::tools::read_tools(&tools_path, diags) {
            Ok(t) => (Some(tools_path), t),
            Err(e) => {
                diags.push(e);
                (Some(tools_path), Vec::new())
            }
        }
    } else {
        (None, Vec::new())
    };
    let channels = channels(&startup, diags);
    Some(Config {
        startup_list: startup_path,
        startup: startup.list,
        runtime_file,
        runtime: runtime?,
        channels: channels?,
        tools_file,
        tools,
        warnings: Vec::new(),
    })
}

fn channels(startup: &StartupList, diags: &mut Vec<Diagnostic>) -> Option<Vec<ChannelConfig>> {
    let count = startup.channel_count?;
    let mut out = Vec::new();
    // Channels may share one list; read and report it once.
    let mut seen: HashMap<PathBuf, ChannelList> = HashMap::new();
    for i in 0..count {
        // A missing sda_mds[i] was reported by interpret_startup.
        let Some(r) = startup.channel_lists.get(&i) else {
            continue;
        };
        if let Some(chan) = seen.get(&r.path) {
            out.push(combine(startup, i, chan.clone(), diags));
            continue;
        }
        let chan = match read_list(&r.path) {
            Ok((list, errs)) => {
                diags.extend(errs);
                let chan = interpret_channel(list, diags);
                seen.insert(r.path.clone(), chan.clone());
                chan
            }
            Err(e) => {
                diags.push(startup.list.error_at(
                    &r.entry,
                    r.entry.value_pos,
                    format!(
                        "{}: channel list {} cannot be read: {}",
                        r.entry.name.text,
                        r.path.display(),
                        e.message
                    ),
                ));
                continue;
            }
        };
        out.push(combine(startup, i, chan, diags));
    }
    // Zero-offset lists; channels may share one: read and report it once.
    let mut tables: HashMap<PathBuf, Option<ZeroOffsetTable>> = HashMap::new();
    for c in &mut out {
        let Some(r) = startup.zero_offset_list(c.index as u32) else {
            continue;
        };
        let table = tables.entry(r.path.clone()).or_insert_with(|| {
            match read_zero_offsets(&r.path, diags) {
                Ok(t) => Some(t),
                Err(e) => {
                    diags.push(startup.list.error_at(
                        &r.entry,
                        r.entry.value_pos,
                        format!(
                            "{}: zero-offset list {} cannot be read: {}",
                            r.entry.name.text,
                            r.path.display(),
                            e.message
                        ),
                    ));
                    None
                }
            }
        });
        if let Some(t) = table {
            c.zero_offset_list = Some(r.path.clone());
            c.zero_offsets = *t;
        }
    }
    (out.len() == count as usize).then_some(out)
}

fn combine(
    startup: &StartupList,
    i: u32,
    chan: ChannelList,
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
        search_paths,
        paths_from_channel_list,
        decoder: decoder.finish(diags),
        zero_offset_list: None,
        zero_offsets: Default::default(),
        list: chan.list,
    }
}
