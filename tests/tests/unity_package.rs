//! Type-checks the Unity package: every `.cs` under `unity-plugin/Runtime`
//! (the MonoBehaviours, `SitarSession.cs`, the generated bindings) is compiled
//! with `mcs` against stubs of the UnityEngine, uGUI, AR Foundation 5.1 and
//! ARCore XR Plugin 5.1 API shapes (`bindings_support/unity_stubs/`), once per
//! build configuration the `#if`s tell apart, with warnings as errors (Unity
//! shows them in its console). This catches wrong member names, types and
//! signatures and wrong calls into `SitarSession.cs`; it runs nothing in
//! Unity. Skipped, loudly, where `mcs` is missing.

mod bindings_support;

use std::path::{Path, PathBuf};
use std::process::Command;

use bindings_support::{mcs_or_skip, run, workspace_root};

/// The build configurations: what they stand for, and the defines.
const CONFIGURATIONS: &[(&str, &str)] = &[
    ("Editor or player, not Android", ""),
    ("Android player", "UNITY_ANDROID"),
    ("Editor, Android target", "UNITY_ANDROID;UNITY_EDITOR"),
];

/// Every `.cs` file under `dir`, recursively, sorted.
fn cs_files(dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut dirs = vec![dir.to_path_buf()];
    while let Some(d) = dirs.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "cs") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

#[test]
fn unity_package_type_checks_against_the_unity_api_shapes() {
    const NAME: &str = "unity_package_type_checks_against_the_unity_api_shapes";
    let Some(mcs) = mcs_or_skip(NAME) else {
        return;
    };
    let stub_sources =
        cs_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bindings_support/unity_stubs"));
    let runtime = cs_files(&workspace_root().join("unity-plugin/Runtime"));
    for expected in [
        "Runtime/NativeMethods.g.cs",
        "Runtime/SitarStatus.g.cs",
        "Runtime/SitarSession.cs",
        "Runtime/Components/SitarRecorder.cs",
        "Runtime/Components/SitarPlaybackLogger.cs",
    ] {
        assert!(
            runtime.iter().any(|f| f.ends_with(expected)),
            "{expected} not found among {runtime:?}"
        );
    }

    let dir = tempfile::tempdir().unwrap();
    let stubs = dir.path().join("UnityApiStubs.dll");
    run(
        Command::new(&mcs)
            .args(["-target:library", "-unsafe", "-warnaserror"])
            .arg(format!("-out:{}", stubs.display()))
            .args(&stub_sources),
        "mcs (Unity API stubs)",
    );
    for (what, defines) in CONFIGURATIONS {
        let mut cmd = Command::new(&mcs);
        cmd.args(["-target:library", "-unsafe", "-warnaserror"])
            .arg(format!("-r:{}", stubs.display()))
            .arg(format!(
                "-out:{}",
                dir.path().join("Sitar.Runtime.dll").display()
            ));
        if !defines.is_empty() {
            cmd.arg(format!("-define:{defines}"));
        }
        cmd.args(&runtime);
        run(&mut cmd, &format!("mcs (unity-plugin/Runtime; {what})"));
        println!(
            "type-checked {} files of unity-plugin/Runtime: {what} (defines: {})",
            runtime.len(),
            if defines.is_empty() { "none" } else { defines }
        );
    }
}
