//! The checks of `scripts/check-android` (`tools/android-link/check-elf`), here where
//! every CI run and every `cargo test` sees them:
//! - the host `libsitar.so` (what the Unity Editor's Play Mode and the JVM tests load)
//!   exports exactly `rust/ffi/include/sitar.h`'s functions plus the JNI natives the
//!   Kotlin sources and the Unity package's Java classes declare, and needs only glibc's
//!   libraries: a function renamed in Rust fails here, not in the Editor;
//! - the Android checks fail on planted defects (a 4 KB link, an export missing from the
//!   header, an import outside API 24, …): `scripts/check-android --self-test` links
//!   small C libraries for arm64-v8a and x86_64 with clang and lld and needs each to fail.
//!
//! Skipped, loudly, without python3, or (the self-test) clang and lld.

mod bindings_support;

use std::process::Command;

use bindings_support::{host_library, skip, which, workspace_root};

#[test]
fn host_library_exports_what_the_header_and_the_jvm_sources_declare() {
    const TEST: &str = "host_library_exports_what_the_header_and_the_jvm_sources_declare";
    if which("python3").is_none() {
        return skip(TEST, "`python3` is not on PATH (Debian package `python3`)");
    }
    let lib = host_library();
    let output = Command::new("python3")
        .current_dir(workspace_root())
        .arg("tools/android-link/check-elf")
        .arg(lib)
        .args(["--host", "--testing"])
        .output()
        .expect("python3 runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "check-elf on {}:\n{stdout}{stderr}",
        lib.display()
    );
    assert!(
        stdout.contains(": ok:") && stdout.contains(" exports as declared"),
        "{stdout}"
    );
}

#[test]
fn android_checks_fail_on_planted_defects() {
    const TEST: &str = "android_checks_fail_on_planted_defects";
    if which("python3").is_none() {
        return skip(TEST, "`python3` is not on PATH (Debian package `python3`)");
    }
    let output = Command::new(workspace_root().join("scripts/check-android"))
        .arg("--self-test")
        .output()
        .expect("scripts/check-android runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    if let Some(line) = stdout.lines().find(|l| l.contains("SKIPPED")) {
        return skip(TEST, line);
    }
    assert!(output.status.success(), "{stdout}{stderr}");
    for abi in ["arm64-v8a", "x86_64"] {
        for defect in [
            "fails on a 4 KB link",
            "fails on an export missing from the header",
            "fails on an import outside API 24",
        ] {
            assert!(
                stdout.contains(&format!("self-test: {abi}: {defect}")),
                "{abi}: no line saying it {defect}:\n{stdout}"
            );
        }
        assert!(
            stdout.contains(&format!("self-test: {abi}: passes without defects")),
            "{stdout}"
        );
    }
}
