//! Every crate's layout, checked from its source: no file-level import cycle among the
//! modules of any crate under `rust/` (dependencies run one way inside a crate, as they do
//! between crates).
//!
//! A module's uses are the `crate::…`, `super::…` and `self::…` paths in its file (`use`
//! groups `{a, b::c}` expanded; comment lines and everything from `#[cfg(test)]` on left
//! out); a path points into the longest module it names, and an item re-exported at the crate
//! root (`crate::Error`) counts as its defining module. A module's own ancestors (whose `mod`
//! lines declare it) are not counted as its uses.
//!
//! Folders too: drawn as its top-level folders (and root files), each crate's graph has no
//! cycle, and the server's layer comment in `lib.rs` lists its folders in an order every
//! import follows (a folder uses only folders listed before it).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The crates under `rust/` (each folder with a `src/`).
fn crates() -> Vec<(String, PathBuf)> {
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

/// Source files under `src`, by module path (`""` for the crate root, `report::scene`, …),
/// with their code: comment lines and everything from `#[cfg(test)]` on removed.
fn sources(src: &Path) -> BTreeMap<String, String> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    let mut files = Vec::new();
    walk(src, &mut files);
    files
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
fn segments(text: &str) -> Vec<String> {
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
fn group_items(text: &str) -> Vec<&str> {
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
fn expand(prefix: &[String], text: &str) -> Vec<Vec<String>> {
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
fn module_paths(module: &str, code: &str) -> Vec<Vec<String>> {
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
fn root_items(lib: &str, modules: &BTreeSet<String>) -> BTreeMap<String, String> {
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
fn graph(sources: &BTreeMap<String, String>) -> BTreeMap<String, BTreeSet<String>> {
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
fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
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

#[test]
fn the_parser_reads_crate_super_and_self_paths() {
    let paths = module_paths(
        "report::scene",
        "use crate::Error;\nuse crate::session::{Lifecycle, NewSession};\n\
         use crate::{deletion, jobs::{self, Begin}};\nlet x = crate::db::now_ms();\n\
         use super::flat_depth::sample;\nuse self::inner::X;\nsuper::super::config::load();\n\
         use sitar_crate::other;",
    );
    let joined: Vec<String> = paths.iter().map(|p| p.join("::")).collect();
    assert_eq!(
        joined,
        [
            "Error",
            "session::Lifecycle",
            "session::NewSession",
            "deletion",
            "jobs::self",
            "jobs::Begin",
            "db::now_ms",
            "report::flat_depth::sample",
            "config::load",
            "report::scene::inner::X",
        ],
        "{paths:?}"
    );
    let modules = BTreeSet::from(["error".to_string(), "config".to_string()]);
    let roots = root_items(
        "pub use error::Error;\npub use config::{AdbConfig, ServerConfig};\npub use glam::DVec3;",
        &modules,
    );
    assert_eq!(roots["Error"], "error");
    assert_eq!(roots["ServerConfig"], "config");
    assert!(!roots.contains_key("DVec3"));
}

#[test]
fn no_crate_has_a_file_level_import_cycle() {
    let crates = crates();
    let names: Vec<&str> = crates.iter().map(|(n, _)| n.as_str()).collect();
    for expected in ["core", "estimator", "sim", "client", "server", "ffi", "cli"] {
        assert!(names.contains(&expected), "{names:?}");
    }
    let mut found = Vec::new();
    for (name, src) in &crates {
        let graph = graph(&sources(src));
        for cycle in cycles(&graph) {
            found.push(format!("{name}: {}", cycle.join(" ↔ ")));
        }
        // The graph is what the files say (a parser that missed edges would find no cycle).
        if name == "server" {
            assert!(graph["report::scene"].contains("report::flat_depth"));
            assert!(graph["http::handlers::trials"].contains("http::helpers"));
            assert!(graph["storage::sqlite::sessions"].contains("storage::metadata"));
        }
        if name == "client" {
            assert!(graph["job"].contains("job_run") && graph["job_run"].contains("job_state"));
        }
    }
    assert!(found.is_empty(), "import cycles:\n{}", found.join("\n"));
}

/// A module's top-level folder (or root file): `storage::sqlite::sessions` → `storage`.
fn folder(module: &str) -> String {
    module.split("::").next().unwrap_or("").to_string()
}

/// Folder → the folders its files use (itself left out).
fn folder_graph(graph: &BTreeMap<String, BTreeSet<String>>) -> BTreeMap<String, BTreeSet<String>> {
    let mut out: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (module, uses) in graph {
        let from = folder(module);
        let entry = out.entry(from.clone()).or_default();
        entry.extend(uses.iter().map(|m| folder(m)).filter(|f| *f != from));
    }
    out
}

#[test]
fn no_crate_has_an_import_cycle_between_folders() {
    let mut found = Vec::new();
    for (name, src) in &crates() {
        let folders = folder_graph(&graph(&sources(src)));
        for cycle in cycles(&folders) {
            found.push(format!("{name}: {}", cycle.join(" ↔ ")));
        }
        if name == "server" {
            // The parser sees folder arrows (none found would prove nothing).
            assert!(folders["storage"].contains("model"), "{folders:?}");
            assert!(folders["jobs"].contains("app_state"), "{folders:?}");
        }
    }
    assert!(
        found.is_empty(),
        "import cycles between folders:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_server_stores_sit_on_the_vocabulary_alone() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../rust/server/src");
    let folders = folder_graph(&graph(&sources(&src)));
    let only = |folder: &str, allowed: &[&str]| {
        let extra: Vec<&String> = folders[folder]
            .iter()
            .filter(|f| !allowed.contains(&f.as_str()))
            .collect();
        assert!(extra.is_empty(), "{folder} imports {extra:?}, above it");
    };
    // The vocabulary at the bottom, the stores on it; the lifecycle, access control and
    // venue logic above both.
    only("model", &["error"]);
    only("storage", &["model", "error"]);
    for logic in ["session", "auth", "venue"] {
        assert!(folders[logic].contains("storage") || folders[logic].contains("model"));
        assert!(!folders["storage"].contains(logic));
    }
    // lib.rs's layer comment lists them in that order.
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    let layers = layer_comment(&lib);
    let rank = |name: &str| {
        layers
            .iter()
            .position(|l| l.iter().any(|n| n == name))
            .unwrap_or_else(|| panic!("lib.rs's layer comment does not list {name}"))
    };
    assert!(rank("error") < rank("model") && rank("model") < rank("storage"));
    for logic in ["session", "auth", "venue"] {
        assert!(rank("storage") < rank(logic), "{logic}");
    }
}

/// The server's layer comment: the modules its `// name, name — what` lines list, in order.
fn layer_comment(lib: &str) -> Vec<Vec<String>> {
    lib.lines()
        .filter_map(|l| l.strip_prefix("// "))
        .filter_map(|l| l.split_once('—').map(|(names, _)| names))
        .map(|names| {
            names
                .split(',')
                .map(|n| n.trim().to_string())
                .filter(|n| !n.is_empty())
                .collect()
        })
        .collect()
}
