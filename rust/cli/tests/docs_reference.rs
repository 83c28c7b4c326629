//! The guide's reference pages (docs/src/reference/) are generated from the code: every
//! command's `--help` (clap), the HTTP routes (the router's table, each handler's doc, the
//! body limits, the error codes), the C ABI (`rust/ffi/include/sitar.h`), the
//! configuration keys (`SessionConfig`, `ServerConfig`), the CSV headers and the JSON files'
//! keys (the calibration file, results, estimates). This test fails when a committed
//! page differs from what the code gives; `SITAR_REGENERATE=1 cargo test -p sitar-cli --test
//! docs_reference` rewrites them (and the commands' entries of docs/src/SUMMARY.md).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

const HEADER: &str = "<!-- Generated from the code by `SITAR_REGENERATE=1 cargo test -p sitar-cli \
                      --test docs_reference`; do not edit. -->\n\n";

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(repo().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// `sitar ARGS… --help`, at a fixed width.
fn help(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_sitar"))
        .args(args)
        .arg("--help")
        .env("COLUMNS", "100")
        .env("NO_COLOR", "1")
        .env_remove("CLICOLOR_FORCE")
        .output()
        .unwrap();
    assert!(out.status.success(), "sitar {args:?} --help failed");
    String::from_utf8(out.stdout).unwrap()
}

/// The subcommands a help text lists: the indented names under `Commands:`, `help` left
/// out (the top level's groups: [`groups`]).
fn subcommands(help: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut in_list = false;
    for line in help.lines() {
        if !line.starts_with(' ') && line.ends_with(':') && !line.starts_with("Usage") {
            in_list = line == "Commands:";
            continue;
        }
        if line.is_empty() {
            continue;
        }
        if in_list
            && line.starts_with("  ")
            && !line.starts_with("   ")
            && let Some(name) = line.split_whitespace().next()
            && name != "help"
            && name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-')
        {
            let about = line.trim_start()[name.len()..].trim().to_owned();
            out.push((name.to_owned(), about));
        }
    }
    out
}

/// The top level's groups: title and commands.
fn groups(top: &str) -> Vec<(String, Vec<String>)> {
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    for line in top.lines() {
        if !line.starts_with(' ') && line.ends_with(':') && !line.starts_with("Usage") {
            if line == "Options:" {
                break;
            }
            out.push((line.trim_end_matches(':').to_owned(), Vec::new()));
        } else if let (Some(last), Some(name)) = (out.last_mut(), line.split_whitespace().next())
            && line.starts_with("  ")
            && name != "help"
        {
            last.1.push(name.to_owned());
        }
    }
    out
}

fn fence(text: &str) -> String {
    format!("```text\n{}\n```\n", text.trim_end())
}

/// Every command's page (`reference/cli/NAME.md`, nested commands `A-B.md`), the index
/// page, and the SUMMARY lines for them.
fn cli_pages(pages: &mut BTreeMap<String, String>) -> Vec<String> {
    let top = help(&[]);
    let mut index = format!(
        "{HEADER}# Commands\n\n`sitar --help`:\n\n{}\nEach command's page is its `--help`; \
         a command with subcommands (the input formats of `ape`, `rpe`, `traj`; `token`'s \
         actions) has one page each.\n\n",
        fence(&top)
    );
    let mut summary = Vec::new();
    for (title, names) in groups(&top) {
        index.push_str(&format!("## {title}\n\n"));
        for name in names {
            walk(&[name.as_str()], 1, pages, &mut index, &mut summary);
        }
        index.push('\n');
    }
    pages.insert("reference/cli.md".into(), index);
    summary
}

fn walk(
    path: &[&str],
    depth: usize,
    pages: &mut BTreeMap<String, String>,
    index: &mut String,
    summary: &mut Vec<String>,
) {
    let text = help(path);
    let file = format!("reference/cli/{}.md", path.join("-"));
    let cmd = format!("sitar {}", path.join(" "));
    pages.insert(
        file.clone(),
        format!("{HEADER}# `{cmd}`\n\n`{cmd} --help`:\n\n{}", fence(&text)),
    );
    index.push_str(&format!(
        "{}- [`{cmd}`]({})\n",
        "  ".repeat(depth - 1),
        file.trim_start_matches("reference/")
    ));
    summary.push(format!("{}- [{cmd}]({file})", "    ".repeat(depth)));
    for (sub, _) in subcommands(&text) {
        let mut next = path.to_vec();
        next.push(&sub);
        walk(&next, depth + 1, pages, index, summary);
    }
}

/// The `///` lines right above the line at `at`, joined.
fn doc_above(lines: &[&str], at: usize) -> String {
    let mut docs = Vec::new();
    let mut i = at;
    while i > 0 {
        i -= 1;
        let l = lines[i].trim();
        if let Some(d) = l.strip_prefix("///") {
            docs.push(d.trim().to_owned());
        } else if l.starts_with("#[") {
            continue;
        } else {
            break;
        }
    }
    docs.reverse();
    docs.join(" ").trim().to_owned()
}

/// A doc comment as guide Markdown: rustdoc's intra-doc links (`[`X`](crate::…)`,
/// `[`X`]`) become plain code, and `|` is escaped for a table cell.
fn cell(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(open) = rest.find("[`") {
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        let Some(close) = after.find("`]") else {
            out.push('[');
            rest = after;
            continue;
        };
        let code = &after[..close + 1];
        let tail = &after[close + 2..];
        out.push_str(code);
        rest = match tail.strip_prefix('(') {
            Some(t) if t.find(')').is_some_and(|e| !t[..e].contains('/')) => {
                &t[t.find(')').unwrap() + 1..]
            }
            _ => tail,
        };
    }
    out.push_str(rest);
    out.replace('|', "\\|").replace('\n', " ")
}

/// The text of the balanced `( … )` that starts at `open`.
fn balanced(text: &str, open: usize) -> &str {
    let mut depth = 0;
    for (i, c) in text[open..].char_indices() {
        match c {
            '(' => depth += 1,
            ')' => {
                depth -= 1;
                if depth == 0 {
                    return &text[open + 1..open + i];
                }
            }
            _ => {}
        }
    }
    &text[open + 1..]
}

fn http_page() -> String {
    let router = read("rust/server/src/http/router.rs");
    let limits = read("rust/server/src/http/request_limits.rs");
    let mut rows = Vec::new();
    let mut from = 0;
    while let Some(pos) = router[from..].find(".route(") {
        let open = from + pos + ".route".len();
        let args = balanced(&router, open);
        from = open + args.len();
        let path = args.split('"').nth(1).unwrap_or_default().to_owned();
        let rest = &args[args.find(',').map_or(0, |i| i + 1)..];
        for method in ["get", "post", "put", "delete", "head"] {
            for (i, _) in rest.match_indices(&format!("{method}(")) {
                let ok_start = i == 0 || !rest.as_bytes()[i - 1].is_ascii_alphanumeric();
                if !ok_start {
                    continue;
                }
                let handler = balanced(rest, i + method.len()).trim().to_owned();
                let doc = handler_doc(&handler);
                let verb = method.to_uppercase();
                let limit = body_limit(&limits, &verb, &path);
                rows.push(format!(
                    "| `{verb}` | `{path}` | {} | {} |",
                    cell(&doc),
                    cell(&limit)
                ));
            }
        }
    }
    let mut page = format!(
        "{HEADER}# HTTP API\n\nEvery route of `sitar serve`, in the order of the router's table \
         (`rust/server/src/http/router.rs`), with its handler's documentation and its body \
         limit (`rust/server/src/http/request_limits.rs`). Every route but `/healthz` needs \
         `Authorization: Bearer TOKEN` (or `?token=`): [Security](../backend/security.md); \
         every bound: [Limits](../backend/limits.md).\n\n\
         | method | route | what | body limit |\n|---|---|---|---|\n"
    );
    for row in rows {
        page.push_str(&row);
        page.push('\n');
    }
    page.push_str(
        "\n## Errors\n\nEvery error is a JSON body `{\"error\":{\"code\":…,\"message\":…}}`; \
         the codes (`rust/server/src/error.rs`):\n\n| error | status and code |\n|---|---|\n",
    );
    let error = read("rust/server/src/error.rs");
    let lines: Vec<&str> = error.lines().collect();
    let start = lines
        .iter()
        .position(|l| l.starts_with("pub enum Error"))
        .expect("pub enum Error");
    for (i, l) in lines.iter().enumerate().skip(start + 1) {
        if l.starts_with('}') {
            break;
        }
        let t = l.trim();
        if l.starts_with("    ")
            && !l.starts_with("     ")
            && !t.starts_with("///")
            && !t.starts_with("#[")
        {
            let name: String = t.chars().take_while(|c| c.is_alphanumeric()).collect();
            if !name.is_empty() {
                page.push_str(&format!("| `{name}` | {} |\n", cell(&doc_above(&lines, i))));
            }
        }
    }
    page
}

/// The documentation of `module::function` in the handlers' folder.
fn handler_doc(handler: &str) -> String {
    let Some((module, function)) = handler.rsplit_once("::") else {
        return String::new();
    };
    let module = module.rsplit("::").next().unwrap();
    let file = format!("rust/server/src/http/handlers/{module}.rs");
    let Ok(text) = std::fs::read_to_string(repo().join(&file)) else {
        return String::new();
    };
    let lines: Vec<&str> = text.lines().collect();
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim_start();
        let t = t
            .trim_start_matches("pub(crate) ")
            .trim_start_matches("pub ")
            .trim_start_matches("async ");
        if t.starts_with(&format!("fn {function}(")) || t.starts_with(&format!("fn {function}<")) {
            return doc_above(&lines, i);
        }
    }
    String::new()
}

/// The match arm of `body_limit` for this route, as written there.
fn body_limit(limits: &str, verb: &str, path: &str) -> String {
    if matches!(verb, "GET" | "HEAD" | "DELETE") {
        return String::new();
    }
    let arm = format!("(\"{verb}\", \"{path}\") =>");
    let Some(at) = limits.find(&arm) else {
        return "small (the default arm of `body_limit`)".into();
    };
    let rest = limits[at + arm.len()..].trim_start();
    let expr: String = if let Some(b) = rest.strip_prefix('{') {
        b[..b.find('}').unwrap_or(b.len())].to_owned()
    } else {
        let end = ["\n        (", "\n        _ =>"]
            .iter()
            .filter_map(|m| rest.find(m))
            .min()
            .unwrap_or(rest.len());
        rest[..end].to_owned()
    };
    let expr = expr
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .replace("( ", "(")
        .replace(" .", ".")
        .replace(", )", ")");
    format!("`{}`", expr.trim_end_matches(','))
}

/// The `pub` fields of a struct with their docs: `| key | doc |` rows.
fn struct_fields(file: &str, name: &str) -> String {
    let text = read(file);
    let lines: Vec<&str> = text.lines().collect();
    let start = lines
        .iter()
        .position(|l| l.starts_with(&format!("pub struct {name}")))
        .unwrap_or_else(|| panic!("{file}: no pub struct {name}"));
    let mut out = String::from("| key | type | what |\n|---|---|---|\n");
    for (i, l) in lines.iter().enumerate().skip(start + 1) {
        if l.starts_with('}') {
            break;
        }
        if let Some(field) = l.trim().strip_prefix("pub ")
            && let Some((key, ty)) = field.split_once(':')
        {
            out.push_str(&format!(
                "| `{}` | `{}` | {} |\n",
                key.trim(),
                ty.trim().trim_end_matches(','),
                cell(&doc_above(&lines, i))
            ));
        }
    }
    out
}

fn config_page() -> String {
    format!(
        "{HEADER}# Configuration keys\n\n## The phone's session (`SessionConfig`)\n\n\
         The JSON a phone gives `sitar_session_new` (Kotlin `SitarSession(configJson)`, C# \
         `new SitarSession(json)`); every key optional, an unknown key refused, naming it \
         (`rust/core/src/config.rs`; the defaults explained: \
         [On the phone](../ar/core.md#session-config-keys)).\n\n{}\n\
         ## The backend (`ServerConfig`)\n\n`sitar serve` sets these from its flags \
         ([`sitar serve --help`](cli/serve.md)); an embedding program sets them on \
         `ServerConfig::new(dir)` (`rust/server/src/config.rs`).\n\n{}",
        struct_fields("rust/core/src/config.rs", "SessionConfig"),
        struct_fields("rust/server/src/config.rs", "ServerConfig")
    )
}

/// C comments (`// …`) right above line `at`, joined.
fn c_comment_above(lines: &[&str], at: usize) -> String {
    let mut out = Vec::new();
    let mut i = at;
    while i > 0 {
        i -= 1;
        match lines[i].trim().strip_prefix("//") {
            Some(c) => out.push(c.trim().to_owned()),
            None => break,
        }
    }
    out.reverse();
    out.join(" ").trim().to_owned()
}

/// The C ABI's page (status codes, functions) and its types' page.
fn c_abi_pages() -> (String, String) {
    let header = read("rust/ffi/include/sitar.h");
    let lines: Vec<&str> = header.lines().collect();
    let intro: String = header
        .split("*/")
        .next()
        .unwrap()
        .lines()
        .map(|l| l.trim_start_matches("/*").trim_start_matches(" *").trim())
        .collect::<Vec<_>>()
        .join("\n");
    let mut page = format!(
        "{HEADER}# C ABI\n\n`rust/ffi/include/sitar.h`, the header of `libsitar.so` (generated \
         by cbindgen from `rust/ffi/src/exports.rs`; how to use it: [The native \
         library](../ar/native-library.md)).\n\n{}\n\n## Status codes\n\n| code | value | \
         meaning |\n|---|---|---|\n",
        intro.trim()
    );
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim();
        if t.starts_with("SITAR_") && t.contains(" = ") {
            let (name, value) = t.trim_end_matches(',').split_once(" = ").unwrap();
            page.push_str(&format!(
                "| `{name}` | {value} | {} |\n",
                cell(&c_comment_above(&lines, i))
            ));
        }
    }
    page.push_str("\nThe structs the functions take and fill: [C ABI types](c-abi-types.md).\n\n");
    let mut types = format!(
        "{HEADER}# C ABI types\n\nThe structs of `rust/ffi/include/sitar.h` ([C ABI](c-abi.md)).\n\n"
    );
    let mut i = 0;
    while i < lines.len() {
        if lines[i].starts_with("typedef struct") {
            let doc = c_comment_above(&lines, i);
            let mut fields = Vec::new();
            let mut j = i + 1;
            while !lines[j].starts_with('}') {
                let t = lines[j].trim();
                if !t.starts_with("//") && t.ends_with(';') {
                    fields.push(format!(
                        "`{}` {}",
                        t.trim_end_matches(';'),
                        c_comment_above(&lines, j)
                    ));
                }
                j += 1;
            }
            let name = lines[j]
                .trim_start_matches('}')
                .trim()
                .trim_end_matches(';');
            types.push_str(&format!("### `{name}`\n\n{doc}\n\n"));
            for f in fields {
                types.push_str(&format!("- {f}\n"));
            }
            types.push('\n');
            i = j;
        }
        i += 1;
    }
    page.push_str("## Functions\n\n");
    let mut i = 0;
    while i < lines.len() {
        let l = lines[i];
        if !l.starts_with(' ')
            && !l.starts_with("//")
            && !l.starts_with('#')
            && let Some(p) = l.find("sitar_")
            && l[p..].contains('(')
        {
            let name = &l[p..p + l[p..].find('(').unwrap()];
            let doc = c_comment_above(&lines, i);
            let mut proto = vec![l];
            while !proto.last().unwrap().trim_end().ends_with(';') {
                i += 1;
                proto.push(lines[i]);
            }
            page.push_str(&format!(
                "### `{name}`\n\n{doc}\n\n```c\n{}\n```\n\n",
                proto.join("\n")
            ));
        }
        i += 1;
    }
    (page, types)
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// The CSV tables' headers, from the `pub const …_HEADER: &str` of the crates' sources.
fn csv_page() -> String {
    let mut page = format!(
        "{HEADER}# CSV headers\n\nThe header line of every CSV table the crates write and \
         check (each `pub const …_HEADER` with a comma in it), with its documentation. \
         Other formats: [File formats](formats.md).\n\n"
    );
    let root = repo();
    let mut found = 0;
    for crate_dir in [
        "core",
        "estimator",
        "scene",
        "client",
        "server",
        "evo",
        "cli",
        "sim",
    ] {
        for file in rust_files(&root.join("rust").join(crate_dir).join("src")) {
            let text = std::fs::read_to_string(&file).unwrap();
            let lines: Vec<&str> = text.lines().collect();
            for (i, l) in lines.iter().enumerate() {
                let Some(rest) = l.strip_prefix("pub const ") else {
                    continue;
                };
                let Some((name, value)) = rest.split_once(": &str = \"") else {
                    continue;
                };
                let value = value.trim_end_matches("\";");
                if !name.ends_with("_HEADER") || !value.contains(',') {
                    continue;
                }
                found += 1;
                let rel = file.strip_prefix(&root).unwrap().display().to_string();
                page.push_str(&format!(
                    "## `{name}`\n\n`{rel}`: {}\n\n```text\n{value}\n```\n\n| # | column |\n|---|---|\n",
                    cell(&doc_above(&lines, i))
                ));
                for (k, column) in value.split(',').enumerate() {
                    page.push_str(&format!("| {k} | `{column}` |\n"));
                }
                page.push('\n');
            }
        }
    }
    assert!(found >= 2, "found {found} CSV headers");
    page
}

/// The JSON files' keys, from the structs that read and write them.
fn json_page() -> String {
    let core = "rust/core/src/calibration";
    format!(
        "{HEADER}# JSON files\n\nThe keys of the JSON documents the crates read and write, \
         from the structs that (de)serialize them. Other formats: [File formats](formats.md), \
         [CSV headers](csv.md).\n\n\
         ## The calibration file (`sitar calibrate -o FILE`, version 2)\n\n\
         Read by `sitar estimate|evaluate --calibration`, `sitar serve --calibration NAME=FILE` \
         and the phone (`sitar_session_set_calibration`); version 1 is read as its one model. \
         Unknown keys are refused, naming them.\n\n### `Calibration`\n\n{}\n\
         ### `fitted_on`\n\n{}\n### `fitted_on.sequences[]`\n\n{}\n\
         ### `models[]`\n\n{}\n### `models[].interval`\n\n{}\n\
         ### `models[].scores`\n\n{}\n### `models[].scores.sequences[]`\n\n{}\n\
         ### `models[].scores.candidates[]`\n\n{}\n### Scores (`raw`, `calibrated`, …)\n\n{}\n\
         ## Results as the phone reads them (`results.json`)\n\n\
         The keys `Results::parse_json` takes (`rust/core/src/results.rs`); windows carry \
         `start`, `end`, the error under the key of its unit (`error_m` or `error_deg`), `pairs`, \
         and in calibrated results `raw_…`, `lower_…`, `upper_…`.\n\n{}\n\
         ## An estimate (`sitar estimate --format json`, the backend's `results.json`)\n\n{}\n",
        struct_fields(&format!("{core}/file.rs"), "Calibration"),
        struct_fields(&format!("{core}/file.rs"), "FittedOn"),
        struct_fields(&format!("{core}/file.rs"), "FittedSequence"),
        struct_fields(&format!("{core}/model.rs"), "CalibrationModel"),
        struct_fields(&format!("{core}/model.rs"), "IntervalModel"),
        struct_fields(&format!("{core}/scores.rs"), "ModelScores"),
        struct_fields(&format!("{core}/scores.rs"), "HeldOutScores"),
        struct_fields(&format!("{core}/scores.rs"), "CandidateScores"),
        struct_fields(&format!("{core}/scores.rs"), "AgreementScores"),
        struct_fields("rust/core/src/results.rs", "Results"),
        estimate_json_doc(),
    )
}

/// The documentation of `Estimate::to_json`, which names every key it writes.
fn estimate_json_doc() -> String {
    let text = read("rust/estimator/src/estimate.rs");
    let lines: Vec<&str> = text.lines().collect();
    let at = lines
        .iter()
        .position(|l| l.trim_start().starts_with("pub fn to_json("))
        .expect("rust/estimator/src/estimate.rs: no to_json");
    doc_above(&lines, at)
}

fn generate() -> (BTreeMap<String, String>, Vec<String>) {
    let mut pages = BTreeMap::new();
    let summary = cli_pages(&mut pages);
    pages.insert("reference/http.md".into(), http_page());
    pages.insert("reference/config.md".into(), config_page());
    pages.insert("reference/csv.md".into(), csv_page());
    pages.insert("reference/json.md".into(), json_page());
    let (abi, types) = c_abi_pages();
    pages.insert("reference/c-abi.md".into(), abi);
    pages.insert("reference/c-abi-types.md".into(), types);
    (pages, summary)
}

/// SUMMARY.md with the commands' entries under `[Commands](reference/cli.md)` replaced.
fn with_summary(summary_md: &str, entries: &[String]) -> String {
    let mut out = Vec::new();
    let mut skipping = false;
    for line in summary_md.lines() {
        if skipping && line.starts_with("    ") {
            continue;
        }
        skipping = false;
        out.push(line.to_owned());
        if line
            .trim_start()
            .starts_with("- [Commands](reference/cli.md)")
        {
            out.extend(entries.iter().cloned());
            skipping = true;
        }
    }
    out.join("\n") + "\n"
}

#[test]
fn the_reference_pages_are_what_the_code_gives() {
    let (pages, summary) = generate();
    let src = repo().join("docs/src");
    let regenerate = std::env::var_os("SITAR_REGENERATE").is_some();
    let mut differ = Vec::new();
    let summary_path = src.join("SUMMARY.md");
    let old_summary = std::fs::read_to_string(&summary_path).unwrap();
    let new_summary = with_summary(&old_summary, &summary);
    let mut all = pages.clone();
    all.insert("SUMMARY.md".into(), new_summary);
    for (rel, text) in &all {
        let path = src.join(rel);
        if std::fs::read_to_string(&path).ok().as_deref() != Some(text.as_str()) {
            if regenerate {
                std::fs::create_dir_all(path.parent().unwrap()).unwrap();
                std::fs::write(&path, text).unwrap();
            }
            differ.push(rel.clone());
        }
    }
    // A generated page the code no longer makes (a removed command).
    for entry in std::fs::read_dir(src.join("reference/cli"))
        .into_iter()
        .flatten()
    {
        let rel = format!(
            "reference/cli/{}",
            entry.unwrap().file_name().to_string_lossy()
        );
        if !pages.contains_key(&rel) {
            if regenerate {
                std::fs::remove_file(src.join(&rel)).unwrap();
            }
            differ.push(format!("{rel} (no such command)"));
        }
    }
    assert!(
        regenerate || differ.is_empty(),
        "docs/src differs from the code in {differ:?}; rewrite with SITAR_REGENERATE=1 cargo \
         test -p sitar-cli --test docs_reference"
    );
}

#[test]
fn the_generators_see_what_they_document() {
    let (pages, summary) = generate();
    // Every group and command of `sitar --help` has its page; nested ones too.
    for cmd in ["serve", "ape", "ape-tum", "token-create", "bench", "demo"] {
        assert!(
            pages.contains_key(&format!("reference/cli/{cmd}.md")),
            "no page for {cmd}"
        );
    }
    assert!(
        summary
            .iter()
            .any(|l| l.contains("reference/cli/rpe-euroc.md"))
    );
    let serve = &pages["reference/cli/serve.md"];
    assert!(
        serve.contains("--max-connections"),
        "serve's flags are missing"
    );
    // Routes with their handler docs and limits; errors with their codes.
    let http = &pages["reference/http.md"];
    assert!(http.contains("| `PUT` | `/v1/sessions/{id}/recording` |"));
    assert!(http.contains("max_recording_bytes"));
    assert!(http.contains("| `POST` | `/v1/sessions` |"));
    assert!(http.contains("`not_found`"));
    let undocumented: Vec<&str> = http
        .lines()
        .filter(|l| l.starts_with("| `") && l.contains("` |  |"))
        .collect();
    assert!(
        undocumented.len() <= 3,
        "routes whose handler has no doc: {undocumented:#?}"
    );
    let abi = &pages["reference/c-abi.md"];
    assert!(abi.contains("### `sitar_session_frame`") && abi.contains("SITAR_ERR_PANIC"));
    let csv = &pages["reference/csv.md"];
    assert!(csv.contains("## `EVIDENCE_HEADER`") && csv.contains("| 0 | `t_ns` |"));
    let config = &pages["reference/config.md"];
    assert!(config.contains("| `subtrajectory_frames` |") && config.contains("| `classify_by` |"));
}
