//! Every relative link in the README, the user guide (`docs/`) and the crate READMEs
//! resolves, offline: the file exists and, for a `#anchor` into Markdown, the page has a
//! heading with that id (mdBook's ids: lower-case, spaces to `-`, punctuation dropped,
//! repeats numbered), and a link in the guide stays inside it (`docs/src`, what the built
//! book holds). Every page under `docs/src` is in `SUMMARY.md`, and every `{{#include}}`
//! names a file that exists.

use std::collections::{BTreeSet, HashMap};
use std::path::{Component, Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// Markdown files whose links are checked, relative to the repository.
fn checked_files(root: &Path) -> Vec<PathBuf> {
    let mut files = vec![PathBuf::from("README.md")];
    let mut stack = vec![root.join("docs")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                // The built book is not a source.
                if path.file_name().is_some_and(|n| n == "book") {
                    continue;
                }
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                files.push(path.strip_prefix(root).unwrap().to_path_buf());
            }
        }
    }
    for entry in std::fs::read_dir(root.join("rust")).unwrap() {
        let readme = entry.unwrap().path().join("README.md");
        if readme.exists() {
            files.push(readme.strip_prefix(root).unwrap().to_path_buf());
        }
    }
    files.sort();
    files
}

/// The text outside fenced code blocks and inline code spans, line by line.
fn prose_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fence = false;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fence = !fence;
            continue;
        }
        if fence {
            continue;
        }
        let mut kept = String::new();
        let mut in_code = false;
        for ch in line.chars() {
            if ch == '`' {
                in_code = !in_code;
            } else if !in_code {
                kept.push(ch);
            }
        }
        out.push((i + 1, kept));
    }
    out
}

/// `[text](target)` and `![alt](target)` targets of one line.
fn link_targets(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let bytes = line.as_bytes();
    let mut i = 0;
    while let Some(pos) = line[i..].find("](") {
        let start = i + pos + 2;
        let mut depth = 1;
        let mut end = start;
        while end < bytes.len() {
            match bytes[end] {
                b'(' => depth += 1,
                b')' => {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                _ => {}
            }
            end += 1;
        }
        if end >= bytes.len() {
            break;
        }
        let target = line[start..end].split_whitespace().next().unwrap_or("");
        out.push(target.to_owned());
        i = end;
    }
    out
}

/// mdBook's id of a heading's text (`normalize_id`), from the Markdown source: link
/// targets, code and emphasis marks removed first.
fn heading_id(text: &str) -> String {
    let mut plain = String::new();
    let mut rest = text;
    // [label](target) → label
    while let Some(open) = rest.find('[') {
        plain.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        match (after.find("]("), after.find(')')) {
            (Some(close), Some(paren)) if close < paren => {
                plain.push_str(&after[..close]);
                rest = &after[paren + 1..];
            }
            _ => {
                plain.push('[');
                rest = after;
            }
        }
    }
    plain.push_str(rest);
    plain
        .trim()
        .chars()
        .filter_map(|ch| {
            if ch.is_alphanumeric() || ch == '_' || ch == '-' {
                Some(ch.to_ascii_lowercase())
            } else if ch.is_whitespace() {
                Some('-')
            } else {
                None
            }
        })
        .collect()
}

/// The ids of a Markdown file's headings, numbered as mdBook numbers repeats.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut seen: HashMap<String, usize> = HashMap::new();
    let mut out = BTreeSet::new();
    let mut fence = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fence = !fence;
            continue;
        }
        if fence || !line.starts_with('#') {
            continue;
        }
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if hashes > 6 || !line[hashes..].starts_with(' ') {
            continue;
        }
        let id = heading_id(&line[hashes + 1..]);
        let n = seen.entry(id.clone()).or_insert(0);
        out.insert(if *n == 0 {
            id.clone()
        } else {
            format!("{id}-{n}")
        });
        *n += 1;
    }
    out
}

/// `a/b/../c` → `a/c`, without touching the file system.
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// The text a page shows: its own, with `{{#include FILE}}` lines replaced.
fn rendered(root: &Path, file: &Path) -> String {
    let text = std::fs::read_to_string(root.join(file)).unwrap();
    let mut out = String::new();
    for line in text.lines() {
        if let Some(inc) = line
            .trim()
            .strip_prefix("{{#include ")
            .and_then(|l| l.strip_suffix("}}"))
        {
            let target = normalize(&file.parent().unwrap().join(inc.trim()));
            out.push_str(&std::fs::read_to_string(root.join(target)).unwrap_or_default());
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    out
}

fn broken_links(root: &Path) -> Vec<String> {
    let mut broken = Vec::new();
    let mut anchor_cache: HashMap<PathBuf, BTreeSet<String>> = HashMap::new();
    for file in checked_files(root) {
        let text = std::fs::read_to_string(root.join(&file)).unwrap();
        for (n, line) in prose_lines(&text) {
            if let Some(inc) = line
                .trim()
                .strip_prefix("{{#include ")
                .and_then(|l| l.strip_suffix("}}"))
            {
                let target = normalize(&file.parent().unwrap().join(inc.trim()));
                if !root.join(&target).is_file() {
                    broken.push(format!(
                        "{}:{n}: include {} does not exist",
                        file.display(),
                        target.display()
                    ));
                }
            }
            for target in link_targets(&line) {
                if target.is_empty()
                    || target.contains("://")
                    || target.starts_with("mailto:")
                    || target.starts_with('<')
                {
                    continue;
                }
                let (path, anchor) = match target.split_once('#') {
                    Some((p, a)) => (p, Some(a)),
                    None => (target.as_str(), None),
                };
                let resolved = if path.is_empty() {
                    file.clone()
                } else {
                    normalize(&file.parent().unwrap().join(path))
                };
                // The book holds docs/src only: a link out of it is dead in the built
                // guide (name a repository file as `code` instead).
                if file.starts_with("docs/src") && !resolved.starts_with("docs/src") {
                    broken.push(format!(
                        "{}:{n}: {target}: leaves the guide ({})",
                        file.display(),
                        resolved.display()
                    ));
                    continue;
                }
                if !root.join(&resolved).exists() {
                    broken.push(format!(
                        "{}:{n}: {target}: {} does not exist",
                        file.display(),
                        resolved.display()
                    ));
                    continue;
                }
                if let Some(anchor) = anchor
                    && resolved.extension().is_some_and(|e| e == "md")
                {
                    let ids = anchor_cache
                        .entry(resolved.clone())
                        .or_insert_with(|| anchors(&rendered(root, &resolved)));
                    if !ids.contains(anchor) {
                        broken.push(format!(
                            "{}:{n}: {target}: no heading #{anchor} in {}",
                            file.display(),
                            resolved.display()
                        ));
                    }
                }
            }
        }
    }
    broken
}

#[test]
fn every_link_in_the_readme_and_the_guide_resolves() {
    let root = repo();
    let broken = broken_links(&root);
    assert!(
        broken.is_empty(),
        "{} broken links:\n{}",
        broken.len(),
        broken.join("\n")
    );
}

#[test]
fn every_guide_page_is_in_the_summary() {
    let root = repo();
    let src = root.join("docs/src");
    let summary = std::fs::read_to_string(src.join("SUMMARY.md")).unwrap();
    let listed: BTreeSet<PathBuf> = prose_lines(&summary)
        .iter()
        .flat_map(|(_, l)| link_targets(l))
        .map(|t| normalize(Path::new(&t)))
        .collect();
    let mut missing = Vec::new();
    let mut stack = vec![src.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                let rel = path.strip_prefix(&src).unwrap().to_path_buf();
                if rel != Path::new("SUMMARY.md") && !listed.contains(&rel) {
                    missing.push(rel.display().to_string());
                }
            }
        }
    }
    missing.sort();
    assert!(missing.is_empty(), "pages not in SUMMARY.md: {missing:?}");
}

#[test]
fn the_checker_finds_a_broken_link_and_a_missing_anchor() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    std::fs::create_dir_all(root.join("docs/src")).unwrap();
    std::fs::create_dir_all(root.join("rust")).unwrap();
    std::fs::write(
        root.join("README.md"),
        "[ok](docs/src/a.md#the-page-a) [gone](docs/src/b.md) `[code](x.md)`\n\
         [anchor](docs/src/a.md#nowhere) [repeat](docs/src/a.md#same-1)\n",
    )
    .unwrap();
    std::fs::write(
        root.join("docs/src/c.md"),
        "# C\n\n[back](a.md#same) [out](../../README.md)\n",
    )
    .unwrap();
    std::fs::write(
        root.join("docs/src/a.md"),
        "# The page: A\n\n## Same\n\n## Same\n\n```\n# not a heading\n```\n",
    )
    .unwrap();
    let broken = broken_links(root);
    assert_eq!(broken.len(), 3, "{broken:?}");
    assert!(
        broken[0].contains("docs/src/b.md does not exist"),
        "{broken:?}"
    );
    assert!(broken[1].contains("no heading #nowhere"), "{broken:?}");
    assert!(
        broken[2].contains("c.md:3: ../../README.md: leaves the guide"),
        "{broken:?}"
    );
}

#[test]
fn ids_are_mdbooks() {
    assert_eq!(
        heading_id("Moving up: `sitar migrate`"),
        "moving-up-sitar-migrate"
    );
    assert_eq!(
        heading_id("Beyond evo: drift over path length, repeated runs"),
        "beyond-evo-drift-over-path-length-repeated-runs"
    );
    assert_eq!(heading_id("[The C ABI](x.md)"), "the-c-abi");
}

/// Every Markdown file of the repository (build output and installed packages aside).
fn markdown_files(root: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if path.is_dir() {
                let skip = name.starts_with('.')
                    || name == "target"
                    || name == "node_modules"
                    || (name == "book" && path.parent() == Some(&root.join("docs")));
                if !skip {
                    stack.push(path);
                }
            } else if name.ends_with(".md") {
                out.push(path);
            }
        }
    }
    out
}

#[test]
fn no_markdown_file_is_over_600_lines_and_the_readme_over_150() {
    let root = repo();
    let files = markdown_files(&root);
    assert!(
        files.len() > 50,
        "found only {} Markdown files",
        files.len()
    );
    let lines = |p: &Path| std::fs::read_to_string(p).unwrap().lines().count();
    let long: Vec<String> = files
        .iter()
        .filter(|p| lines(p) > 600)
        .map(|p| format!("{} ({} lines)", p.display(), lines(p)))
        .collect();
    assert!(long.is_empty(), "Markdown files over 600 lines: {long:?}");
    let readme = lines(&root.join("README.md"));
    assert!(readme <= 150, "README.md has {readme} lines (at most 150)");
}
