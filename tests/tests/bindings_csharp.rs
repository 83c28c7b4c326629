//! Compiles `SitarSession.cs` and the generated `NativeMethods.g.cs` and
//! `SitarStatus.g.cs` with `mcs`, plus the host test main (`unity-plugin/Tests~/HostTest.cs`), and
//! runs it with `mono` against the host-built `libsitar.so`: the same session
//! and error cases as the Kotlin test. Skipped, loudly, where `mcs` or `mono`
//! is missing.

mod bindings_support;

use std::process::Command;

use bindings_support::{library_dir, mono_or_skip, run, workspace_root, write_walk_calibrations};

#[test]
fn csharp_wrapper_runs_a_session_and_maps_every_error() {
    const NAME: &str = "csharp_wrapper_runs_a_session_and_maps_every_error";
    let Some((mcs, mono)) = mono_or_skip(NAME) else {
        return;
    };
    let plugin = workspace_root().join("unity-plugin");
    let dir = tempfile::tempdir().unwrap();
    let exe = dir.path().join("HostTest.exe");
    run(
        Command::new(mcs)
            .arg("-unsafe")
            .arg("-warnaserror")
            .arg(format!("-out:{}", exe.display()))
            .arg(plugin.join("Runtime/NativeMethods.g.cs"))
            .arg(plugin.join("Runtime/SitarStatus.g.cs"))
            .arg(plugin.join("Runtime/SitarSession.cs"))
            .arg(plugin.join("Tests~/HostTest.cs")),
        "mcs",
    );
    let work = dir.path().join("work");
    std::fs::create_dir(&work).unwrap();
    write_walk_calibrations(&work);
    let stdout = run(
        Command::new(mono)
            .env("LD_LIBRARY_PATH", library_dir())
            .arg(&exe)
            .arg(env!("CARGO_PKG_VERSION"))
            .arg(&work),
        "C# host test",
    );
    assert!(stdout.contains("PASSED"), "{stdout}");
    println!("{}", stdout.trim());
}
