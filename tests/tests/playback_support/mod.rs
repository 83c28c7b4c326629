//! The playback contract (docs/playback-contract.md) as the shipped apps declare
//! it, read from their sources: the Kotlin playback app's package
//! (`android/playback/build.gradle.kts`), its activity (its manifest), and the
//! extras and file names in `PlaybackRequest.kt` and the Unity package's
//! `SitarPlaybackRun.cs`. The tests compare them with the backend's defaults.
#![allow(dead_code)]

use std::collections::BTreeMap;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

fn read(relative: &str) -> String {
    let path = root().join(relative);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The quoted value after `key` on the first line that has it, e.g. `applicationId = "x"`.
fn quoted_after(text: &str, key: &str, file: &str) -> String {
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with(key))
        .unwrap_or_else(|| panic!("{file}: no line starting with {key}"));
    let start = line.find('"').unwrap_or_else(|| panic!("{file}: {line}")) + 1;
    let end = line[start..]
        .find('"')
        .unwrap_or_else(|| panic!("{file}: {line}"))
        + start;
    line[start..end].to_owned()
}

/// An attribute of an XML element's text: `name="value"`.
fn attribute(element: &str, name: &str) -> Option<String> {
    let at = element.find(&format!("{name}=\""))? + name.len() + 2;
    let end = element[at..].find('"')? + at;
    Some(element[at..end].to_owned())
}

/// The Kotlin playback app as its build and manifest declare it.
#[derive(Debug)]
pub struct KotlinPlaybackApp {
    /// `applicationId`: the package adb starts.
    pub package: String,
    /// The activity's `android:name` (relative to the package when it starts with `.`).
    pub activity: String,
    /// `android:exported`: `am start` from the shell needs `true`.
    pub exported: String,
    /// `android:launchMode`: `singleTask` makes a second launch `onNewIntent`.
    pub launch_mode: String,
}

impl KotlinPlaybackApp {
    /// `PACKAGE/ACTIVITY`, as `am start -n` takes it.
    pub fn component(&self) -> String {
        format!("{}/{}", self.package, self.activity)
    }
}

/// Reads `android/playback`'s build file and manifest.
pub fn kotlin_playback_app() -> KotlinPlaybackApp {
    let gradle_file = "android/playback/build.gradle.kts";
    let gradle = read(gradle_file);
    let package = quoted_after(&gradle, "applicationId", gradle_file);
    let manifest_file = "android/playback/src/main/AndroidManifest.xml";
    let manifest = read(manifest_file);
    let activities: Vec<&str> = manifest
        .match_indices("<activity")
        .map(|(i, _)| &manifest[i..])
        .collect();
    assert_eq!(activities.len(), 1, "{manifest_file}: one activity");
    let element = &activities[0][..activities[0].find('>').expect("element ends")];
    let get = |name| {
        attribute(element, name)
            .unwrap_or_else(|| panic!("{manifest_file}: the activity has no {name}"))
    };
    KotlinPlaybackApp {
        package,
        activity: get("android:name"),
        exported: get("android:exported"),
        launch_mode: get("android:launchMode"),
    }
}

/// `NAME = "value"` string constants of a source file, for lines starting with `prefix`
/// (`const val` in Kotlin, `public const string` in C#).
fn constants(relative: &str, prefix: &str) -> BTreeMap<String, String> {
    let text = read(relative);
    let mut out = BTreeMap::new();
    for line in text
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with(prefix))
    {
        let rest = line[prefix.len()..].trim();
        let Some((name, value)) = rest.split_once('=') else {
            continue;
        };
        let value = value.trim().trim_end_matches(';');
        if let Some(v) = value.strip_prefix('"').and_then(|v| v.strip_suffix('"')) {
            out.insert(name.trim().to_owned(), v.to_owned());
        }
    }
    out
}

/// The string constants of the Kotlin app's `PlaybackRequest` (`EXTRA_TRIALS` → `trials`, …).
pub fn kotlin_constants() -> BTreeMap<String, String> {
    constants(
        "android/playback/src/main/kotlin/io/github/sitar/playback/PlaybackRequest.kt",
        "const val",
    )
}

/// The string constants of the Unity package's `PlaybackRequest` (`ExtraTrials` → `trials`,
/// …), which `SitarPlaybackLogger` reads the launch with.
pub fn unity_constants() -> BTreeMap<String, String> {
    constants(
        "unity-plugin/Runtime/SitarPlaybackRun.cs",
        "public const string",
    )
}

/// The source of the Unity `SitarPlaybackLogger` MonoBehaviour.
pub fn unity_logger_source() -> String {
    read("unity-plugin/Runtime/Components/SitarPlaybackLogger.cs")
}
