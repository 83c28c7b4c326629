//! The import graph of a crate, read from its source, for the layout tests: a module's
//! uses are the `crate::…`, `super::…` and `self::…` paths in its file (`use` groups
//! `{a, b::c}` expanded; comment lines and everything from `#[cfg(test)]` on left out); a
//! path points into the longest module it names, and an item re-exported at the crate root
//! (`crate::Error`) counts as its defining module. A module's own ancestors (whose `mod`
//! lines declare it) are not counted as its uses.
#![allow(dead_code)] // each test binary uses its part

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The crates under `rust/` (each folder with a `src/`).
pub fn crates() -> Vec<(String, PathBuf)> {
    let rust = Path::new(env!("CARGO_MANIFEST_DIR")).join("../rust");
    let mut out: Vec<_> = std::fs::read_dir(&rust)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("src").is_dir())
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                p.join("src"),
            )
        })
        .collect();
    out.sort();
    out
}

/// Every `.rs` file under `dir`, sorted.
pub fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    let mut files = Vec::new();
    for path in entries {
        if path.is_dir() {
            files.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
    files
}

/// Source files under `src`, by module path (`""` for the crate root, `report::scene`, …),
/// with their code: comment lines and everything from `#[cfg(test)]` on removed.
pub fn sources(src: &Path) -> BTreeMap<String, String> {
    rust_files(src)
        .into_iter()
        .filter(|path| !path.starts_with(src.join("bin")))
        .map(|path| {
            let relative = path.strip_prefix(src).unwrap().with_extension("");
            let mut parts: Vec<String> = relative
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if parts.len() == 1 && (parts[0] == "lib" || parts[0] == "main") {
                parts.clear();
            }
            if parts.last().is_some_and(|p| p == "mod") {
                parts.pop();
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let code = text.split("#[cfg(test)]").next().unwrap_or("");
            let code: String = code
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .map(|l| format!("{l}\n"))
                .collect();
            (parts.join("::"), code)
        })
        .collect()
}

/// The leading `a::b::c` of `text`, as segments.
pub fn segments(text: &str) -> Vec<String> {
    let end = text
        .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
        .unwrap_or(text.len());
    text[..end]
        .split("::")
        .filter(|s| !s.is_empty())
        .map(str::to_string)
        .collect()
}

/// The items of a `{…}` group (`text` starts after the `{`), split at its own commas.
pub fn group_items(text: &str) -> Vec<&str> {
    let (mut depth, mut start, mut items) = (0usize, 0, Vec::new());
    for (i, c) in text.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => {
                items.push(&text[start..i]);
                break;
            }
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    items
}

/// The full paths that `text` (what follows a path's `prefix`) names: `a::b`, or each item
/// of a `a::{b, c::{d, e}}` group.
pub fn expand(prefix: &[String], text: &str) -> Vec<Vec<String>> {
    let head = segments(text);
    let end = text
        .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
        .unwrap_or(text.len());
    let mut path = prefix.to_vec();
    path.extend(head);
    match text[end..].strip_prefix('{') {
        Some(group) if text[..end].ends_with("::") || end == 0 => group_items(group)
            .into_iter()
            .flat_map(|item| expand(&path, item.trim()))
            .collect(),
        _ => vec![path],
    }
}

/// Every module path `code` (the file of `module`) names, from the crate root.
pub fn module_paths(module: &str, code: &str) -> Vec<Vec<String>> {
    let me: Vec<String> = module
        .split("::")
        .filter(|s| !s.is_empty())
        .map(str::to_string)
        .collect();
    let mut out = Vec::new();
    for keyword in ["crate::", "super::", "self::"] {
        let mut rest = code;
        while let Some(at) = rest.find(keyword) {
            let before = rest[..at].chars().last();
            rest = &rest[at + keyword.len()..];
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                continue; // another crate's path (`sitar_crate::`), or `super::super::`
            }
            let mut base = match keyword {
                "crate::" => Vec::new(),
                "self::" => me.clone(),
                _ => me[..me.len().saturating_sub(1)].to_vec(),
            };
            while let Some(more) = rest.strip_prefix("super::") {
                base.pop();
                rest = more; // `super::super::`: read once, from the first
            }
            out.extend(expand(&base, rest));
        }
    }
    out
}

/// `pub use module::{A, B};` at the crate root: item → module.
pub fn root_items(lib: &str, modules: &BTreeSet<String>) -> BTreeMap<String, String> {
    let mut items = BTreeMap::new();
    for statement in lib.split(';') {
        let Some(rest) = statement.trim().strip_prefix("pub use ") else {
            continue;
        };
        let (module, names) = rest.split_once("::").unwrap_or((rest, ""));
        if !modules.contains(module.trim()) {
            continue; // another crate's items
        }
        for name in names
            .split(|c: char| !(c.is_alphanumeric() || c == '_'))
            .filter(|n| !n.is_empty() && *n != "self")
        {
            items.insert(name.to_string(), module.trim().to_string());
        }
    }
    items
}

/// Module → the modules it uses (itself, its ancestors and the crate root left out).
pub fn graph(sources: &BTreeMap<String, String>) -> BTreeMap<String, BTreeSet<String>> {
    let modules: BTreeSet<String> = sources.keys().filter(|m| !m.is_empty()).cloned().collect();
    let roots = sources
        .get("")
        .map(|lib| root_items(lib, &modules))
        .unwrap_or_default();
    modules
        .iter()
        .map(|module| {
            let uses = module_paths(module, &sources[module])
                .iter()
                .filter_map(|path| {
                    (1..=path.len())
                        .rev()
                        .map(|n| path[..n].join("::"))
                        .find(|m| modules.contains(m))
                        .or_else(|| path.first().and_then(|item| roots.get(item).cloned()))
                })
                .filter(|m| m != module && !module.starts_with(&format!("{m}::")))
                .collect();
            (module.clone(), uses)
        })
        .collect()
}

/// Every cycle's modules (strongly connected components of two or more), sorted.
pub fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    // Two modules are in one cycle when each reaches the other.
    let reach = |from: &str| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.to_string()];
        while let Some(m) = stack.pop() {
            for next in graph.get(&m).into_iter().flatten() {
                if seen.insert(next.clone()) {
                    stack.push(next.clone());
                }
            }
        }
        seen
    };
    let reached: BTreeMap<&String, BTreeSet<String>> =
        graph.keys().map(|m| (m, reach(m))).collect();
    let mut out: Vec<Vec<String>> = Vec::new();
    for m in graph.keys() {
        if !reached[m].contains(m) || out.iter().any(|c| c.contains(m)) {
            continue;
        }
        let mut cycle: Vec<String> = graph
            .keys()
            .filter(|n| reached[m].contains(*n) && reached[*n].contains(m))
            .cloned()
            .collect();
        cycle.sort();
        out.push(cycle);
    }
    out
}

/// A module's top-level folder (or root file): `storage::sqlite::sessions` → `storage`.
pub fn folder(module: &str) -> String {
    module.split("::").next().unwrap_or("").to_string()
}

/// Folder → the folders its files use (itself left out).
pub fn folder_graph(
    graph: &BTreeMap<String, BTreeSet<String>>,
) -> BTreeMap<String, BTreeSet<String>> {
    let mut out: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (module, uses) in graph {
        let from = folder(module);
        let entry = out.entry(from.clone()).or_default();
        entry.extend(uses.iter().map(|m| folder(m)).filter(|f| *f != from));
    }
    out
}

/// The layer list of lib.rs's comment (`// name — what`), lowest first.
pub fn layer_list(lib: &str) -> Vec<String> {
    lib.lines()
        .filter_map(|l| l.trim_start().strip_prefix("// "))
        .filter_map(|l| l.split_once(" — "))
        .map(|(name, _)| name.trim().to_string())
        .filter(|name| name.chars().all(|c| c.is_ascii_lowercase() || c == '_'))
        .collect()
}
