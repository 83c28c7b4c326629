//! Shared by the binding tests: builds the host `libsitar.so` with the
//! `testing` feature once per test binary, finds tools, reports skips loudly.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

#[path = "../../../rust/ffi/tests/support/walk_calibration.rs"]
pub mod walk_calibration;

/// Writes the calibrations the Kotlin and C# host tests read into `dir`: the one-run
/// calibration of `walk_calibration` (`calibration-walk.json`), the same saying its runs do
/// not predict the error (`calibration-guess.json`), one for 20-frame windows
/// (`calibration-window20.json`) and one without a model for one run
/// (`calibration-expected-only.json`).
pub fn write_walk_calibrations(dir: &Path) {
    use walk_calibration::{expected_only_calibration, walk_calibration};
    for (name, calibration) in [
        ("calibration-walk.json", walk_calibration(10, true)),
        ("calibration-guess.json", walk_calibration(10, false)),
        ("calibration-window20.json", walk_calibration(20, true)),
        (
            "calibration-expected-only.json",
            expected_only_calibration(),
        ),
    ] {
        std::fs::write(dir.join(name), calibration.to_json()).unwrap();
    }
}

/// The workspace root.
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// Builds `sitar-ffi` (cdylib, `--features testing`) and returns the path of
/// the host `libsitar.so`. The build uses its own target directory so it
/// never waits on, or changes, the library the outer `cargo` builds.
pub fn host_library() -> &'static Path {
    static LIB: OnceLock<PathBuf> = OnceLock::new();
    LIB.get_or_init(|| {
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned());
        let target_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("bindings-target");
        let output = Command::new(cargo)
            .current_dir(workspace_root())
            .env("CARGO_TARGET_DIR", &target_dir)
            .args([
                "build",
                "-p",
                "sitar-ffi",
                "--lib",
                "--features",
                "testing",
                "--message-format=json",
            ])
            .output()
            .expect("cargo runs");
        assert!(
            output.status.success(),
            "building sitar-ffi failed:\n{}",
            String::from_utf8_lossy(&output.stderr)
        );
        let stdout = String::from_utf8(output.stdout).unwrap();
        let mut found = None;
        for line in stdout.lines() {
            let Ok(msg) = serde_json::from_str::<serde_json::Value>(line) else {
                continue;
            };
            if msg["reason"] != "compiler-artifact" || msg["target"]["name"] != "sitar" {
                continue;
            }
            for f in msg["filenames"].as_array().into_iter().flatten() {
                let f = f.as_str().unwrap_or_default();
                if f.ends_with(std::env::consts::DLL_SUFFIX) {
                    found = Some(PathBuf::from(f));
                }
            }
        }
        found.expect("cargo reported the sitar cdylib")
    })
}

/// A directory holding only `libsitar.so` (for `java.library.path` / mono).
pub fn library_dir() -> &'static Path {
    host_library().parent().unwrap()
}

/// The path of `tool` on `PATH`, if any.
pub fn which(tool: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|dir| dir.join(tool))
        .find(|p| p.is_file())
}

/// The Mono compiler `mcs`, or `None` with `test` reported as skipped.
pub fn mcs_or_skip(test: &str) -> Option<PathBuf> {
    let found = which("mcs");
    if found.is_none() {
        skip(test, "`mcs` is not on PATH (Debian package `mono-mcs`)");
    }
    found
}

/// `mcs` and the Mono runtime `mono`, or `None` with `test` reported as skipped.
pub fn mono_or_skip(test: &str) -> Option<(PathBuf, PathBuf)> {
    let mcs = mcs_or_skip(test)?;
    let Some(mono) = which("mono") else {
        skip(
            test,
            "`mono` is not on PATH (Debian package `mono-runtime`)",
        );
        return None;
    };
    Some((mcs, mono))
}

/// Reports a skipped test so it cannot pass silently: written straight to
/// the stderr handle, which the test harness does not capture.
pub fn skip(test: &str, reason: &str) {
    use std::io::Write as _;
    let _ = writeln!(std::io::stderr(), "SKIPPED {test}: {reason}");
}

/// Runs a command; panics with its output on failure; returns stdout.
pub fn run(cmd: &mut Command, what: &str) -> String {
    let output = cmd
        .output()
        .unwrap_or_else(|e| panic!("{what}: cannot run: {e}"));
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(
        output.status.success(),
        "{what} failed ({}):\n--- stdout\n{stdout}\n--- stderr\n{stderr}",
        output.status
    );
    stdout
}

/// A results CSV (`start,error`) giving sub-trajectory k (frames 10k…10k+10 at
/// `frame_ns` spacing) the error `errors[k]`.
pub fn results_csv(frame_ns: i64, errors: &[f64]) -> String {
    let mut csv = String::from("start,error\n");
    for (k, e) in errors.iter().enumerate() {
        csv.push_str(&format!("{},{e}\n", 10 * k as i64 * frame_ns));
    }
    csv
}
