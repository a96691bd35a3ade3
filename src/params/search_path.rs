//! Program search paths: `pfad[i].prg|typ|prioritaet[j]` of the start-up list and
//! `path[j].dir|type|priority` of a channel list, checked and resolved against the list's folder.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::list::{Entry, ParamList};
use super::value::{string_value, uint_value};
use crate::diag::Diagnostic;

/// Path type bit: the folder holds main programs (P-STUP-00020 / P-CHAN-00403).
pub const MAIN_PROGRAMS: u16 = 0x01;
/// Path type bit: the folder holds global subroutines and cycles.
pub const SUBROUTINES: u16 = 0x02;
/// Path type bit: `#MSG SAVE` output folder (accepted, not used by the emulator).
pub(crate) const MSG_SAVE: u16 = 0x04;
/// Path type bit: debug data `*.dbg` folder (accepted, not used by the emulator).
pub(crate) const DEBUG_DATA: u16 = 0x08;
const ALL_TYPES: u16 = MAIN_PROGRAMS | SUBROUTINES | MSG_SAVE | DEBUG_DATA;

/// Program paths per channel (`j = 0 ... 11` in the ISG documentation).
pub(crate) const MAX_PATHS: u32 = 12;
/// Longest path string the kernel accepts (P-CHAN-00401: 256 characters).
pub(crate) const MAX_DIR_CHARS: usize = 256;

/// One folder the channel searches for NC programs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SearchPath {
    /// Absolute as written, or joined to the folder of the list that names it.
    pub dir: PathBuf,
    /// Path type bits (`MAIN_PROGRAMS`, `SUBROUTINES`, ...).
    pub kinds: u16,
    /// 0 is searched first.
    pub priority: u16,
    /// Where the folder was named, for messages such as "program not found in …".
    pub file: PathBuf,
    pub line: usize,
}

impl SearchPath {
    pub(crate) fn serves_main_programs(&self) -> bool {
        self.kinds & MAIN_PROGRAMS != 0
    }

    pub(crate) fn serves_subroutines(&self) -> bool {
        self.kinds & SUBROUTINES != 0
    }
}

/// Which field of a path an entry sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PathField {
    Dir,
    Kinds,
    Priority,
}

/// The entries seen for one path index, before checking.
#[derive(Default)]
struct RawPath<'a> {
    dir: Option<&'a Entry>,
    kinds: Option<&'a Entry>,
    priority: Option<&'a Entry>,
}

/// Collects the path entries of one list for one channel, then checks and resolves them.
#[derive(Default)]
pub(crate) struct PathCollector<'a> {
    paths: BTreeMap<u32, RawPath<'a>>,
}

impl<'a> PathCollector<'a> {
    /// Record one entry. The path index is checked here so the error points at it.
    pub fn add(
        &mut self,
        list: &ParamList,
        entry: &'a Entry,
        index: u32,
        field: PathField,
        diags: &mut Vec<Diagnostic>,
    ) {
        if index >= MAX_PATHS {
            diags.push(list.error_at(
                entry,
                entry.name_pos,
                format!(
                    "{}: path index {index} is out of range (at most {MAX_PATHS} paths, 0 ... {})",
                    entry.name.text,
                    MAX_PATHS - 1
                ),
            ));
            return;
        }
        let raw = self.paths.entry(index).or_default();
        match field {
            PathField::Dir => raw.dir = Some(entry),
            PathField::Kinds => raw.kinds = Some(entry),
            PathField::Priority => raw.priority = Some(entry),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.paths.is_empty()
    }

    /// Check every path and return them sorted by priority (ties: path index).
    /// `base` is the folder relative paths are joined to.
    pub fn finish(
        self,
        list: &ParamList,
        base: &Path,
        diags: &mut Vec<Diagnostic>,
    ) -> Vec<SearchPath> {
        let mut out: Vec<(u16, u32, SearchPath)> = Vec::new();
        // Per type bit: priority → the entry that claimed it.
        let mut claimed: BTreeMap<(u16, u16), &Entry> = BTreeMap::new();
        for (index, raw) in &self.paths {
            let Some(dir_entry) = raw.dir else {
                // A type or priority without its folder.
                let orphan = raw.kinds.or(raw.priority);
                if let Some(e) = orphan {
                    diags.push(list.error_at(
                        e,
                        e.name_pos,
                        format!(
                            "{}: path {index} has a type or priority but no folder",
                            e.name.text
                        ),
                    ));
                }
                continue;
            };
            let dir_text = match string_value(list, dir_entry, MAX_DIR_CHARS) {
                Ok(s) => s,
                Err(d) => {
                    diags.push(d);
                    continue;
                }
            };
            if dir_text.is_empty() {
                diags.push(list.error_at(
                    dir_entry,
                    dir_entry.value_pos,
                    format!("{}: empty folder", dir_entry.name.text),
                ));
                continue;
            }
            let kinds = match raw.kinds {
                None => {
                    diags.push(list.warning_at(
                        dir_entry,
                        dir_entry.name_pos,
                        format!(
                            "{}: path {index} has no type (default 0), so it is never searched",
                            dir_entry.name.text
                        ),
                    ));
                    0
                }
                Some(e) => match uint_value(list, e, u64::from(ALL_TYPES)) {
                    Ok(v) => v as u16,
                    Err(d) => {
                        diags.push(d);
                        continue;
                    }
                },
            };
            let (priority, prio_entry) = match raw.priority {
                None => (0, dir_entry),
                Some(e) => match uint_value(list, e, u64::from(u16::MAX)) {
                    Ok(v) => (v as u16, e),
                    Err(d) => {
                        diags.push(d);
                        continue;
                    }
                },
            };
            if let Err((bit, first)) = claim_types(&mut claimed, dir_entry, kinds, priority) {
                let explicit = raw.priority.is_some();
                diags.push(priority_clash(
                    list, prio_entry, explicit, priority, bit, first,
                ));
                continue;
            }
            out.push((
                priority,
                *index,
                SearchPath {
                    dir: resolve(base, &dir_text),
                    kinds,
                    priority,
                    file: list.file.clone(),
                    line: dir_entry.name_pos.line,
                },
            ));
        }
        out.sort_by_key(|(prio, index, _)| (*prio, *index));
        out.into_iter().map(|(_, _, p)| p).collect()
    }
}

/// Claim each type bit of `kinds` at `priority` for `dir_entry`, in bit order; the first
/// bit another path already holds at that priority is returned with that path's entry (bits
/// before it stay claimed).
fn claim_types<'a>(
    claimed: &mut BTreeMap<(u16, u16), &'a Entry>,
    dir_entry: &'a Entry,
    kinds: u16,
    priority: u16,
) -> Result<(), (u16, &'a Entry)> {
    for bit in [MAIN_PROGRAMS, SUBROUTINES, MSG_SAVE, DEBUG_DATA] {
        if kinds & bit == 0 {
            continue;
        }
        if let Some(first) = claimed.get(&(bit, priority)) {
            return Err((bit, *first));
        }
        claimed.insert((bit, priority), dir_entry);
    }
    Ok(())
}

/// The error for two paths of one type at one priority, at the priority's value (or the
/// folder's name when the priority is the default).
fn priority_clash(
    list: &ParamList,
    prio_entry: &Entry,
    explicit: bool,
    priority: u16,
    bit: u16,
    first: &Entry,
) -> Diagnostic {
    let pos = if explicit {
        prio_entry.value_pos
    } else {
        prio_entry.name_pos
    };
    list.error_at(
        prio_entry,
        pos,
        format!(
            "{}: priority {priority} is already used by another path of type \
             0x{bit:02x} ({}, line {}); two paths of one type need different priorities",
            prio_entry.name.text, first.name.text, first.name_pos.line
        ),
    )
}

/// The folder a list's relative paths are relative to.
pub(crate) fn list_folder(list_file: &Path) -> PathBuf {
    match list_file.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// An absolute path stays; a relative one is joined to `base`. Lists copied from a Windows
/// controller write `..\nc`: on other systems backslashes are taken as separators.
pub fn resolve(base: &Path, text: &str) -> PathBuf {
    let text: std::borrow::Cow<str> = if cfg!(windows) {
        text.into()
    } else {
        text.replace('\\', "/").into()
    };
    let p = Path::new(text.as_ref());
    let joined = if p.is_absolute() {
        p.to_path_buf()
    } else {
        base.join(p)
    };
    // `./listen/x.lis` names `listen/x.lis`: the `.` parts say nothing, and messages read
    // better without them.
    let clean: PathBuf = joined
        .components()
        .filter(|c| !matches!(c, std::path::Component::CurDir))
        .collect();
    if clean.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        clean
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolve_relative_and_absolute() {
        assert_eq!(
            resolve(Path::new("/a/b"), "../nc"),
            PathBuf::from("/a/b/../nc")
        );
        assert_eq!(resolve(Path::new("/a/b"), "/abs"), PathBuf::from("/abs"));
        if !cfg!(windows) {
            assert_eq!(
                resolve(Path::new("/a"), "..\\nc"),
                PathBuf::from("/a/../nc")
            );
        }
        assert_eq!(list_folder(Path::new("startup.lis")), PathBuf::from("."));
        assert_eq!(list_folder(Path::new("p/startup.lis")), PathBuf::from("p"));
    }
}
