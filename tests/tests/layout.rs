//! Every crate's layout, checked from its source: no file-level import cycle among the
//! modules of any crate under `rust/` (dependencies run one way inside a crate, as they do
//! between crates).
//!
//! Folders too: drawn as its top-level folders (and root files), each crate's graph has no
//! cycle. The server's layer order is `server_layout.rs`'s check, the CLI's folders
//! `cli_layout.rs`'s; all three read the imports through `layout_graph`.

mod layout_graph;

use std::collections::BTreeSet;

use layout_graph::{crates, cycles, folder_graph, graph, module_paths, root_items, sources};

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
