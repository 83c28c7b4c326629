//! The server's layout, checked from its source: no import cycle among its modules, handlers
//! that use the HTTP helpers and never each other, and one writer of a session's state.
//!
//! The module graph comes from the `crate::…` paths in every file under `src/` (comments and
//! `#[cfg(test)]` sections left out); items re-exported at the crate root (`crate::Error`)
//! count as their defining module.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Source files under `src/`, by module path (`session::lifecycle`, `handlers::trials`, …),
/// with their code: comment lines and everything from `#[cfg(test)]` on removed.
fn sources() -> BTreeMap<String, String> {
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
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    walk(&src, &mut files);
    files
        .into_iter()
        .map(|path| {
            let relative = path.strip_prefix(&src).unwrap().with_extension("");
            let mut parts: Vec<String> = relative
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
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

/// Every `crate::a::b…` path in `code`, with `use crate::{a, b::c}` groups expanded, as
/// segment lists.
fn crate_paths(code: &str) -> Vec<Vec<String>> {
    /// The leading `a::b::c` of `text`.
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
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let before = rest[..at].chars().last();
        rest = &rest[at + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue; // another crate's path, e.g. `sitar_crate::`
        }
        match rest.strip_prefix('{') {
            Some(group) => out.extend(
                group_items(group)
                    .into_iter()
                    .map(|item| segments(item.trim()))
                    .filter(|s| !s.is_empty()),
            ),
            None => out.push(segments(rest)),
        }
    }
    out
}

/// The module a path points into: the longest module path it starts with, or (for an item
/// re-exported at the crate root) the module the root takes it from.
fn target(
    path: &[String],
    modules: &BTreeSet<String>,
    root_items: &BTreeMap<String, String>,
) -> Option<String> {
    (1..=path.len())
        .rev()
        .map(|n| path[..n].join("::"))
        .find(|m| modules.contains(m))
        .or_else(|| path.first().and_then(|item| root_items.get(item).cloned()))
}

/// `pub use module::{A, B};` at the crate root: item → module.
fn root_items(lib: &str) -> BTreeMap<String, String> {
    let mut items = BTreeMap::new();
    for statement in lib.split(';') {
        let Some(rest) = statement.trim().strip_prefix("pub use ") else {
            continue;
        };
        let (module, names) = rest.split_once("::").unwrap_or((rest, ""));
        for name in names.trim_matches(|c| c == '{' || c == '}').split(',') {
            let name = name.trim();
            if !name.is_empty() {
                items.insert(name.to_string(), module.trim().to_string());
            }
        }
    }
    items
}

/// Module → the modules it uses (itself and the crate root left out).
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let sources = sources();
    let modules: BTreeSet<String> = sources.keys().filter(|m| *m != "lib").cloned().collect();
    let roots = root_items(&sources["lib"]);
    modules
        .iter()
        .map(|module| {
            let uses = crate_paths(&sources[module])
                .iter()
                .filter_map(|path| target(path, &modules, &roots))
                .filter(|m| m != module && !module.starts_with(&format!("{m}::")))
                .collect();
            (module.clone(), uses)
        })
        .collect()
}

#[test]
fn the_parser_reads_paths_groups_and_root_items() {
    let paths = crate_paths(
        "use crate::Error;\nuse crate::session::{Lifecycle, NewSession};\n\
         use crate::{deletion, jobs::{self, Begin}};\nlet x = crate::db::now_ms();",
    );
    let joined: Vec<String> = paths.iter().map(|p| p.join("::")).collect();
    assert_eq!(
        joined,
        ["Error", "session", "deletion", "jobs", "db::now_ms"],
        "{paths:?}"
    );
    let roots = root_items("pub use error::Error;\npub use config::{AdbConfig, ServerConfig};");
    assert_eq!(roots["Error"], "error");
    assert_eq!(roots["ServerConfig"], "config");
}

#[test]
fn no_import_cycle_among_the_modules() {
    let graph = graph();
    assert!(graph.len() > 20, "{:?}", graph.keys());
    // Depth-first search; a module met again while on the stack closes a cycle.
    fn visit<'a>(
        module: &'a str,
        graph: &'a BTreeMap<String, BTreeSet<String>>,
        stack: &mut Vec<&'a str>,
        done: &mut BTreeSet<&'a str>,
    ) {
        if done.contains(module) {
            return;
        }
        if let Some(at) = stack.iter().position(|m| *m == module) {
            panic!("import cycle: {} → {module}", stack[at..].join(" → "));
        }
        stack.push(module);
        for next in graph.get(module).into_iter().flatten() {
            visit(next, graph, stack, done);
        }
        stack.pop();
        done.insert(module);
    }
    let mut done = BTreeSet::new();
    for module in graph.keys() {
        visit(module, &graph, &mut Vec::new(), &mut done);
    }
    // The seams later work builds on: the helpers sit below every handler, and the router
    // is the only user of the handlers (besides `fuzzing`, the fuzz targets' hidden window on
    // the handlers' parsers, at the top beside the router).
    for (module, uses) in &graph {
        let handler = module.starts_with("http::handlers::");
        for used in uses {
            if used.starts_with("http::handlers") {
                assert!(
                    module == "http::router"
                        || module == "http"
                        || module == "fuzzing"
                        || (module == "http::handlers" && handler),
                    "{module} uses {used}: only the router takes handlers"
                );
            }
            if handler {
                assert!(
                    !used.starts_with("http::handlers::"),
                    "{module} uses {used}"
                );
            }
        }
    }
    // The graph is what the files say (a parser that missed edges would find no cycle).
    let uses = |module: &str, used: &str| graph[module].contains(used);
    assert!(uses("http::handlers::trials", "http::helpers"));
    assert!(uses("http::handlers::trials", "ingest::trials"));
    assert!(uses("jobs::playback", "app_state") && uses("jobs::playback_run", "ingest::trials"));
    assert!(uses("jobs::live_session", "estimate::live_sessions"));
    assert!(uses("session::lifecycle", "storage") && uses("session::lifecycle", "error"));
    assert!(uses("storage::sqlite::sessions", "storage::metadata"));
    assert!(uses("http::router", "http::handlers") && uses("http::server", "http::router"));
    assert!(
        !graph["http::helpers"]
            .iter()
            .any(|m| m.starts_with("http::handlers"))
    );
}

/// The modules of the two metadata stores that own the `sessions` table.
const SESSION_TABLES: [&str; 2] = ["storage::sqlite::sessions", "storage::postgres::sessions"];

#[test]
fn only_the_lifecycle_writes_a_sessions_state() {
    let mut sql_writers = BTreeSet::new();
    for (module, code) in sources() {
        let mut rest = code.as_str();
        while let Some(at) = rest.find("UPDATE sessions") {
            rest = &rest[at..];
            let statement = &rest[..rest.find("WHERE").unwrap_or(rest.len())];
            if statement.contains("state") {
                sql_writers.insert(module.clone());
            }
            rest = &rest["UPDATE sessions".len()..];
        }
        if code.contains("INSERT INTO sessions") {
            // A row is born `created`; nothing but the store's sessions make rows.
            assert!(
                SESSION_TABLES.contains(&module.as_str()),
                "{module} inserts sessions"
            );
        }
        // The store's state writes are called by the lifecycle alone.
        if !module.starts_with("storage") {
            for call in ["store.transition(", "db.transition(", ".fail_unreadable("] {
                let direct = code.contains(call) && !code.contains("lifecycle().fail_unreadable(");
                assert!(
                    !direct || module == "session::lifecycle",
                    "{module} calls {call} directly: go through session::Lifecycle"
                );
            }
        }
        // The wire names of the states are written once (the jobs table shares two).
        for name in [
            "created",
            "uploaded",
            "playing",
            "estimating",
            "done",
            "failed",
        ] {
            let literal = format!("\"{name}\"");
            if code.contains(&literal) {
                let jobs = module == "storage::metadata" && matches!(name, "done" | "failed");
                // The playback app's status file (docs/playback-contract.md) has a
                // `failed MESSAGE` line of its own: a word of that contract, not a state.
                let status_file = module == "playback::adb" && name == "failed";
                assert!(
                    module == "model::session_state" || jobs || status_file,
                    "{module} spells the state {literal}"
                );
            }
        }
    }
    // In the embedded store, the state is written by `transition` and `fail_unreadable`
    // of one file.
    assert_eq!(
        sql_writers,
        BTreeSet::from(SESSION_TABLES.map(String::from)),
        "modules that write a session's state"
    );
}

#[test]
fn only_the_storage_folder_speaks_sql() {
    let sources = sources();
    assert!(sources.len() > 40, "{:?}", sources.keys());
    for (module, code) in &sources {
        let sql = [
            "rusqlite",
            "SELECT ",
            "INSERT INTO",
            "DELETE FROM",
            "CREATE TABLE",
        ]
        .into_iter()
        .find(|word| code.contains(word));
        if let Some(word) = sql {
            assert!(
                module.starts_with("storage::sqlite") || module.starts_with("storage::postgres"),
                "{module} speaks SQL ({word:?}): only storage::sqlite and storage::postgres may"
            );
        }
    }
    // The test sees what the files hold: the embedded store does speak SQL.
    assert!(sources["storage::sqlite::sessions"].contains("INSERT INTO sessions"));
}

/// The layer list of lib.rs's comment (`// name — what`), lowest first.
fn layer_list(lib: &str) -> Vec<String> {
    lib.lines()
        .filter_map(|l| l.trim_start().strip_prefix("// "))
        .filter_map(|l| l.split_once(" — "))
        .map(|(name, _)| name.trim().to_string())
        .filter(|name| name.chars().all(|c| c.is_ascii_lowercase() || c == '_'))
        .collect()
}

#[test]
fn the_layer_comment_is_true() {
    let lib =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs")).unwrap();
    let layers = layer_list(&lib);
    let declared: BTreeSet<&str> = lib
        .lines()
        .filter_map(|l| {
            let l = l.trim();
            l.strip_prefix("mod ")
                .or_else(|| l.strip_prefix("pub mod "))
                .and_then(|rest| rest.strip_suffix(';'))
        })
        .collect();
    assert!(declared.len() >= 10, "{declared:?}");
    let listed: BTreeSet<&str> = layers.iter().map(String::as_str).collect();
    assert_eq!(
        declared, listed,
        "lib.rs's layer comment must list exactly the modules it declares"
    );
    // Every import between top-level modules points down the list.
    let rank = |module: &str| {
        let top = module.split("::").next().unwrap_or(module);
        layers.iter().position(|l| l == top)
    };
    let mut upward = Vec::new();
    for (module, uses) in graph() {
        let Some(from) = rank(&module) else { continue };
        for used in uses {
            if rank(&used).is_some_and(|to| to > from) {
                upward.push(format!("{module} → {used}"));
            }
        }
    }
    assert!(
        upward.is_empty(),
        "imports against lib.rs's layer list (a module may import only modules listed \
         before it):\n{}",
        upward.join("\n")
    );
}

#[test]
fn the_layer_list_is_read_in_order() {
    let lib = "// Folders, lowest first:\n// error — the enum\n// model    — words\n\
               // see `a — b` here\nmod error;";
    assert_eq!(layer_list(lib), ["error", "model"]);
}

#[test]
fn only_the_storage_folder_touches_the_data_directory() {
    // File-system calls outside `storage`, each with the one reason it may have: none of them
    // builds a path in the data directory (they read what they are handed, or the system's).
    let allowed: BTreeMap<&str, &str> = BTreeMap::from([
        (
            "http::tls::certificate",
            "reads /etc/hostname and the operator's --cert/--key",
        ),
        (
            "playback::adb",
            "the playback scratch folder beside the local recording it is handed",
        ),
        (
            "ingest::mp4_check",
            "reads the staged upload it is handed, and the local sim recording the sim player is",
        ),
        (
            "playback::remote",
            "hashes the local recording it is handed (the playback hosts' cache key)",
        ),
    ]);
    let sources = sources();
    let mut found = BTreeSet::new();
    for (module, code) in &sources {
        if module.starts_with("storage") || module == "lib" {
            continue;
        }
        for call in ["std::fs", "tokio::fs", "File::open", "File::create"] {
            if code.contains(call) {
                found.insert(module.as_str());
                assert!(
                    allowed.contains_key(module.as_str()),
                    "{module} uses {call}: only storage touches the data directory"
                );
            }
        }
        // Nobody but the app state (which opens the stores) reaches for the embedded ones.
        for word in ["storage::files", "storage::sqlite", "data_dir.join"] {
            assert!(
                !code.contains(word) || module == "app_state",
                "{module} names {word}: go through the storage traits"
            );
        }
    }
    // The allowances are still needed (a stale one would hide a new use).
    let unused: Vec<_> = allowed.keys().filter(|m| !found.contains(*m)).collect();
    assert!(unused.is_empty(), "allowed but unused: {unused:?}");
}
