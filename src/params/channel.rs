//! A channel list: the streaming program name (P-CHAN-00158), the channel's own program
//! search paths (`path[j].*`, replacing the start-up list's) and decoder overrides.

use super::decoder::{DecoderField, DecoderParams};
use super::list::ParamList;
use super::search_path::{list_folder, PathCollector, PathField, SearchPath};
use super::startup::{shape, warn_duplicates, warn_unknown};
use super::value::{string_value, uint_value};
use crate::diag::Diagnostic;

/// Longest `streaming_prog_file` (ISG FCT-C19 Data streaming: a string of up to 83 characters).
pub const MAX_STREAMING_PROG_CHARS: usize = 83;

/// A channel list, checked.
#[derive(Debug, Clone)]
pub struct ChannelList {
    pub list: ParamList,
    /// `None`: streaming is off (parameter missing or empty).
    pub streaming_prog_file: Option<String>,
    /// `Some` when the list names any `path[j].*`: these replace the start-up list's paths.
    pub search_paths: Option<Vec<SearchPath>>,
    pub decoder: DecoderParams,
}

/// Check a channel list's entries. Problems go to `diags`.
pub fn interpret_channel(list: ParamList, diags: &mut Vec<Diagnostic>) -> ChannelList {
    warn_duplicates(&list, diags);
    let mut streaming_prog_file = None;
    let mut decoder = DecoderParams::default();
    let mut paths = PathCollector::default();

    for e in &list.entries {
        match shape(e).as_slice() {
            [("streaming_prog_file", None)] => {
                match string_value(&list, e, MAX_STREAMING_PROG_CHARS) {
                    Ok(s) if s.is_empty() => streaming_prog_file = None,
                    Ok(s) => streaming_prog_file = Some(s),
                    Err(d) => diags.push(d),
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
                        warn_unknown(&list, e, diags);
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
                        warn_unknown(&list, e, diags);
                        continue;
                    }
                };
                decoder.set(&list, e, field, diags);
            }
            _ => warn_unknown(&list, e, diags),
        }
    }

    let search_paths = if paths.is_empty() {
        None
    } else {
        Some(paths.finish(&list, &list_folder(&list.file), diags))
    };
    ChannelList {
        list,
        streaming_prog_file,
        search_paths,
        decoder,
    }
}
