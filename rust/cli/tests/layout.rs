//! The CLI's layout, checked from its source: no import cycle among the modules of
//! `src/` (a module's uses are the `crate::name` paths in its code, `use crate::{a, b::c}`
//! groups included, tests and comment lines left out), and the figure model a leaf.

use std::collections::{BTreeMap, BTreeSet};

/// Module name → the modules its code names.
fn uses() -> BTreeMap<String, BTreeSet<String>> {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut code = BTreeMap::new();
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        let Some(stem) = path.file_stem().map(|s| s.to_string_lossy().into_owned()) else {
            continue;
        };
        if path.extension().is_some_and(|e| e == "rs") && stem != "main" && stem != "lib" {
            let text = std::fs::read_to_string(&path).unwrap();
            let before_tests = text.split("#[cfg(test)]").next().unwrap_or_default();
            let lines = before_tests
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"));
            code.insert(stem, lines.collect::<Vec<_>>().join("\n"));
        }
    }
    let modules: BTreeSet<String> = code.keys().cloned().collect();
    code.iter()
        .map(|(module, text)| {
            let named = text
                .split("crate::")
                .skip(1)
                .flat_map(first_names)
                .filter(|n| modules.contains(n) && n != module)
                .collect();
            (module.clone(), named)
        })
        .collect()
}

/// The module names at the start of what follows `crate::`: one name, or each item's first
/// name in a `{a, b::c, d::{e, f}}` group.
fn first_names(after: &str) -> Vec<String> {
    let ident = |s: &str| -> String {
        s.trim_start()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let Some(group) = after.strip_prefix('{') else {
        return vec![ident(after)];
    };
    let mut names = Vec::new();
    let (mut depth, mut item_start) = (0, true);
    for (i, c) in group.char_indices() {
        if item_start && depth == 0 && !c.is_whitespace() {
            names.push(ident(&group[i..]));
            item_start = false;
        }
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => break,
            '}' => depth -= 1,
            ',' if depth == 0 => item_start = true,
            _ => {}
        }
    }
    names
}

#[test]
fn first_names_read_paths_and_groups() {
    assert_eq!(first_names("plot::legend(x)"), ["plot"]);
    assert_eq!(
        first_names("{canvas::{self, Page}, console::Console, metric};"),
        ["canvas", "console", "metric"]
    );
}

#[test]
fn no_import_cycle_among_the_modules() {
    let graph = uses();
    assert!(graph.len() > 20, "{:?}", graph.keys());
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
        graph["figure"].is_empty(),
        "figure uses {:?}",
        graph["figure"]
    );
    let uses = |module: &str, used: &str| graph[module].contains(used);
    assert!(uses("plot", "figure") && uses("panels", "plot") && uses("canvas", "panels"));
    assert!(
        uses("figures", "canvas") && uses("figures", "metric_args") && uses("figures", "archive")
    );
    assert!(!uses("plot", "canvas") && !uses("canvas", "figures"));
}
