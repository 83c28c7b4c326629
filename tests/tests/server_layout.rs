//! The server's layout, checked from its source (`layout_graph` reads the imports): the
//! modules follow lib.rs's layer list, handlers use the HTTP helpers and never each other,
//! only the stores speak SQL or touch the data directory, and one writer of a session's
//! state.

mod layout_graph;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use layout_graph::layer_list;

/// The server's `src/`.
fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../rust/server/src")
}

/// The server's files by module path (`""` for lib.rs), their code without comments or tests.
fn sources() -> BTreeMap<String, String> {
    layout_graph::sources(&src())
}

/// Module → the modules it uses.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    layout_graph::graph(&sources())
}

#[test]
fn handlers_use_the_helpers_and_never_each_other() {
    let graph = graph();
    assert!(graph.len() > 20, "{:?}", graph.keys());
    // The seams later work builds on: the helpers sit below every handler, and the router
    // is the only user of the handlers (besides `fuzzing`, the fuzz targets' hidden window on
    // the handlers' parsers, at the top beside the router). A share link is another door to
    // the answers of the resources it names (report, scene, results, evidence images), so
    // `share` alone answers with other handlers' answers.
    const SHARE: &str = "http::handlers::share";
    for (module, uses) in &graph {
        let handler = module.starts_with("http::handlers::") && module != SHARE;
        for used in uses {
            if used.starts_with("http::handlers") {
                assert!(
                    module == "http::router"
                        || module == "http"
                        || module == "fuzzing"
                        || module == SHARE
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

#[test]
fn the_layer_comment_is_true() {
    let lib = std::fs::read_to_string(src().join("lib.rs")).unwrap();
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
    // The vocabulary at the bottom and the stores on it alone; the lifecycle, access control
    // and venue logic (and all else) above both.
    assert_eq!(layers[..3], ["error", "model", "storage"], "{layers:?}");
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
        if module.starts_with("storage") || module.is_empty() {
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
