//! Shared by the tests of the apps' sources (Kotlin apps, Unity package):
//! finding source files, and checking the JSON escaping cases the host tests
//! print as `JSON <hex of the input> <document>` with serde_json.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// Every file under `dir` whose name ends with `suffix`, recursively, sorted.
pub fn files_with_suffix(dir: &Path, suffix: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut dirs = vec![dir.to_path_buf()];
    while let Some(d) = dirs.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.to_string_lossy().ends_with(suffix) {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// Whether a Kotlin source needs Android or ARCore (so it only type-checks against stubs).
pub fn uses_android(source: &Path) -> bool {
    let text = std::fs::read_to_string(source).unwrap();
    text.lines().any(|l| {
        let l = l.trim_start();
        l.starts_with("import android.")
            || l.starts_with("import com.google.ar.")
            || l.starts_with("import javax.microedition.")
    })
}

/// Parses every `JSON <hex> <document>` line of `stdout` with serde_json: the document is
/// `{"convention": convention, "server_url": <the hex-decoded input>}` and nothing else.
/// Returns how many there were.
pub fn check_json_cases(stdout: &str, convention: &str) -> usize {
    let mut cases = 0;
    for line in stdout.lines().filter_map(|l| l.strip_prefix("JSON ")) {
        let (hex, doc) = line.split_once(' ').expect("JSON <hex> <document>");
        let bytes: Vec<u8> = (0..hex.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap())
            .collect();
        let expected = String::from_utf8(bytes).unwrap();
        let parsed: serde_json::Value =
            serde_json::from_str(doc).unwrap_or_else(|e| panic!("{e}: {doc}"));
        assert_eq!(parsed["server_url"], expected.as_str(), "{doc}");
        assert_eq!(parsed["convention"], convention, "{doc}");
        assert_eq!(parsed.as_object().unwrap().len(), 2, "{doc}");
        cases += 1;
    }
    cases
}
