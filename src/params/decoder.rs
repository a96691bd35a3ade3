//! Decoder start-up settings: `…decoder.function` (P-STUP-00050 / P-CHAN-00500) and the
//! file cache sizes `…decoder.max_cache_number|max_cache_size` (P-STUP-00051/52, P-CHAN-00503/04).

use std::path::PathBuf;

use super::list::{Entry, ParamList, Pos};
use super::value::{string_value, uint_value};
use crate::diag::Diagnostic;

/// Switches file caching (`#CACHE LOAD`) on.
pub const FCT_USE_CACHED_FILES: &str = "FCT_USE_CACHED_FILES";
/// Function names the kernel documents. Only caching changes the emulator's behaviour.
pub(crate) const KNOWN_FUNCTIONS: [&str; 3] = [
    "FCT_DEFAULT",
    FCT_USE_CACHED_FILES,
    "FCT_VOL_COMP_COMPUTATION",
];

/// Cache files when caching is on and `max_cache_number` is not given.
pub(crate) const DEFAULT_CACHE_FILES: u32 = 4;
/// Bytes per cache file when caching is on and `max_cache_size` is not given.
pub(crate) const DEFAULT_CACHE_FILE_BYTES: u32 = 4096;
/// Plausibility bound: the kernel allows UNS32, but the emulator holds cached programs in
/// memory, so more files than this is refused as a typo rather than risked.
pub(crate) const MAX_CACHE_FILES: u32 = 1024;
/// Plausibility bound on one cache file (64 MiB), same reason.
pub(crate) const MAX_CACHE_FILE_BYTES: u32 = 64 * 1024 * 1024;
/// Longest function string we read.
const MAX_FUNCTION_CHARS: usize = 1024;

/// The file cache of one channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CacheSettings {
    /// `FCT_USE_CACHED_FILES` is set; `#CACHE LOAD` is allowed.
    pub enabled: bool,
    /// How many programs the cache holds at once.
    pub max_files: u32,
    /// Largest program the cache takes, in bytes.
    pub max_file_bytes: u32,
}

/// The decoder settings of one channel after start-up and channel list are combined.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DecoderSettings {
    /// Every `FCT_…` name set, in list order.
    pub functions: Vec<String>,
    pub cache: CacheSettings,
}

/// Where a value came from, so a later warning can point at it.
#[derive(Debug, Clone)]
struct Origin {
    file: PathBuf,
    pos: Pos,
    line_text: String,
    name: String,
}

impl Origin {
    fn of(list: &ParamList, e: &Entry) -> Self {
        Origin {
            file: list.file.clone(),
            pos: e.name_pos,
            line_text: e.line_text.clone(),
            name: e.name.text.clone(),
        }
    }
}

/// Which decoder parameter an entry sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum DecoderField {
    Function,
    MaxCacheNumber,
    MaxCacheSize,
}

/// The decoder values one list sets; unset fields stay `None` so a channel list overrides
/// only what it names.
#[derive(Debug, Clone, Default)]
pub(crate) struct DecoderParams {
    functions: Option<Vec<String>>,
    max_cache_number: Option<(u32, Origin)>,
    max_cache_size: Option<(u32, Origin)>,
}

impl DecoderParams {
    /// Record one entry; a bad value is an error in `diags`.
    pub fn set(
        &mut self,
        list: &ParamList,
        e: &Entry,
        field: DecoderField,
        diags: &mut Vec<Diagnostic>,
    ) {
        match field {
            DecoderField::Function => {
                if let Some(f) = parse_functions(list, e, diags) {
                    self.functions = Some(f);
                }
            }
            DecoderField::MaxCacheNumber => match uint_value(list, e, u64::from(MAX_CACHE_FILES)) {
                Ok(v) => self.max_cache_number = Some((v as u32, Origin::of(list, e))),
                Err(d) => diags.push(d),
            },
            DecoderField::MaxCacheSize => {
                match uint_value(list, e, u64::from(MAX_CACHE_FILE_BYTES)) {
                    Ok(v) => self.max_cache_size = Some((v as u32, Origin::of(list, e))),
                    Err(d) => diags.push(d),
                }
            }
        }
    }

    /// `over` (the channel list) wins field by field over `self` (the start-up list).
    pub(crate) fn overlay(self, over: DecoderParams) -> DecoderParams {
        DecoderParams {
            functions: over.functions.or(self.functions),
            max_cache_number: over.max_cache_number.or(self.max_cache_number),
            max_cache_size: over.max_cache_size.or(self.max_cache_size),
        }
    }

    /// Apply the defaults: 4 files of 4096 bytes with caching on, 0 without; explicit values win.
    /// Cache sizes set while caching is off draw a warning: they have no effect.
    pub fn finish(self, warnings: &mut Vec<Diagnostic>) -> DecoderSettings {
        let functions = self.functions.unwrap_or_default();
        let enabled = functions.iter().any(|f| f == FCT_USE_CACHED_FILES);
        if !enabled {
            for (_, o) in [&self.max_cache_number, &self.max_cache_size]
                .into_iter()
                .flatten()
            {
                warnings.push(
                    Diagnostic::warning(
                        &o.file,
                        o.pos.line,
                        o.pos.col,
                        None,
                        format!(
                            "{}: has no effect because {FCT_USE_CACHED_FILES} is not set in \
                             decoder.function",
                            o.name
                        ),
                    )
                    .with_source(&o.line_text),
                );
            }
        }
        let (def_files, def_bytes) = if enabled {
            (DEFAULT_CACHE_FILES, DEFAULT_CACHE_FILE_BYTES)
        } else {
            (0, 0)
        };
        DecoderSettings {
            functions,
            cache: CacheSettings {
                enabled,
                max_files: self.max_cache_number.map_or(def_files, |(v, _)| v),
                max_file_bytes: self.max_cache_size.map_or(def_bytes, |(v, _)| v),
            },
        }
    }
}

/// Function names are separated by `|` (also `,`, or blanks inside quotes):
/// `FCT_USE_CACHED_FILES|FCT_VOL_COMP_COMPUTATION`. `-` or an empty string means none.
fn parse_functions(
    list: &ParamList,
    e: &Entry,
    diags: &mut Vec<Diagnostic>,
) -> Option<Vec<String>> {
    let text = match string_value(list, e, MAX_FUNCTION_CHARS) {
        Ok(t) => t,
        Err(d) => {
            diags.push(d);
            return None;
        }
    };
    if text.trim() == "-" {
        return Some(Vec::new());
    }
    let mut out = Vec::new();
    let mut ok = true;
    for name in text.split(['|', ',', ' ', '\t']).filter(|s| !s.is_empty()) {
        let well_formed = name.len() > 4
            && name.starts_with("FCT_")
            && name
                .chars()
                .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_');
        if !well_formed {
            diags.push(list.error_at(
                e,
                e.value_pos,
                format!(
                    "{}: `{name}` is not a function name (FCT_…; separate several with `|`)",
                    e.name.text
                ),
            ));
            ok = false;
            continue;
        }
        if !KNOWN_FUNCTIONS.contains(&name) {
            diags.push(list.warning_at(
                e,
                e.value_pos,
                format!(
                    "{}: unknown function `{name}`; kept, no effect",
                    e.name.text
                ),
            ));
        }
        out.push(name.to_string());
    }
    ok.then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::Severity;
    use crate::params::list::parse_list;
    use std::path::Path;

    fn params(text: &str) -> (DecoderParams, Vec<Diagnostic>) {
        let (list, errs) = parse_list(Path::new("t.lis"), text);
        assert!(errs.is_empty(), "{errs:?}");
        let mut p = DecoderParams::default();
        let mut diags = Vec::new();
        for e in &list.entries {
            let field = match e.name.segments.last().unwrap().ident.as_str() {
                "f" => DecoderField::Function,
                "max_cache_number" => DecoderField::MaxCacheNumber,
                "max_cache_size" => DecoderField::MaxCacheSize,
                other => panic!("test names f, max_cache_number, max_cache_size; got {other}"),
            };
            p.set(&list, e, field, &mut diags);
        }
        (p, diags)
    }

    #[test]
    fn caching_defaults_and_explicit_values() {
        let (p, d) = params("f FCT_USE_CACHED_FILES\n");
        assert!(d.is_empty());
        let s = p.finish(&mut Vec::new());
        assert_eq!(
            s.cache,
            CacheSettings {
                enabled: true,
                max_files: 4,
                max_file_bytes: 4096
            }
        );
        let (p, _) = params("f FCT_USE_CACHED_FILES\nmax_cache_number 6\nmax_cache_size 6000\n");
        let s = p.finish(&mut Vec::new());
        assert_eq!((s.cache.max_files, s.cache.max_file_bytes), (6, 6000));
        let (p, _) = params("f -\n");
        let s = p.finish(&mut Vec::new());
        assert_eq!(
            s.cache,
            CacheSettings {
                enabled: false,
                max_files: 0,
                max_file_bytes: 0
            }
        );
    }

    #[test]
    fn combined_functions_and_unknown_function() {
        let (p, d) = params("f FCT_VOL_COMP_COMPUTATION|FCT_USE_CACHED_FILES\n");
        assert!(d.is_empty());
        assert!(p.finish(&mut Vec::new()).cache.enabled);
        let (p, d) = params("f \"FCT_USE_CACHED_FILES, FCT_NEW_THING\"\n");
        assert_eq!(d.len(), 1);
        assert_eq!(d[0].severity, Severity::Warning);
        assert_eq!(p.finish(&mut Vec::new()).functions.len(), 2);
        let (_, d) = params("f caching\n");
        assert_eq!(d[0].severity, Severity::Error);
    }

    #[test]
    fn cache_sizes_without_caching_warn() {
        let (p, _) = params("max_cache_size 6000\n");
        let mut w = Vec::new();
        let s = p.finish(&mut w);
        assert_eq!(s.cache.max_file_bytes, 6000);
        assert!(!s.cache.enabled);
        assert_eq!(w.len(), 1);
        assert_eq!(w[0].line, 1);
    }

    #[test]
    fn channel_overrides_field_by_field() {
        let (start, _) =
            params("f FCT_USE_CACHED_FILES\nmax_cache_number 6\nmax_cache_size 6000\n");
        let (chan, _) = params("max_cache_size 100\n");
        let s = start.overlay(chan).finish(&mut Vec::new());
        assert_eq!((s.cache.max_files, s.cache.max_file_bytes), (6, 100));
    }
}
