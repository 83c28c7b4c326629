//! The Unity package imports cleanly: every asset has a committed `.meta`
//! whose GUID is the one its path gives (FNV-1a 128 of `io.github.sitar/PATH`,
//! the rule of `scripts/unity-meta`, recomputed here), GUIDs are unique, no
//! `.meta` is orphaned, the native libraries' `.meta` files carry their
//! platform and CPU, `package.json` has what UPM asks for and its samples
//! exist; and the Editor scripts type-check against stubs of the UnityEditor
//! API. A new file without its `.meta` fails here: run `scripts/unity-meta`.

mod bindings_support;
mod host_support;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

use bindings_support::{mcs_or_skip, run, skip, which, workspace_root};

fn package() -> PathBuf {
    workspace_root().join("unity-plugin")
}

/// The GUID rule: FNV-1a, 128 bits, over the UTF-8 of `io.github.sitar/` + the path.
fn guid(path: &str) -> String {
    let mut h: u128 = 0x6c62_272e_07bb_0142_62b8_2175_6295_c58d;
    for b in format!("io.github.sitar/{path}").bytes() {
        h ^= u128::from(b);
        h = h.wrapping_mul(0x0000_0000_0100_0000_0000_0000_0000_013b);
    }
    format!("{h:032x}")
}

/// Where the native libraries go (scripts/build-unity-plugins), and their platform and CPU.
const LIBRARIES: [(&str, &str, &str); 4] = [
    (
        "Plugins/Android/libs/arm64-v8a/libsitar.so",
        "Android",
        "ARM64",
    ),
    (
        "Plugins/Android/libs/armeabi-v7a/libsitar.so",
        "Android",
        "ARMv7",
    ),
    (
        "Plugins/Android/libs/x86_64/libsitar.so",
        "Android",
        "X86_64",
    ),
    ("Plugins/Linux/x86_64/libsitar.so", "Linux", "x86_64"),
];

/// Relative path → is a folder, for every asset Unity imports (and so needs a `.meta`):
/// not hidden, not under a `~` folder except inside `Samples~/` (samples are copied
/// into projects with their `.meta` files); the libraries and their folders always.
fn assets() -> BTreeMap<String, bool> {
    fn walk(root: &Path, rel: &str, out: &mut BTreeMap<String, bool>) {
        let dir = if rel.is_empty() {
            root.to_path_buf()
        } else {
            root.join(rel)
        };
        for entry in std::fs::read_dir(&dir).unwrap() {
            let entry = entry.unwrap();
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') || name.ends_with(".meta") {
                continue;
            }
            let path = if rel.is_empty() {
                name.clone()
            } else {
                format!("{rel}/{name}")
            };
            let is_dir = entry.file_type().unwrap().is_dir();
            if is_dir && name.ends_with('~') {
                if path == "Samples~" {
                    walk(root, &path, out);
                }
                continue;
            }
            if rel != "Samples~" || is_dir {
                out.insert(path.clone(), is_dir);
            }
            if is_dir {
                walk(root, &path, out);
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(&package(), "", &mut out);
    for (lib, _, _) in LIBRARIES {
        out.insert(lib.to_owned(), false);
        let mut parent = Path::new(lib).parent();
        while let Some(p) = parent.filter(|p| !p.as_os_str().is_empty()) {
            out.insert(p.to_string_lossy().into_owned(), true);
            parent = p.parent();
        }
    }
    out
}

/// Every `.meta` file under the package, as the asset path it belongs to.
fn metas() -> BTreeSet<String> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeSet<String>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(root, &path, out);
            } else if let Some(asset) = path.to_string_lossy().strip_suffix(".meta") {
                let rel = Path::new(asset).strip_prefix(root).unwrap();
                out.insert(rel.to_string_lossy().replace('\\', "/"));
            }
        }
    }
    let mut out = BTreeSet::new();
    walk(&package(), &package(), &mut out);
    out
}

fn read_meta(asset: &str) -> String {
    let path = package().join(format!("{asset}.meta"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn every_asset_has_a_meta_with_its_stable_unique_guid() {
    let assets = assets();
    let metas = metas();
    assert!(assets.len() > 40, "{assets:?}");
    let missing: Vec<&String> = assets.keys().filter(|a| !metas.contains(*a)).collect();
    assert!(
        missing.is_empty(),
        "assets without a .meta (run scripts/unity-meta): {missing:?}"
    );
    let orphans: Vec<&String> = metas.iter().filter(|m| !assets.contains_key(*m)).collect();
    assert!(orphans.is_empty(), ".meta files of nothing: {orphans:?}");
    let mut seen: BTreeMap<String, String> = BTreeMap::new();
    for (asset, is_dir) in &assets {
        let text = read_meta(asset);
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("fileFormatVersion: 2"), "{asset}.meta");
        let found = lines
            .next()
            .and_then(|l| l.strip_prefix("guid: "))
            .unwrap_or_else(|| panic!("{asset}.meta: no guid on line 2"));
        assert_eq!(found, guid(asset), "{asset}.meta: the GUID its path gives");
        if let Some(other) = seen.insert(found.to_owned(), asset.clone()) {
            panic!("{asset} and {other} share the GUID {found}");
        }
        let importer = match (
            is_dir,
            Path::new(asset).extension().and_then(|e| e.to_str()),
        ) {
            (true, _) => "folderAsset: yes\nDefaultImporter:",
            (false, Some("cs")) => "MonoImporter:",
            (false, Some("asmdef")) => "AssemblyDefinitionImporter:",
            (false, Some("md" | "json")) => "TextScriptImporter:",
            (false, Some("prefab")) => "PrefabImporter:",
            (false, Some("mat")) => {
                "NativeFormatImporter:\n  externalObjects: {}\n  mainObjectFileID: 2100000"
            }
            // The reference image library: a ScriptableObject, main object 11400000.
            (false, Some("asset")) => {
                "NativeFormatImporter:\n  externalObjects: {}\n  mainObjectFileID: 11400000"
            }
            (false, Some("png")) => "TextureImporter:",
            (false, Some("so" | "java")) => "PluginImporter:",
            _ => "DefaultImporter:",
        };
        assert!(
            text.contains(importer),
            "{asset}.meta has {importer}:\n{text}"
        );
    }
    // The package's own sources are all there (a generated file of the bridge included).
    for expected in [
        "package.json",
        "Runtime/NativeMethods.g.cs",
        "Runtime/SitarSession.cs",
        "Runtime/Components/SitarRecorder.cs",
        "Editor/Sitar.Editor.asmdef",
        "Samples~/Recorder/Recorder.unity",
    ] {
        assert!(assets.contains_key(expected), "{expected}");
    }
    println!(
        "{} assets, each with its .meta and its own GUID",
        assets.len()
    );
}

#[test]
fn the_native_libraries_meta_files_carry_their_platform_and_cpu() {
    for (lib, platform, cpu) in LIBRARIES {
        let text = read_meta(lib);
        // Each platform entry: `- first:\n      KEY: VALUE\n    second:\n      enabled: N\n      settings: …`.
        let entry = |first: &str| -> (bool, String) {
            let at = text
                .find(&format!("      {first}\n"))
                .unwrap_or_else(|| panic!("{lib}.meta: no entry {first}"));
            let rest = &text[at..];
            let end = rest[1..].find("  - first:").map_or(rest.len(), |e| e + 1);
            let block = &rest[..end];
            (block.contains("enabled: 1"), block.to_owned())
        };
        let (android, android_block) = entry("Android: Android");
        let (editor, editor_block) = entry("Editor: Editor");
        let (linux, linux_block) = entry("Standalone: Linux64");
        for (other, _) in [
            ("Standalone: Win64", 0),
            ("Standalone: OSXUniversal", 0),
            ("iPhone: iOS", 0),
        ] {
            assert!(!entry(other).0, "{lib}: {other} is off");
        }
        match platform {
            "Android" => {
                assert!(android && !editor && !linux, "{lib}: Android only");
                assert!(
                    android_block.contains(&format!("CPU: {cpu}\n")),
                    "{lib}: CPU {cpu}"
                );
                assert!(
                    text.contains("Exclude Android: 0") && text.contains("Exclude Editor: 1"),
                    "{lib}"
                );
            }
            _ => {
                assert!(
                    !android && editor && linux,
                    "{lib}: Editor and Linux players only"
                );
                assert!(
                    editor_block.contains("OS: Linux") && editor_block.contains("CPU: x86_64"),
                    "{lib}"
                );
                assert!(linux_block.contains("CPU: x86_64"), "{lib}");
                assert!(
                    text.contains("Exclude Android: 1") && text.contains("Exclude Editor: 0"),
                    "{lib}"
                );
            }
        }
    }
}

#[test]
fn the_android_java_source_is_for_android_players_only() {
    let text = read_meta("Plugins/Android/Native.java");
    let android = text
        .split("  - first:\n")
        .find(|block| block.contains("      Android: Android\n"))
        .expect("an Android entry");
    assert!(android.contains("enabled: 1"), "{android}");
    assert!(
        text.contains("Exclude Android: 0") && text.contains("Exclude Editor: 1"),
        "{text}"
    );
    assert_eq!(
        text.matches("enabled: 1").count(),
        1,
        "Android only:\n{text}"
    );
}

#[test]
fn package_json_has_what_upm_asks_for_and_its_samples_exist() {
    let text = std::fs::read_to_string(package().join("package.json")).unwrap();
    let p: serde_json::Value = serde_json::from_str(&text).unwrap();
    let field = |k: &str| {
        p[k].as_str()
            .unwrap_or_else(|| panic!("package.json: {k} is a string"))
    };
    let name = field("name");
    assert!(
        name.split('.').count() >= 3
            && name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || ".-_".contains(c))
            && name.len() <= 214,
        "a reverse-domain, lower-case package name: {name}"
    );
    let version = field("version");
    let parts: Vec<&str> = version.split('.').collect();
    assert!(
        parts.len() == 3 && parts.iter().all(|n| n.parse::<u32>().is_ok()),
        "semver: {version}"
    );
    let unity = field("unity");
    assert!(
        unity.split_once('.').is_some_and(|(y, m)| y.len() == 4
            && y.parse::<u32>().is_ok()
            && m.parse::<u32>().is_ok()),
        "unity is YEAR.MINOR: {unity}"
    );
    for k in ["displayName", "description", "license"] {
        assert!(!field(k).is_empty(), "{k}");
    }
    assert!(
        p["author"]["name"].as_str().is_some_and(|n| !n.is_empty()),
        "author.name"
    );
    for k in ["documentationUrl", "changelogUrl", "licensesUrl"] {
        assert!(field(k).starts_with("https://"), "{k}: {}", field(k));
    }
    let deps = p["dependencies"].as_object().expect("dependencies");
    for dep in [
        "com.unity.xr.arfoundation",
        "com.unity.xr.arcore",
        "com.unity.ugui",
    ] {
        assert!(
            deps[dep]
                .as_str()
                .is_some_and(|v| v.split('.').count() == 3),
            "{dep}"
        );
    }
    let samples = p["samples"].as_array().expect("samples");
    assert_eq!(samples.len(), 2);
    for s in samples {
        for k in ["displayName", "description", "path"] {
            assert!(
                s[k].as_str().is_some_and(|v| !v.is_empty()),
                "samples[].{k}: {s}"
            );
        }
        let path = s["path"].as_str().unwrap();
        assert!(path.starts_with("Samples~/"), "{path}");
        let dir = package().join(path);
        assert!(dir.is_dir(), "{path} exists");
        let scene = format!("{}.unity", path.rsplit('/').next().unwrap());
        assert!(dir.join(&scene).is_file(), "{path}/{scene}");
    }
    let changelog = std::fs::read_to_string(package().join("CHANGELOG.md")).unwrap();
    assert!(
        changelog.contains(&format!("## [{version}]")),
        "CHANGELOG.md has {version}"
    );
    let license = std::fs::read_to_string(package().join("LICENSE.md")).unwrap();
    assert!(
        license.contains("MIT") && license.contains("Apache"),
        "LICENSE.md"
    );
    let docs: Vec<_> = std::fs::read_dir(package().join("Documentation~"))
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "md"))
        .collect();
    assert!(!docs.is_empty(), "Documentation~ has a manual page");
}

#[test]
fn the_meta_script_agrees_with_the_committed_files() {
    const NAME: &str = "the_meta_script_agrees_with_the_committed_files";
    let Some(python) = which("python3") else {
        return skip(NAME, "`python3` is not on PATH (Debian package `python3`)");
    };
    let stdout = run(
        Command::new(python)
            .arg(workspace_root().join("scripts/unity-meta"))
            .arg("--check"),
        "scripts/unity-meta --check",
    );
    assert!(stdout.contains("up to date"), "{stdout}");
    // A copy with a new file and a stale .meta: the check names both and fails.
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("unity-plugin");
    copy_dir(&package(), &copy);
    std::fs::write(copy.join("Runtime/New.cs"), "// new\n").unwrap();
    std::fs::write(
        copy.join("README.md.meta"),
        "fileFormatVersion: 2\nguid: 0123\n",
    )
    .unwrap();
    let out = Command::new(which("python3").unwrap())
        .arg(workspace_root().join("scripts/unity-meta"))
        .args(["--check", "--root"])
        .arg(&copy)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success(), "{text}");
    assert!(
        text.contains("missing Runtime/New.cs.meta") && text.contains("outdated README.md.meta"),
        "{text}"
    );
    // Without --check it writes them, with the rule's GUIDs.
    run(
        Command::new(which("python3").unwrap())
            .arg(workspace_root().join("scripts/unity-meta"))
            .arg("--root")
            .arg(&copy),
        "scripts/unity-meta --root COPY",
    );
    let written = std::fs::read_to_string(copy.join("Runtime/New.cs.meta")).unwrap();
    assert!(
        written.contains(&format!("guid: {}\nMonoImporter:", guid("Runtime/New.cs"))),
        "{written}"
    );
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else if !entry.file_name().to_string_lossy().ends_with(".so") {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}

#[test]
fn the_editor_scripts_type_check_against_the_unity_editor_api_shapes() {
    const NAME: &str = "the_editor_scripts_type_check_against_the_unity_editor_api_shapes";
    let Some(mcs) = mcs_or_skip(NAME) else {
        return;
    };
    let support = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bindings_support");
    let cs = |dir: &Path| host_support::files_with_suffix(dir, ".cs");
    let dir = tempfile::tempdir().unwrap();
    let stubs = dir.path().join("UnityEditorStubs.dll");
    run(
        Command::new(&mcs)
            .args(["-target:library", "-unsafe", "-warnaserror"])
            .arg(format!("-out:{}", stubs.display()))
            .args(cs(&support.join("unity_stubs")))
            .args(cs(&support.join("unity_editor_stubs"))),
        "mcs (Unity and UnityEditor stubs)",
    );
    let editor = cs(&package().join("Editor"));
    assert!(!editor.is_empty());
    for defines in [
        "UNITY_EDITOR;UNITY_EDITOR_LINUX",
        "UNITY_EDITOR;UNITY_EDITOR_WIN",
        "UNITY_EDITOR;UNITY_EDITOR_OSX",
    ] {
        run(
            Command::new(&mcs)
                .args(["-target:library", "-warnaserror"])
                .arg(format!("-r:{}", stubs.display()))
                .arg(format!("-define:{defines}"))
                .arg(format!(
                    "-out:{}",
                    dir.path().join("Sitar.Editor.dll").display()
                ))
                .args(&editor),
            &format!("mcs (unity-plugin/Editor; {defines})"),
        );
    }
    println!(
        "type-checked {} Editor files for Linux, Windows and macOS Editors",
        editor.len()
    );
}
