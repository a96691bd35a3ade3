//! The layout docs/architecture.md draws, held against the code: which room (a folder or file
//! directly under `src/`) imports which, as the table "Who may import whom" allows, and no
//! circle of imports between rooms or between the files of one room.
//!
//! The imports are read from the source text: every `crate::…` and `super::…` path outside
//! comments, strings and `#[cfg(test)]` modules, resolved to the file that defines the module
//! it names. A new room must get its row in the table before it builds.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file under `src/`, by its path relative to `src/` with `/` separators.
fn sources() -> BTreeMap<String, String> {
    fn walk(dir: &Path, base: &Path, out: &mut BTreeMap<String, String>) {
        let mut entries: Vec<_> = std::fs::read_dir(dir)
            .expect("src/ is readable")
            .map(|e| e.expect("directory entry").path())
            .collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(&p, base, out);
            } else if p.extension().is_some_and(|e| e == "rs") {
                let rel = p.strip_prefix(base).expect("under src");
                let rel = rel.to_string_lossy().replace('\\', "/");
                out.insert(rel, std::fs::read_to_string(&p).expect("source is UTF-8"));
            }
        }
    }
    let src = root().join("src");
    let mut out = BTreeMap::new();
    walk(&src, &src, &mut out);
    out
}

/// The source without comments, string and character literals (their text could look like
/// a path) and without `#[cfg(test)]` modules (tests may reach anywhere in their room).
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                let mut depth = 0;
                while i < b.len() {
                    if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
                        depth += 1;
                        i += 2;
                    } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        i += 1;
                    }
                }
            }
            b'r' if matches!(b.get(i + 1), Some(b'"' | b'#'))
                && (i == 0 || !is_ident(b[i - 1])) =>
            {
                let mut j = i + 1;
                let mut hashes = 0;
                while b.get(j) == Some(&b'#') {
                    hashes += 1;
                    j += 1;
                }
                if b.get(j) != Some(&b'"') {
                    out.push('r');
                    i += 1;
                    continue;
                }
                j += 1;
                loop {
                    if j >= b.len() {
                        break;
                    }
                    if b[j] == b'"' && b[j + 1..].iter().take(hashes).all(|&c| c == b'#') {
                        j += 1 + hashes;
                        break;
                    }
                    j += 1;
                }
                out.push_str("\"\"");
                i = j;
            }
            b'"' => {
                i += 1;
                while i < b.len() && b[i] != b'"' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                i += 1;
                out.push_str("\"\"");
            }
            b'\'' => {
                // A character literal ('x', '\n', '\u{..}') or a lifetime ('a).
                if b.get(i + 1) == Some(&b'\\') {
                    let mut j = i + 2;
                    while j < b.len() && b[j] != b'\'' {
                        j += 1;
                    }
                    i = j + 1;
                } else if b.get(i + 2) == Some(&b'\'') {
                    i += 3;
                } else {
                    out.push('\'');
                    i += 1;
                }
                out.push(' ');
            }
            c => {
                out.push(c as char);
                i += 1;
            }
        }
    }
    without_test_modules(&out)
}

fn without_test_modules(code: &str) -> String {
    let mut out = String::with_capacity(code.len());
    let mut rest = code;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let after = &rest[at + "#[cfg(test)]".len()..];
        let item = after.trim_start();
        if item.starts_with("mod ") {
            if let Some(open) = item.find('{') {
                let mut depth = 0;
                let mut end = item.len();
                for (k, c) in item[open..].char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = open + k + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                rest = &item[end..];
                continue;
            }
        }
        rest = after;
    }
    out.push_str(rest);
    out
}

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// The module path (from the crate root) a file defines: `decoder/mod.rs` → `decoder`.
fn module_of(file: &str) -> Vec<String> {
    let stem = file.trim_end_matches(".rs");
    let mut parts: Vec<String> = stem.split('/').map(str::to_string).collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    if parts == ["lib"] || parts == ["main"] {
        parts.clear();
    }
    parts
}

/// Every path the code names through `crate::` or `super::`, as module paths from the crate
/// root (use trees `a::{b, c::d}` expanded).
fn named_paths(file: &str, code: &str) -> Vec<Vec<String>> {
    let me = module_of(file);
    let parent: Vec<String> = me[..me.len().saturating_sub(1)].to_vec();
    let b = code.as_bytes();
    let mut out = Vec::new();
    for (head, base) in [("crate::", Vec::new()), ("super::", parent)] {
        let mut from = 0;
        while let Some(k) = code[from..].find(head) {
            let at = from + k;
            from = at + head.len();
            if at > 0 && (is_ident(b[at - 1]) || b[at - 1] == b':') {
                continue;
            }
            let mut prefix = base.clone();
            tree(b, &mut from.clone(), &mut prefix, &mut out);
        }
    }
    out
}

/// Reads a use tree at `*i` below `prefix` and records each leaf path.
fn tree(b: &[u8], i: &mut usize, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    let depth = prefix.len();
    loop {
        skip_space(b, i);
        if b.get(*i) == Some(&b'{') {
            *i += 1;
            loop {
                skip_space(b, i);
                match b.get(*i) {
                    Some(b'}') => {
                        *i += 1;
                        break;
                    }
                    Some(b',') => *i += 1,
                    None => break,
                    _ => {
                        let mut inner = prefix.clone();
                        tree(b, i, &mut inner, out);
                    }
                }
            }
            prefix.truncate(depth);
            return;
        }
        let start = *i;
        while *i < b.len() && is_ident(b[*i]) {
            *i += 1;
        }
        if start == *i {
            break;
        }
        let seg = String::from_utf8_lossy(&b[start..*i]).into_owned();
        if seg != "self" {
            prefix.push(seg);
        }
        skip_space(b, i);
        if b.get(*i) == Some(&b':') && b.get(*i + 1) == Some(&b':') {
            *i += 2;
        } else {
            break;
        }
    }
    out.push(prefix.clone());
}

fn skip_space(b: &[u8], i: &mut usize) {
    while *i < b.len() && b[*i].is_ascii_whitespace() {
        *i += 1;
    }
}

/// The file defining the longest prefix of `path` that is a module.
fn resolve(path: &[String], files: &BTreeMap<String, String>) -> Option<String> {
    (1..=path.len()).rev().find_map(|k| {
        let stem = path[..k].join("/");
        [format!("{stem}.rs"), format!("{stem}/mod.rs")]
            .into_iter()
            .find(|f| files.contains_key(f))
    })
}

fn room(file: &str) -> &str {
    file.split('/')
        .next()
        .unwrap_or(file)
        .trim_end_matches(".rs")
}

/// Edges file → file it imports (itself excluded).
fn file_imports(files: &BTreeMap<String, String>) -> BTreeMap<String, BTreeSet<String>> {
    files
        .iter()
        .map(|(f, text)| {
            let code = code_only(text);
            let targets = named_paths(f, &code)
                .iter()
                .filter_map(|p| resolve(p, files))
                .filter(|t| t != f)
                .collect();
            (f.clone(), targets)
        })
        .collect()
}

/// The circles of a directed graph: its strongly connected components of more than one node.
fn circles(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    let nodes: BTreeSet<&String> = edges.keys().chain(edges.values().flatten()).collect();
    let reach = |from: &String| -> BTreeSet<String> {
        let mut seen = BTreeSet::new();
        let mut todo = vec![from.clone()];
        while let Some(n) = todo.pop() {
            for m in edges.get(&n).into_iter().flatten() {
                if seen.insert(m.clone()) {
                    todo.push(m.clone());
                }
            }
        }
        seen
    };
    let reachable: BTreeMap<&String, BTreeSet<String>> =
        nodes.iter().map(|n| (*n, reach(n))).collect();
    let mut done = BTreeSet::new();
    let mut out = Vec::new();
    for n in &nodes {
        if done.contains(*n) {
            continue;
        }
        let comp: Vec<String> = nodes
            .iter()
            .filter(|m| *m == n || (reachable[*n].contains(**m) && reachable[**m].contains(*n)))
            .map(|m| (*m).clone())
            .collect();
        done.extend(comp.iter().cloned());
        if comp.len() > 1 {
            out.push(comp);
        }
    }
    out
}

#[test]
fn no_module_circles_between_rooms_or_between_the_files_of_a_room() {
    let files = sources();
    let imports = file_imports(&files);
    let mut rooms: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut siblings: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (f, targets) in &imports {
        if module_of(f).is_empty() {
            continue;
        }
        for t in targets {
            if module_of(t).is_empty() {
                continue;
            }
            if room(f) != room(t) {
                rooms
                    .entry(room(f).into())
                    .or_default()
                    .insert(room(t).into());
            } else if !f.ends_with("mod.rs") && !t.ends_with("mod.rs") {
                // A room's mod.rs declares its files; the circles that count are between
                // the files themselves.
                siblings.entry(f.clone()).or_default().insert(t.clone());
            }
        }
    }
    let mut found = circles(&rooms);
    found.extend(circles(&siblings));
    assert!(found.is_empty(), "module circles: {found:?}");
}

/// The rows of docs/architecture.md's table "Who may import whom": (rooms, rooms they may
/// import), "any room in the rows before them" expanded.
fn layer_table() -> Vec<(Vec<String>, BTreeSet<String>)> {
    let doc =
        std::fs::read_to_string(root().join("docs/architecture.md")).expect("docs/architecture.md");
    let at = doc
        .find("Who may import whom")
        .expect("the layer table's heading");
    let ticked = |cell: &str| -> Vec<String> {
        cell.split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect()
    };
    let mut rows: Vec<(Vec<String>, BTreeSet<String>)> = Vec::new();
    for line in doc[at..]
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2)
    {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let (who, may) = (cells[1], cells[2]);
        let allowed: BTreeSet<String> = if may.contains("any room in the rows before") {
            rows.iter().flat_map(|(r, _)| r.iter().cloned()).collect()
        } else if may.contains("nothing of the crate") {
            BTreeSet::new()
        } else {
            ticked(may).into_iter().collect()
        };
        rows.push((ticked(who), allowed));
    }
    rows
}

#[test]
fn rooms_import_only_what_docs_architecture_allows() {
    let files = sources();
    let imports = file_imports(&files);
    let table = layer_table();
    let allowed: BTreeMap<&str, &BTreeSet<String>> = table
        .iter()
        .flat_map(|(rooms, may)| rooms.iter().map(move |r| (r.as_str(), may)))
        .collect();
    let mut wrong = BTreeSet::new();
    let mut unlisted = BTreeSet::new();
    for (f, targets) in &imports {
        if module_of(f).is_empty() {
            continue;
        }
        let from = room(f);
        let Some(may) = allowed.get(from) else {
            unlisted.insert(from.to_string());
            continue;
        };
        for t in targets {
            let to = room(t);
            if module_of(t).is_empty() || to == from || to == "vocab" || may.contains(to) {
                continue;
            }
            wrong.insert(format!("{f} imports `{to}`"));
        }
    }
    assert!(
        unlisted.is_empty(),
        "rooms without a row in docs/architecture.md's layer table: {unlisted:?}"
    );
    assert!(
        wrong.is_empty(),
        "imports the layer table of docs/architecture.md does not allow:\n{}",
        wrong.into_iter().collect::<Vec<_>>().join("\n")
    );
}

/// The checker itself: a circle and a forbidden import are found.
#[test]
fn the_checker_finds_circles_and_paths() {
    let mut g = BTreeMap::new();
    g.insert("a".to_string(), BTreeSet::from(["b".to_string()]));
    g.insert("b".to_string(), BTreeSet::from(["a".to_string()]));
    g.insert("c".to_string(), BTreeSet::from(["a".to_string()]));
    assert_eq!(circles(&g), vec![vec!["a".to_string(), "b".to_string()]]);
    let code = code_only(
        "use crate::x::{y, z::{w, self}};\n// crate::no\nlet s = \"crate::no\";\nuse super::v::K;\n\
         #[cfg(test)]\nmod tests { use crate::hidden; }\n",
    );
    let paths = named_paths("r/f.rs", &code);
    let joined: Vec<String> = paths.iter().map(|p| p.join("::")).collect();
    assert_eq!(joined, ["x::y", "x::z::w", "x::z", "r::v::K"]);
}
