//! The CLI's layout, checked from its source (`layout_graph` reads the imports): `src/`
//! follows `sitar --help`'s groups (each command of `GROUPS` in lib.rs lives in its group's
//! folder, nothing but lib.rs and main.rs at the top), no file is over 600 lines, and the
//! figures sit below what draws them (the figure model a leaf). No import cycle, between
//! files or folders, is `tests/layout.rs`'s check for every crate.

mod layout_graph;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The longest a source file may be.
const MAX_LINES: usize = 600;

/// The folder of each group of `sitar --help` (by the start of its title in lib.rs's
/// `GROUPS`).
const GROUP_FOLDERS: &[(&str, &str)] = &[
    ("Getting started", "getting_started"),
    ("Backend", "backend"),
    ("evo-compatible", "evo"),
    ("Beyond evo", "beyond_evo"),
    ("SiTAR analysis", "analysis"),
    ("Tools", "tools"),
];

/// The CLI's `src/`.
fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../rust/cli/src")
}

#[test]
fn the_figures_sit_below_what_draws_them() {
    let graph: BTreeMap<String, BTreeSet<String>> =
        layout_graph::graph(&layout_graph::sources(&src()));
    assert!(graph.len() > 40, "{:?}", graph.keys());
    // The figure model is a leaf; drawing sits below the files, the files below the
    // builders (a parser that missed edges would find no cycle either).
    assert!(
        graph["figures::figure"].is_empty(),
        "figures::figure uses {:?}",
        graph["figures::figure"]
    );
    let uses = |module: &str, used: &str| graph[module].contains(used);
    let within =
        |module: &str, folder: &str| module == folder || module.starts_with(&format!("{folder}::"));
    // A file of `folder` (or the file itself) using `used`.
    let any_uses = |folder: &str, used: &str| {
        graph
            .iter()
            .any(|(m, u)| within(m, folder) && u.contains(used))
    };
    // `module` using `folder` or a file of it.
    let any_uses_of = |module: &str, folder: &str| graph[module].iter().any(|u| within(u, folder));
    assert!(uses("figures::plot", "figures::figure"));
    assert!(any_uses_of("figures::panels", "figures::plot"));
    assert!(uses("figures::canvas", "figures::panels"));
    assert!(uses("results::error_figures", "figures::canvas"));
    assert!(uses("results::error_figures", "results::metric_args"));
    assert!(uses("results::error_figures", "results::archive"));
    // drift and relative share their options.
    assert!(uses("beyond_evo::drift", "beyond_evo::shared_args"));
    assert!(uses("beyond_evo::relative", "beyond_evo::shared_args"));
    assert!(!any_uses("figures::plot", "figures::canvas"));
    assert!(!uses("figures::canvas", "results::error_figures"));
}

#[test]
fn no_file_is_over_the_limit() {
    let files = layout_graph::rust_files(&src());
    assert!(files.len() > 40, "{files:?}");
    let long: Vec<(String, usize)> = files
        .iter()
        .map(|f| {
            let lines = std::fs::read_to_string(f).unwrap().lines().count();
            (f.strip_prefix(src()).unwrap().display().to_string(), lines)
        })
        .filter(|(_, lines)| *lines > MAX_LINES)
        .collect();
    assert!(
        long.is_empty(),
        "files over {MAX_LINES} lines (split them by concept): {long:?}"
    );
}

/// lib.rs's `GROUPS`: each group's title and its commands.
fn groups() -> Vec<(String, Vec<String>)> {
    let lib = std::fs::read_to_string(src().join("lib.rs")).unwrap();
    let start = lib.find("const GROUPS").expect("lib.rs declares GROUPS");
    let block = &lib[start..];
    let block = &block[block.find("= &[").unwrap() + 4..];
    let block = &block[..block.find("\n];").unwrap()];
    let literals =
        |s: &str| -> Vec<String> { s.split('"').skip(1).step_by(2).map(str::to_owned).collect() };
    let mut groups = Vec::new();
    let mut rest = block;
    while let Some(list) = rest.find("&[") {
        let title = literals(&rest[..list])
            .pop()
            .expect("a title before each list");
        let end = list + rest[list..].find(']').unwrap();
        groups.push((title, literals(&rest[list..end])));
        rest = &rest[end + 1..];
    }
    groups
}

#[test]
fn each_command_lives_in_its_groups_folder() {
    let groups = groups();
    assert!(groups.len() >= 6, "{groups:?}");
    let lib = std::fs::read_to_string(src().join("lib.rs")).unwrap();
    let mut commands = 0;
    for (title, names) in &groups {
        let folder = GROUP_FOLDERS
            .iter()
            .find(|(start, _)| title.starts_with(start))
            .map(|(_, folder)| *folder)
            .unwrap_or_else(|| panic!("group {title:?} has no folder in GROUP_FOLDERS"));
        assert!(
            lib.contains(&format!("\nmod {folder};")),
            "lib.rs does not declare the group folder {folder}"
        );
        // `help` is clap's own command.
        for name in names.iter().filter(|n| *n != "help") {
            let dir = src().join(folder);
            let file = dir.join(format!("{name}.rs"));
            let module = dir.join(name).join("mod.rs");
            assert!(
                file.is_file() || module.is_file(),
                "`sitar {name}` ({title}) is not in src/{folder}/: no {name}.rs nor {name}/mod.rs"
            );
            commands += 1;
        }
    }
    assert!(commands >= 19, "{groups:?}");
    // And nothing of a command is left at the top: src/ holds lib.rs, main.rs and folders.
    let top: Vec<String> = std::fs::read_dir(src())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .filter(|n| n != "lib.rs" && n != "main.rs")
        .collect();
    assert!(top.is_empty(), "files at the top of src/: {top:?}");
}
