//! The Kotlin apps on the host: the library (`android/src/main/kotlin`), the
//! playback app (`android/playback`) and the recorder sample
//! (`android/samples/recorder`).
//!
//! 1. Type-check: every source, the Activities included, is compiled with
//!    `kotlinc -Werror` against Java stubs of the Android and ARCore API shapes
//!    (`android/hostStubs/java`, real signatures, only what is used).
//! 2. Host tests on the JVM: the apps' pure-Kotlin logic (every source that
//!    imports nothing from Android or ARCore) with `src/hostTest` mains, against
//!    the host-built `libsitar.so`: pause and resume, a second launch, atomic
//!    trajectory and status files, the recorder's start/stop/pause; the JSON the
//!    recorder builds is parsed here with serde_json.
//!
//! Skipped, loudly, where `kotlinc` or `java` is missing.

mod bindings_support;
mod host_support;

use std::path::Path;
use std::process::Command;

use bindings_support::{library_dir, run, skip, which, workspace_root};
use host_support::{check_json_cases, files_with_suffix as files, uses_android};

const APPS: [&str; 2] = ["playback", "samples/recorder"];

#[test]
fn kotlin_apps_type_check_against_the_android_and_arcore_api_shapes() {
    const NAME: &str = "kotlin_apps_type_check_against_the_android_and_arcore_api_shapes";
    let Some(kotlinc) = which("kotlinc") else {
        return skip(NAME, "`kotlinc` is not on PATH (Debian package `kotlin`)");
    };
    let android = workspace_root().join("android");
    let stubs = files(&android.join("hostStubs/java"), ".java");
    assert!(stubs.len() > 40, "stubs: {stubs:?}");
    let mut sources = files(&android.join("src/main/kotlin"), ".kt");
    for app in APPS {
        sources.extend(files(&android.join(app).join("src/main/kotlin"), ".kt"));
    }
    for expected in [
        "playback/PlaybackActivity.kt",
        "playback/PlaybackRun.kt",
        "recorder/RecorderActivity.kt",
        "recorder/RecorderFlow.kt",
        "sitar/SitarSession.kt",
    ] {
        assert!(
            sources.iter().any(|f| f.ends_with(expected)),
            "{expected} not among {sources:?}"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    run(
        Command::new(kotlinc)
            .arg("-Werror")
            .args(&sources)
            .args(&stubs)
            .arg("-d")
            .arg(dir.path().join("classes")),
        "kotlinc (library, playback app, recorder sample against the Android/ARCore stubs)",
    );
    println!(
        "type-checked {} Kotlin files against {} Android/ARCore stubs",
        sources.len(),
        stubs.len()
    );
}

#[test]
fn kotlin_app_logic_runs_on_the_jvm_with_the_real_library() {
    const NAME: &str = "kotlin_app_logic_runs_on_the_jvm_with_the_real_library";
    let Some(kotlinc) = which("kotlinc") else {
        return skip(NAME, "`kotlinc` is not on PATH (Debian package `kotlin`)");
    };
    let Some(java) = which("java") else {
        return skip(NAME, "`java` is not on PATH");
    };
    let android = workspace_root().join("android");
    // The library's sources that need no Android (`Sitar.kt` takes a `Context`).
    let mut sources: Vec<_> = files(&android.join("src/main/kotlin"), ".kt")
        .into_iter()
        .filter(|f| !uses_android(f))
        .collect();
    let mut pure = Vec::new();
    for app in APPS {
        let app = android.join(app);
        pure.extend(
            files(&app.join("src/main/kotlin"), ".kt")
                .into_iter()
                .filter(|f| !uses_android(f)),
        );
        sources.push(app.join("src/hostTest/kotlin"));
    }
    for expected in [
        "PlaybackRun.kt",
        "PlaybackRequest.kt",
        "StatusFile.kt",
        "LibraryTrialLog.kt",
        "RecorderFlow.kt",
        "Json.kt",
    ] {
        assert!(
            pure.iter().any(|f| f.ends_with(expected)),
            "{expected} is not pure Kotlin: {pure:?}"
        );
    }
    assert!(!pure.iter().any(|f| f.ends_with("Activity.kt")));
    let dir = tempfile::tempdir().unwrap();
    let jar = dir.path().join("apps-host-test.jar");
    run(
        Command::new(kotlinc)
            .arg("-Werror")
            .args(&sources)
            .args(&pure)
            .arg("-include-runtime")
            .arg("-d")
            .arg(&jar),
        "kotlinc (app logic + host tests)",
    );
    let work = dir.path().join("work");
    std::fs::create_dir(&work).unwrap();
    let java_main = |main: &str, args: &[&Path]| {
        run(
            Command::new(&java)
                .arg(format!("-Djava.library.path={}", library_dir().display()))
                .arg("-cp")
                .arg(&jar)
                .arg(main)
                .args(args),
            main,
        )
    };

    let playback = java_main("io.github.sitar.playback.PlaybackHostTestKt", &[&work]);
    assert!(playback.contains("PASSED"), "{playback}");
    println!("playback app: {}", playback.trim());

    let recorder = java_main("io.github.sitar.recorder.RecorderHostTestKt", &[]);
    assert!(recorder.contains("PASSED"), "{recorder}");
    let cases = check_json_cases(&recorder, "arcore");
    assert!(cases >= 7, "{recorder}");
    println!(
        "recorder sample: {} ({cases} JSON escaping cases parsed by serde_json)",
        recorder.lines().last().unwrap_or_default()
    );
}
