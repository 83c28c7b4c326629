//! The CLI's layout, checked from its source: `src/` follows `sitar --help`'s groups (each
//! command of `GROUPS` in lib.rs lives in its group's folder), no file is over 600 lines, and
//! no import cycle among the files (a module's path is its file's path under `src/`, `mod.rs`
//! being its folder; a file's uses are the `crate::…` and `super::…` paths in its code,
//! `use crate::{a, b::{c, d}}` groups included, tests and comment lines left out), the figure
//! model a leaf.

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

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            files.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
    files
}

/// A file's module path: `figures/plot/axes.rs` is `figures::plot::axes`, `evo/traj/mod.rs`
/// is `evo::traj`.
fn module_path(file: &Path) -> String {
    let relative = file.strip_prefix(src()).unwrap().with_extension("");
    let mut parts: Vec<String> = relative
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts.join("::")
}

/// The code a module's uses are read from: before its tests, without comment lines.
fn code(text: &str) -> String {
    let before_tests = text.split("#[cfg(test)]").next().unwrap_or_default();
    before_tests
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Module path → the modules its code names (lib.rs and main.rs left out: they name every
/// group).
fn uses() -> BTreeMap<String, BTreeSet<String>> {
    let mut code_of = BTreeMap::new();
    for file in rust_files(&src()) {
        let module = module_path(&file);
        if module != "lib" && module != "main" {
            code_of.insert(module, code(&std::fs::read_to_string(&file).unwrap()));
        }
    }
    let modules: BTreeSet<String> = code_of.keys().cloned().collect();
    code_of
        .iter()
        .map(|(module, text)| {
            let parent: Vec<&str> = module.split("::").collect();
            let parent = parent[..parent.len() - 1].join("::");
            let mut named = BTreeSet::new();
            for (anchor, base) in [("crate::", String::new()), ("super::", parent)] {
                for after in text.split(anchor).skip(1) {
                    for path in paths(after) {
                        let full: Vec<String> = base
                            .split("::")
                            .filter(|s| !s.is_empty())
                            .map(str::to_owned)
                            .chain(path)
                            .collect();
                        // The longest prefix that is a module: the rest names an item in it.
                        let found = (1..=full.len())
                            .rev()
                            .map(|n| full[..n].join("::"))
                            .find(|m| modules.contains(m));
                        if let Some(used) = found.filter(|m| m != module) {
                            named.insert(used);
                        }
                    }
                }
            }
            (module.clone(), named)
        })
        .collect()
}

/// The paths at the start of what follows `crate::`: `a::b::c`, or a use tree
/// `a::{b, c::{d, e}, self}` as each of its paths.
fn paths(after: &str) -> Vec<Vec<String>> {
    let chars: Vec<char> = after.chars().take(4000).collect();
    tree(&chars, &mut 0)
}

/// Reads one use tree from `s[at..]`, leaving `at` after it.
fn tree(s: &[char], at: &mut usize) -> Vec<Vec<String>> {
    let skip_space = |at: &mut usize| {
        while s.get(*at).is_some_and(|c| c.is_whitespace()) {
            *at += 1;
        }
    };
    let mut prefix: Vec<String> = Vec::new();
    loop {
        skip_space(at);
        if s.get(*at) == Some(&'{') {
            *at += 1;
            let mut paths = Vec::new();
            loop {
                skip_space(at);
                match s.get(*at) {
                    None => break,
                    Some('}') => {
                        *at += 1;
                        break;
                    }
                    Some(',') => *at += 1,
                    Some(_) => {
                        let before = *at;
                        for path in tree(s, at) {
                            let mut full = prefix.clone();
                            full.extend(path.into_iter().filter(|p| p != "self"));
                            paths.push(full);
                        }
                        if *at == before {
                            *at += 1; // `*` and the like: the group's prefix itself
                        }
                    }
                }
            }
            return paths;
        }
        let start = *at;
        while s.get(*at).is_some_and(|c| c.is_alphanumeric() || *c == '_') {
            *at += 1;
        }
        if *at == start {
            return vec![prefix];
        }
        prefix.push(s[start..*at].iter().collect());
        if s.get(*at) == Some(&':') && s.get(*at + 1) == Some(&':') {
            *at += 2;
        } else {
            return vec![prefix];
        }
    }
}

fn names(paths: Vec<Vec<String>>) -> Vec<String> {
    paths.into_iter().map(|p| p.join("::")).collect()
}

#[test]
fn paths_read_single_paths_and_use_trees() {
    assert_eq!(
        names(paths("figures::plot::legend(x)")),
        ["figures::plot::legend"]
    );
    assert_eq!(
        names(paths(
            "{figures::canvas::{self, Page}, io::console::Console, metric};"
        )),
        [
            "figures::canvas",
            "figures::canvas::Page",
            "io::console::Console",
            "metric"
        ]
    );
    assert_eq!(
        names(paths("evo::traj::{args::{Args, Format}, Kind};")),
        [
            "evo::traj::args::Args",
            "evo::traj::args::Format",
            "evo::traj::Kind"
        ]
    );
}

#[test]
fn module_paths_follow_the_folders() {
    assert_eq!(
        module_path(&src().join("figures/plot/axes.rs")),
        "figures::plot::axes"
    );
    assert_eq!(module_path(&src().join("evo/traj/mod.rs")), "evo::traj");
    assert_eq!(module_path(&src().join("lib.rs")), "lib");
}

#[test]
fn no_import_cycle_among_the_modules() {
    let graph = uses();
    assert!(graph.len() > 40, "{:?}", graph.keys());
    // Kahn's algorithm: peel modules that use nothing left; whatever remains is on a cycle.
    let mut left = graph.clone();
    while let Some(leaf) = left
        .iter()
        .find(|(_, used)| used.iter().all(|u| !left.contains_key(u)))
        .map(|(m, _)| m.clone())
    {
        left.remove(&leaf);
    }
    assert!(
        left.is_empty(),
        "modules on an import cycle (each with what it uses among them): {:?}",
        left.iter()
            .map(|(m, used)| (
                m,
                used.iter()
                    .filter(|u| left.contains_key(*u))
                    .collect::<Vec<_>>()
            ))
            .collect::<Vec<_>>()
    );
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
    assert!(uses("figures::error_figures", "figures::canvas"));
    assert!(uses("figures::error_figures", "results::metric_args"));
    assert!(uses("figures::error_figures", "results::archive"));
    // super:: paths count: the worker's slot names its parent.
    assert!(uses("backend::worker::slot", "backend::worker"));
    assert!(!any_uses("figures::plot", "figures::canvas"));
    assert!(!uses("figures::canvas", "figures::error_figures"));
}

#[test]
fn no_file_is_over_the_limit() {
    let files = rust_files(&src());
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
