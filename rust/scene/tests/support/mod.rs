//! What the GLB tests share: a GLB's JSON document and the Khronos glTF validator
//! (npm `gltf-validator`, pinned in `tools/npm`, run by `tools/npm/validate-gltf.mjs`).

use std::path::{Path, PathBuf};
use std::process::Command;

/// The JSON chunk of a GLB.
pub fn document(glb: &[u8]) -> serde_json::Value {
    let glb = gltf::binary::Glb::from_slice(glb).unwrap();
    serde_json::from_slice(&glb.json).unwrap()
}

/// Writes each `(name, glb)` into a temporary folder and asserts the validator reports no
/// error, no warning and some vertices for every one. Without the validator installed it
/// prints why it skipped and returns false.
pub fn assert_khronos_clean(glbs: &[(&str, Vec<u8>)]) -> bool {
    let tools = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tools/npm");
    if !tools.join("node_modules/gltf-validator").exists() {
        println!(
            "SKIPPED the Khronos glTF validator: run `npm ci --prefix tools/npm` (.ci/run does)"
        );
        return false;
    }
    let dir = tempfile::tempdir().unwrap();
    let files: Vec<PathBuf> = glbs
        .iter()
        .map(|(name, glb)| {
            let path = dir.path().join(format!("{name}.glb"));
            std::fs::write(&path, glb).unwrap();
            path
        })
        .collect();
    let out = Command::new("node")
        .arg(tools.join("validate-gltf.mjs"))
        .args(&files)
        .output()
        .expect("node runs");
    let text = String::from_utf8_lossy(&out.stdout);
    let reports: serde_json::Value = serde_json::from_str(&text).unwrap_or_else(|e| {
        panic!(
            "validator output ({e}): {text} {}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    let reports = reports.as_array().unwrap();
    assert_eq!(reports.len(), files.len(), "one report per file");
    for (report, path) in reports.iter().zip(&files) {
        let issues = &report["issues"];
        let pretty = serde_json::to_string_pretty(issues).unwrap();
        let name = Path::new(path).file_name().unwrap().to_string_lossy();
        assert_eq!(issues["numErrors"], 0, "{name}: {pretty}");
        assert_eq!(issues["numWarnings"], 0, "{name}: {pretty}");
        assert!(
            report["info"]["totalVertexCount"].as_u64().unwrap() > 0,
            "{name}"
        );
    }
    assert!(out.status.success());
    true
}
