//! The Unity package's Java classes for Android players
//! (`unity-plugin/Plugins/Android/Native.java`, which `SitarPlatformTls.cs` calls through
//! `AndroidJavaClass`) is compiled with `javac` and run on the host JVM against the
//! host-built `libsitar.so`: its `native` method must bind to the library's
//! `Java_io_github_sitar_Native_platformTlsInit` (the same name and signature as the
//! generated `Native.kt`), which on the host is a no-op answering true, and a null context
//! is the package's `SitarException.java` (the library constructs it by name) with the NULL
//! status. Skipped, loudly, where `javac` or `java`
//! is missing.

mod bindings_support;

use std::process::Command;

use bindings_support::{library_dir, run, skip, which, workspace_root};

const MAIN: &str = r#"
package io.github.sitar;

public final class BridgeMain {
    public static void main(String[] args) {
        if (!Native.platformTlsInit(new Object())) throw new AssertionError("host init answered false");
        try {
            Native.platformTlsInit(null);
            throw new AssertionError("a null context was accepted");
        } catch (SitarException e) {
            if (e.getCode() != -1 || !e.getMessage().contains("context"))
                throw new AssertionError("null context: " + e.getCode() + " " + e.getMessage());
        }
        System.out.println("BRIDGE OK");
    }
}
"#;

#[test]
fn the_unity_java_class_binds_to_the_library_init() {
    const NAME: &str = "the_unity_java_class_binds_to_the_library_init";
    let Some(javac) = which("javac") else {
        return skip(
            NAME,
            "`javac` is not on PATH (Debian package `default-jdk-headless`)",
        );
    };
    let Some(java) = which("java") else {
        return skip(NAME, "`java` is not on PATH");
    };
    let dir = tempfile::tempdir().unwrap();
    let main = dir.path().join("BridgeMain.java");
    std::fs::write(&main, MAIN).unwrap();
    let plugins = workspace_root().join("unity-plugin/Plugins/Android");
    let classes = dir.path().join("classes");
    run(
        Command::new(javac)
            .arg("-d")
            .arg(&classes)
            .arg(plugins.join("Native.java"))
            .arg(plugins.join("SitarException.java"))
            .arg(&main),
        "javac (Plugins/Android/Native.java, SitarException.java)",
    );
    let stdout = run(
        Command::new(java)
            .arg(format!("-Djava.library.path={}", library_dir().display()))
            .arg("-cp")
            .arg(&classes)
            .arg("io.github.sitar.BridgeMain"),
        "Unity's Java bridge on the host JVM",
    );
    assert!(stdout.contains("BRIDGE OK"), "{stdout}");
}
