//! Compiles the Kotlin library sources (`android/src/main/kotlin`, those that need
//! no Android: `Sitar.kt` takes a `Context` and is type-checked by `kotlin_apps`) and the
//! host test main (`android/src/hostTest/kotlin`) with `kotlinc`, then runs
//! it on the JVM against the host-built `libsitar.so`: a whole session and
//! every error path as the right `SitarException`. Skipped, loudly, where
//! `kotlinc` or `java` is missing.

mod bindings_support;
mod host_support;

use std::process::Command;

use bindings_support::{library_dir, run, skip, which, workspace_root, write_walk_calibrations};
use host_support::{files_with_suffix, uses_android};

#[test]
fn kotlin_wrapper_runs_a_session_and_maps_every_error() {
    const NAME: &str = "kotlin_wrapper_runs_a_session_and_maps_every_error";
    let Some(kotlinc) = which("kotlinc") else {
        return skip(NAME, "`kotlinc` is not on PATH (Debian package `kotlin`)");
    };
    let Some(java) = which("java") else {
        return skip(NAME, "`java` is not on PATH");
    };
    let android = workspace_root().join("android");
    let dir = tempfile::tempdir().unwrap();
    let jar = dir.path().join("host-test.jar");
    let library: Vec<_> = files_with_suffix(&android.join("src/main/kotlin"), ".kt")
        .into_iter()
        .filter(|f| !uses_android(f))
        .collect();
    assert!(
        library.iter().any(|f| f.ends_with("Native.kt")),
        "{library:?}"
    );
    run(
        Command::new(kotlinc)
            .args(&library)
            .arg(android.join("src/hostTest/kotlin"))
            .arg("-include-runtime")
            .arg("-d")
            .arg(&jar),
        "kotlinc",
    );
    let work = dir.path().join("work");
    std::fs::create_dir(&work).unwrap();
    write_walk_calibrations(&work);
    let stdout = run(
        Command::new(java)
            .arg(format!("-Djava.library.path={}", library_dir().display()))
            .arg("-cp")
            .arg(&jar)
            .arg("io.github.sitar.HostTestKt")
            .arg(env!("CARGO_PKG_VERSION"))
            .arg(&work),
        "Kotlin host test",
    );
    assert!(stdout.contains("PASSED"), "{stdout}");
    println!("{}", stdout.trim());
}
