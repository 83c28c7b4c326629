//! The Unity package's UnityEngine-free logic on Mono: `SitarPlaybackRun.cs`
//! (the playback phone: launches, pause/resume, a second launch, failures,
//! the trajectory and status files) with the real `PlaybackLogger` of
//! `SitarSession.cs` over the host-built `libsitar.so`, `SitarVenueView.cs` (edge arrows from
//! the real library's guide, the kineticon, the venue layer's colours), and `SitarJson.cs`,
//! whose documents are parsed here with serde_json. Compiled with `mcs`
//! (warnings as errors) with `unity-plugin/Tests~/LogicTest.cs`. Skipped,
//! loudly, where `mcs` or `mono` is missing.

mod bindings_support;
mod host_support;

use std::process::Command;

use bindings_support::{library_dir, mono_or_skip, run, workspace_root};

#[test]
fn unity_playback_logic_and_json_run_on_mono_with_the_real_library() {
    const NAME: &str = "unity_playback_logic_and_json_run_on_mono_with_the_real_library";
    let Some((mcs, mono)) = mono_or_skip(NAME) else {
        return;
    };
    let plugin = workspace_root().join("unity-plugin");
    let dir = tempfile::tempdir().unwrap();
    let exe = dir.path().join("LogicTest.exe");
    run(
        Command::new(mcs)
            .args(["-unsafe", "-warnaserror", "-r:System.Core"])
            .arg(format!("-out:{}", exe.display()))
            .arg(plugin.join("Runtime/NativeMethods.g.cs"))
            .arg(plugin.join("Runtime/SitarStatus.g.cs"))
            .arg(plugin.join("Runtime/SitarSession.cs"))
            .arg(plugin.join("Runtime/SitarJson.cs"))
            .arg(plugin.join("Runtime/SitarPlaybackRun.cs"))
            .arg(plugin.join("Runtime/SitarVenueView.cs"))
            .arg(plugin.join("Tests~/LogicTest.cs")),
        "mcs (SitarPlaybackRun, SitarJson, SitarVenueView, LogicTest)",
    );
    let work = dir.path().join("work");
    std::fs::create_dir(&work).unwrap();
    let stdout = run(
        Command::new(mono)
            .env("LD_LIBRARY_PATH", library_dir())
            .arg(&exe)
            .arg(&work),
        "C# logic test",
    );
    assert!(stdout.contains("PASSED"), "{stdout}");
    let cases = host_support::check_json_cases(&stdout, "unity");
    assert!(cases >= 7, "{stdout}");
    println!(
        "{} ({cases} JSON escaping cases parsed by serde_json)",
        stdout.lines().last().unwrap_or_default()
    );
}
