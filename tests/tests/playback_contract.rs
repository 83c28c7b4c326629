//! One playback contract (docs/playback-contract.md): the backend's adb
//! defaults and names, the Kotlin playback app (its build, manifest and
//! `PlaybackRequest.kt`) and the Unity playback logger (`SitarPlaybackRun.cs`,
//! `SitarPlaybackLogger.cs`) must agree, and the page must say the same.

mod playback_support;

use sitar_server::{AdbConfig, adb_contract};

#[test]
fn the_backend_defaults_are_the_shipped_kotlin_playback_app() {
    let app = playback_support::kotlin_playback_app();
    let adb = AdbConfig::default();
    assert_eq!(app.package, adb.package, "android/playback applicationId");
    assert_eq!(app.package, AdbConfig::DEFAULT_PACKAGE);
    assert_eq!(app.activity, adb.activity, "android/playback activity");
    assert_eq!(
        app.exported, "true",
        "am start from the shell needs an exported activity"
    );
    assert_eq!(
        app.launch_mode, "singleTask",
        "a second launch is onNewIntent"
    );
    assert_eq!(
        adb.remote_dir(),
        format!("/sdcard/Android/data/{}/files", app.package),
        "the app's own external folder"
    );
    assert!(adb.check().is_ok());
}

/// (backend name, value) of every name the apps must share.
fn backend_names() -> Vec<(&'static str, &'static str)> {
    vec![
        ("trials extra", adb_contract::EXTRA_TRIALS),
        ("first extra", adb_contract::EXTRA_FIRST),
        ("recording extra", adb_contract::EXTRA_RECORDING),
        ("output extra", adb_contract::EXTRA_OUTPUT),
        ("recording file", adb_contract::RECORDING_FILE),
        ("output folder", adb_contract::OUTPUT_DIR),
        ("status file", adb_contract::STATUS_FILE),
    ]
}

#[test]
fn the_apps_read_the_extras_and_write_the_files_the_backend_uses() {
    let kotlin = playback_support::kotlin_constants();
    let unity = playback_support::unity_constants();
    let names = [
        ("EXTRA_TRIALS", "ExtraTrials"),
        ("EXTRA_FIRST", "ExtraFirst"),
        ("EXTRA_RECORDING", "ExtraRecording"),
        ("EXTRA_OUTPUT", "ExtraOutput"),
        ("RECORDING_FILE", "RecordingFile"),
        ("OUTPUT_DIR", "OutputDir"),
        ("STATUS_FILE", "StatusFile"),
    ];
    for ((what, value), (k, u)) in backend_names().into_iter().zip(names) {
        assert_eq!(
            kotlin.get(k).map(String::as_str),
            Some(value),
            "{what}: PlaybackRequest.{k} in the Kotlin app"
        );
        assert_eq!(
            unity.get(u).map(String::as_str),
            Some(value),
            "{what}: PlaybackRequest.{u} in the Unity package"
        );
    }
    // The Unity MonoBehaviour reads the launch with those names, on every launch.
    let logger = playback_support::unity_logger_source();
    for (_, u) in names {
        assert!(
            logger.contains(&format!("public const string {u} = PlaybackRequest.{u};")),
            "SitarPlaybackLogger exposes {u}"
        );
    }
    for read_on in [
        "void OnApplicationPause(bool paused)",
        "void OnApplicationFocus(bool focused)",
    ] {
        let at = logger.find(read_on).unwrap_or_else(|| panic!("{read_on}"));
        let body = &logger[at..at + logger[at..].find("\n        }\n").unwrap()];
        assert!(
            body.contains("ReadLaunch()"),
            "{read_on} reads the launch extras"
        );
    }
    assert!(
        logger.contains("SleepTimeout.NeverSleep"),
        "keeps the screen on"
    );
}

#[test]
fn the_contract_page_says_what_the_code_does() {
    let page = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/playback-contract.md"),
    )
    .unwrap();
    let adb = AdbConfig::default();
    for needle in [
        format!("`{}`", adb.package),
        format!("`{}`", adb.activity),
        "`/sdcard/Android/data/PACKAGE/files`".to_owned(),
        "am start -S -W -n PACKAGE/ACTIVITY".to_owned(),
        "--ei trials N --ei first F".to_owned(),
        "--es recording FILES/recording.mp4 --es output FILES/out".to_owned(),
        "`output/trajectory_{first + k}.txt`".to_owned(),
        "`failed MESSAGE`".to_owned(),
        "--adb-package".to_owned(),
        "--adb-activity".to_owned(),
        "--adb-remote-dir".to_owned(),
    ] {
        assert!(
            page.contains(&needle),
            "docs/playback-contract.md lacks {needle}"
        );
    }
    for (what, value) in backend_names() {
        assert!(
            page.contains(&format!("`{value}`")) || page.contains(&format!("/{value}")),
            "docs/playback-contract.md names the {what} `{value}`"
        );
    }
    for state in ["`starting`", "`playing K/N`", "`paused K/N`", "`done N/N`"] {
        assert!(page.contains(state), "status {state}");
    }
}
