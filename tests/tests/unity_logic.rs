//! The Unity package's UnityEngine-free logic on Mono: `SitarPlaybackRun.cs`
//! (the playback phone: launches, pause/resume, a second launch, failures,
//! the trajectory and status files) with the real `PlaybackLogger` of
//! `SitarSession.cs` over the host-built `libsitar.so`, and `SitarJson.cs`,
//! whose documents are parsed here with serde_json. Compiled with `mcs`
//! (warnings as errors) with `unity-plugin/Tests~/LogicTest.cs`. Skipped,
//! loudly, where `mcs` or `mono` is missing.

mod bindings_support;

use std::process::Command;

use bindings_support::{library_dir, run, skip, which, workspace_root};

#[test]
fn unity_playback_logic_and_json_run_on_mono_with_the_real_library() {
    const NAME: &str = "unity_playback_logic_and_json_run_on_mono_with_the_real_library";
    let Some(mcs) = which("mcs") else {
        return skip(NAME, "`mcs` is not on PATH (Debian package `mono-mcs`)");
    };
    let Some(mono) = which("mono") else {
        return skip(
            NAME,
            "`mono` is not on PATH (Debian package `mono-runtime`)",
        );
    };
    let plugin = workspace_root().join("unity-plugin");
    let dir = tempfile::tempdir().unwrap();
    let exe = dir.path().join("LogicTest.exe");
    run(
        Command::new(mcs)
            .args(["-unsafe", "-warnaserror", "-r:System.Core"])
            .arg(format!("-out:{}", exe.display()))
            .arg(plugin.join("Runtime/NativeMethods.g.cs"))
            .arg(plugin.join("Runtime/SitarSession.cs"))
            .arg(plugin.join("Runtime/SitarJson.cs"))
            .arg(plugin.join("Runtime/SitarPlaybackRun.cs"))
            .arg(plugin.join("Tests~/LogicTest.cs")),
        "mcs (SitarPlaybackRun, SitarJson, LogicTest)",
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
        assert_eq!(parsed["convention"], "unity");
        assert_eq!(parsed.as_object().unwrap().len(), 2, "{doc}");
        cases += 1;
    }
    assert!(cases >= 7, "{stdout}");
    println!(
        "{} ({cases} JSON escaping cases parsed by serde_json)",
        stdout.lines().last().unwrap_or_default()
    );
}
