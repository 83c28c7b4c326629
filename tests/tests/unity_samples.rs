//! The Unity package's samples (`unity-plugin/Samples~`, made by
//! `scripts/unity-samples`): the prefabs have the paper's sizes, the
//! materials its colours, and every reference in the scenes, prefabs and
//! materials resolves — to an object in the same file, to an asset of the
//! package by its `.meta` GUID, to Unity's built-in resources, or to a script
//! of AR Foundation 5.1, the Input System or uGUI by its package's GUID — and
//! the MonoBehaviours of the package set only fields their classes serialize.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn package() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../unity-plugin")
}

/// Scripts of the samples' dependencies, by the GUIDs of their `.meta` files in
/// the packages (AR Foundation 5.1.0, XR Core Utilities 2.x, Input System 1.6, uGUI 1.0).
/// The image tracking pair is AR Foundation 5.1.0's
/// `Runtime/ARFoundation/ARTrackedImageManager.cs.meta` and
/// `Runtime/ARSubsystems/ImageTrackingSubsystem/XRReferenceImageLibrary.cs.meta`.
const EXTERNAL_SCRIPTS: [(&str, &str); 16] = [
    ("4dea56a9eaadd1c439095de4f9a371cb", "ARTrackedImageManager"),
    (
        "848409ee8ba454f42a5ddff137688a27",
        "XRReferenceImageLibrary",
    ),
    ("3859a92a05d4f5d418cb6ca605290e74", "ARSession"),
    ("fa850fbd5b8aded44846f96e35f1a9f5", "ARInputManager"),
    ("4966719baa26e4b0e8231a24d9bd491a", "ARCameraManager"),
    ("816b289ef451e094f9ae174fb4cf8db0", "ARCameraBackground"),
    ("b15f82cc229284894964d2d30806969d", "AROcclusionManager"),
    ("e0cb9aa70a22847b5925ee5f067c10a9", "XROrigin"),
    ("c2fadf230d1919748a9aa21d40f74619", "TrackedPoseDriver"),
    (
        "01614664b831546d2ae94a42149d80ac",
        "InputSystemUIInputModule",
    ),
    ("76c392e42b5098c458856cdf6ecaaaa1", "EventSystem"),
    ("0cd44c1031e13a943bb63640046fad76", "CanvasScaler"),
    ("dc42784cf147c0c48a680349fa168899", "GraphicRaycaster"),
    ("5f7201a12d95ffc409449d95f23cf332", "Text"),
    ("fe87c0e1cc204ed48ad3b37840f39efc", "Image"),
    ("4e29b1a8efbd4b44bb3f3716e73f07ff", "Button"),
];

/// Unity's built-in resources the samples use: (guid, fileID).
const BUILTINS: [(&str, i64, &str); 7] = [
    ("0000000000000000e000000000000000", 10202, "Cube mesh"),
    ("0000000000000000e000000000000000", 10206, "Cylinder mesh"),
    ("0000000000000000e000000000000000", 10207, "Sphere mesh"),
    ("0000000000000000e000000000000000", 10102, "Arial font"),
    ("0000000000000000f000000000000000", 46, "Standard shader"),
    ("0000000000000000f000000000000000", 10304, "default skybox"),
    ("0000000000000000f000000000000000", 10905, "UISprite"),
];

#[derive(Debug)]
struct Object {
    class_id: u32,
    file_id: i64,
    body: String,
}

/// The documents of a Unity YAML file.
fn objects(text: &str) -> Vec<Object> {
    let mut out: Vec<Object> = Vec::new();
    for line in text.lines() {
        if let Some(header) = line.strip_prefix("--- !u!") {
            let (class, id) = header.split_once(" &").expect("--- !u!CLASS &ID");
            out.push(Object {
                class_id: class.parse().unwrap(),
                file_id: id.split_whitespace().next().unwrap().parse().unwrap(),
                body: String::new(),
            });
        } else if let Some(last) = out.last_mut() {
            last.body.push_str(line);
            last.body.push('\n');
        }
    }
    out
}

/// The value of a top-level key (`  key: value`).
fn value<'a>(body: &'a str, key: &str) -> Option<&'a str> {
    body.lines()
        .find_map(|l| l.strip_prefix(&format!("  {key}: ")))
        .map(str::trim)
}

/// `{x: 1, y: 2, z: 3}` (or with w, or r/g/b/a) as numbers, in order.
fn numbers(inline: &str) -> Vec<f64> {
    inline
        .trim_matches(|c| c == '{' || c == '}')
        .split(',')
        .map(|kv| kv.split_once(':').unwrap().1.trim().parse().unwrap())
        .collect()
}

/// Every `{fileID: N, guid: G, type: T}` and `{fileID: N}` of a text.
fn references(text: &str) -> Vec<(i64, Option<String>)> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(at) = rest.find("{fileID: ") {
        let inner = &rest[at + 9..];
        let end = inner.find('}').unwrap();
        let mut parts = inner[..end].split(',');
        let id: i64 = parts.next().unwrap().trim().parse().unwrap();
        let guid = parts
            .next()
            .and_then(|g| g.trim().strip_prefix("guid: "))
            .map(|g| g.trim().to_owned());
        out.push((id, guid));
        rest = &inner[end..];
    }
    out
}

/// GUID → asset path, from the package's `.meta` files.
fn package_guids() -> BTreeMap<String, String> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, String>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(root, &path, out);
            } else if let Some(asset) = path.to_string_lossy().strip_suffix(".meta") {
                let text = std::fs::read_to_string(&path).unwrap();
                let guid = text
                    .lines()
                    .nth(1)
                    .unwrap()
                    .strip_prefix("guid: ")
                    .unwrap()
                    .to_owned();
                let rel = Path::new(asset)
                    .strip_prefix(root)
                    .unwrap()
                    .to_string_lossy()
                    .into_owned();
                out.insert(guid, rel);
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(&package(), &package(), &mut out);
    out
}

fn sample_files() -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut dirs = vec![package().join("Samples~")];
    while let Some(d) = dirs.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                dirs.push(p);
            } else if p
                .extension()
                .is_some_and(|e| e == "unity" || e == "prefab" || e == "mat" || e == "asset")
            {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

#[test]
fn every_reference_of_the_samples_resolves() {
    let guids = package_guids();
    let external: BTreeMap<&str, &str> = EXTERNAL_SCRIPTS.into_iter().collect();
    let files = sample_files();
    assert_eq!(
        files
            .iter()
            .filter(|f| f.extension().unwrap() == "unity")
            .count(),
        2
    );
    let mut checked = 0;
    for file in &files {
        let name = file.strip_prefix(package()).unwrap().display().to_string();
        let text = std::fs::read_to_string(file).unwrap();
        let objs = objects(&text);
        let local: BTreeSet<i64> = objs.iter().map(|o| o.file_id).collect();
        for (id, guid) in references(&text) {
            checked += 1;
            match guid {
                None => assert!(
                    id == 0 || local.contains(&id),
                    "{name}: {{fileID: {id}}} is in the file"
                ),
                Some(g) if g.starts_with("0000000000000000") => assert!(
                    BUILTINS.iter().any(|(bg, bid, _)| *bg == g && *bid == id),
                    "{name}: built-in {id}/{g} is one the samples know"
                ),
                Some(g) => {
                    if let Some(asset) = guids.get(&g) {
                        let target = package().join(asset);
                        let expected_id = match target.extension().and_then(|e| e.to_str()) {
                            Some("cs") => 11500000,
                            Some("mat") => 2100000,
                            // A ScriptableObject asset and a texture, by their main objects.
                            Some("asset") => 11400000,
                            Some("png") => 2800000,
                            Some("prefab") => {
                                // A prefab is referred to by its root GameObject.
                                let t = std::fs::read_to_string(&target).unwrap();
                                let root = objects(&t)
                                    .into_iter()
                                    .find(|o| o.class_id == 1 && o.file_id == id)
                                    .unwrap_or_else(|| {
                                        panic!("{name}: {asset} has no GameObject {id}")
                                    });
                                let transform = objects(&t)
                                    .into_iter()
                                    .find(|o| {
                                        o.class_id == 4
                                            && value(&o.body, "m_GameObject")
                                                == Some(&format!("{{fileID: {}}}", root.file_id))
                                    })
                                    .unwrap();
                                assert_eq!(
                                    value(&transform.body, "m_Father"),
                                    Some("{fileID: 0}"),
                                    "{asset}: the root"
                                );
                                id
                            }
                            _ => panic!("{name}: refers to {asset}, which nothing should refer to"),
                        };
                        assert_eq!(id, expected_id, "{name}: {asset}");
                        assert!(target.is_file(), "{asset}");
                    } else {
                        assert!(
                            external.contains_key(g.as_str()),
                            "{name}: unknown GUID {g}"
                        );
                        assert_eq!(id, 11500000, "{name}: script {}", external[g.as_str()]);
                    }
                }
            }
        }
    }
    println!(
        "{checked} references in {} sample files resolve",
        files.len()
    );
}

/// The fields Unity serializes of a MonoBehaviour: `public` or `[SerializeField]`, not
/// const, static or readonly, not properties or methods.
fn serialized_fields(source: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for line in source.lines() {
        let mut l = line.trim();
        let mut serialize = false;
        while l.starts_with('[') {
            let end = l.find(']').unwrap();
            serialize |= l[..end].contains("SerializeField");
            l = l[end + 1..].trim_start();
        }
        let public = l.starts_with("public ");
        if !(public || serialize) || l.contains('(') || l.contains('{') || !l.contains(';') {
            continue;
        }
        if ["const ", "static ", "readonly ", "class ", "enum "]
            .iter()
            .any(|k| l.contains(k))
        {
            continue;
        }
        let decl = l.split(['=', ';']).next().unwrap().trim();
        out.insert(decl.rsplit(' ').next().unwrap().to_owned());
    }
    out
}

#[test]
fn the_package_components_in_the_scenes_set_only_their_fields() {
    let guids = package_guids();
    let by_path: BTreeMap<&str, &str> = guids
        .iter()
        .map(|(g, p)| (p.as_str(), g.as_str()))
        .collect();
    let frame = "  m_ObjectHideFlags m_CorrespondingSourceObject m_PrefabInstance m_PrefabAsset m_GameObject \
                 m_Enabled m_EditorHideFlags m_Script m_Name m_EditorClassIdentifier";
    for (scene, script, required) in [
        (
            "Samples~/Recorder/Recorder.unity",
            "Runtime/Components/SitarRecorder.cs",
            &[
                "cameraManager",
                "occlusionManager",
                "arCamera",
                "startPrefab",
                "stopPrefab",
                "cylinderPrefab",
                "jointPrefab",
                "frustumPrefab",
                "errorAreaHighPrefab",
                "errorAreaMediumPrefab",
                "errorPatchHighPrefab",
                "errorPatchMediumPrefab",
                "errorHigh",
                "errorMedium",
                "errorLow",
                "startButton",
                "stopButton",
                "retryButton",
                "status",
                "trajectoryDuration",
                "trajectoryLength",
                "trajectoryDepth",
                "trajectoryRegions",
                "unreliableWarning",
            ][..],
        ),
        (
            "Samples~/Recorder/Recorder.unity",
            "Runtime/Components/SitarVenue.cs",
            &[
                "trackedImageManager",
                "surfaceTilePrefab",
                "pathDotPrefab",
                "tileLow",
                "tileMedium",
                "tileHigh",
                "trail",
                "mapToggle",
                "arCamera",
            ][..],
        ),
        (
            "Samples~/Playback/Playback.unity",
            "Runtime/Components/SitarPlaybackLogger.cs",
            &["cameraManager", "arCamera", "log"][..],
        ),
    ] {
        let source = std::fs::read_to_string(package().join(script)).unwrap();
        let fields = serialized_fields(&source);
        assert!(fields.len() >= required.len(), "{script}: {fields:?}");
        let text = std::fs::read_to_string(package().join(scene)).unwrap();
        let guid = by_path[script];
        let component = objects(&text)
            .into_iter()
            .find(|o| o.class_id == 114 && o.body.contains(&format!("guid: {guid}, type: 3")))
            .unwrap_or_else(|| panic!("{scene} has a {script} (GUID {guid})"));
        let keys: Vec<&str> = component
            .body
            .lines()
            .filter(|l| l.starts_with("  ") && !l.starts_with("   "))
            .filter_map(|l| l.trim().split_once(':').map(|(k, _)| k))
            .filter(|k| !frame.contains(&format!(" {k}")))
            .collect();
        for key in &keys {
            assert!(
                fields.contains(*key),
                "{scene}: {script} has no serialized field {key} ({fields:?})"
            );
        }
        for field in required {
            let v =
                value(&component.body, field).unwrap_or_else(|| panic!("{scene}: {field} is set"));
            assert!(
                v.starts_with("{fileID: ") && !v.starts_with("{fileID: 0}"),
                "{scene}: {field} = {v}"
            );
        }
    }
}

/// The bounding box (min, max) of a prefab's meshes in its root's frame.
fn bounding_box(prefab: &str) -> ([f64; 3], [f64; 3]) {
    let text = std::fs::read_to_string(package().join(prefab)).unwrap();
    let objs = objects(&text);
    let by_id: BTreeMap<i64, &Object> = objs.iter().map(|o| (o.file_id, o)).collect();
    let transform_of = |go: i64| {
        objs.iter()
            .find(|o| {
                o.class_id == 4
                    && value(&o.body, "m_GameObject") == Some(&format!("{{fileID: {go}}}"))
            })
            .unwrap()
    };
    let parse_id = |v: &str| -> i64 {
        v.trim_matches(|c| c == '{' || c == '}')
            .split(':')
            .nth(1)
            .unwrap()
            .trim()
            .parse()
            .unwrap()
    };
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    let mut meshes = 0;
    for filter in objs.iter().filter(|o| o.class_id == 33) {
        let mesh = references(value(&filter.body, "m_Mesh").unwrap())[0].0;
        let half = match mesh {
            10202 | 10207 => [0.5, 0.5, 0.5],
            10206 => [0.5, 1.0, 0.5],
            other => panic!("{prefab}: mesh {other}"),
        };
        meshes += 1;
        for corner in 0..8 {
            let mut p = [0.0; 3];
            for (axis, h) in half.iter().enumerate() {
                p[axis] = if corner >> axis & 1 == 1 { *h } else { -*h };
            }
            // Up the hierarchy: scale, rotate, translate at each level, the root's own included.
            let mut t = transform_of(parse_id(value(&filter.body, "m_GameObject").unwrap()));
            loop {
                let s = numbers(value(&t.body, "m_LocalScale").unwrap());
                let q = numbers(value(&t.body, "m_LocalRotation").unwrap());
                let o = numbers(value(&t.body, "m_LocalPosition").unwrap());
                let v = [p[0] * s[0], p[1] * s[1], p[2] * s[2]];
                let (x, y, z, w) = (q[0], q[1], q[2], q[3]);
                // v + 2w(q×v) + 2 q×(q×v)
                let c1 = [
                    y * v[2] - z * v[1],
                    z * v[0] - x * v[2],
                    x * v[1] - y * v[0],
                ];
                let c2 = [
                    y * c1[2] - z * c1[1],
                    z * c1[0] - x * c1[2],
                    x * c1[1] - y * c1[0],
                ];
                for i in 0..3 {
                    p[i] = v[i] + 2.0 * w * c1[i] + 2.0 * c2[i] + o[i];
                }
                let father = parse_id(value(&t.body, "m_Father").unwrap());
                if father == 0 {
                    break;
                }
                t = by_id[&father];
            }
            for i in 0..3 {
                lo[i] = lo[i].min(p[i]);
                hi[i] = hi[i].max(p[i]);
            }
        }
    }
    assert!(meshes > 0, "{prefab}");
    (lo, hi)
}

fn size(prefab: &str) -> [f64; 3] {
    let (lo, hi) = bounding_box(prefab);
    [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]]
}

fn near(a: f64, b: f64, what: &str) {
    assert!((a - b).abs() < 1e-6, "{what}: {a} vs {b}");
}

#[test]
fn the_prefabs_have_the_papers_sizes() {
    let p = "Samples~/Recorder/Prefabs/";
    // Cylinders and spheres: 0.3 m diameter; Unity's cylinder is 2 units tall, SitarRecorder
    // scales its height to each segment.
    let c = size(&format!("{p}TrajectoryCylinder.prefab"));
    near(c[0], 0.3, "cylinder diameter x");
    near(c[2], 0.3, "cylinder diameter z");
    near(c[1], 2.0, "cylinder height before the recorder scales it");
    let s = size(&format!("{p}TrajectorySphere.prefab"));
    for v in s {
        near(v, 0.3, "sphere diameter");
    }
    // Exclamation points: 5 cm wide, 30 cm high, 5 cm deep, standing upright.
    for name in ["ExclamationHigh", "ExclamationMedium"] {
        let e = size(&format!("{p}{name}.prefab"));
        near(e[0], 0.05, name);
        near(e[1], 0.30, name);
        near(e[2], 0.05, name);
    }
    // Warning signs: 30 × 30 cm in the local XZ plane (local +Y is the surface normal),
    // the apex up the surface (local -Z).
    for name in ["WarningSignHigh", "WarningSignMedium"] {
        let (lo, hi) = bounding_box(&format!("{p}{name}.prefab"));
        near(hi[0] - lo[0], 0.30, name);
        near(hi[2] - lo[2], 0.30, name);
        assert!(hi[1] - lo[1] < 0.02, "{name} is flat: {}", hi[1] - lo[1]);
        near(lo[2], -0.15, name);
    }
    // Frustums: apex at the camera, 15 × 10 cm at 20 cm along +Z (edges 1 cm thick).
    let (lo, hi) = bounding_box(&format!("{p}Frustum.prefab"));
    assert!(
        (hi[2] - 0.20).abs() < 0.006 && lo[2].abs() < 0.006,
        "depth {lo:?} {hi:?}"
    );
    assert!(
        (hi[0] - lo[0] - 0.15).abs() < 0.012 && (hi[1] - lo[1] - 0.10).abs() < 0.012,
        "{lo:?} {hi:?}"
    );
}

#[test]
fn the_materials_have_the_papers_colours_and_the_prefabs_use_them() {
    let guids = package_guids();
    let by_path: BTreeMap<&str, &str> = guids
        .iter()
        .map(|(g, p)| (p.as_str(), g.as_str()))
        .collect();
    let m = "Samples~/Recorder/Materials/";
    let colour = |name: &str| {
        let text = std::fs::read_to_string(package().join(format!("{m}{name}.mat"))).unwrap();
        let line = text
            .lines()
            .find_map(|l| l.trim().strip_prefix("- _Color: "))
            .unwrap();
        numbers(line)
    };
    let high = colour("ErrorHigh");
    assert!(
        high[0] > 0.8 && high[1] < 0.2 && high[2] < 0.2,
        "high is red: {high:?}"
    );
    let medium = colour("ErrorMedium");
    assert!(
        medium[0] > 0.8 && medium[1] > 0.7 && medium[2] < 0.3,
        "medium is yellow: {medium:?}"
    );
    let low = colour("ErrorLow");
    assert!(
        low[2] > 0.8 && low[0] < 0.3 && low[1] < 0.5,
        "low is blue: {low:?}"
    );
    // The venue layer's tiles: the class colours, translucent (Standard shader, Fade mode).
    for (tile, class) in [
        ("VenueTileHigh", &high),
        ("VenueTileMedium", &medium),
        ("VenueTileLow", &low),
    ] {
        let c = colour(tile);
        assert_eq!(c[..3], class[..3], "{tile} has its class's colour");
        assert!(c[3] > 0.2 && c[3] < 0.8, "{tile} is translucent: {c:?}");
        let text = std::fs::read_to_string(package().join(format!("{m}{tile}.mat"))).unwrap();
        assert!(
            text.contains("    - _Mode: 2\n") && text.contains("_ALPHABLEND_ON"),
            "{tile}"
        );
    }
    assert!(colour("VenueTrail")[3] < 0.5, "the trail is faint");
    for (prefab, material) in [
        ("VenueTile", "VenueTileLow"),
        ("VenueTrailDot", "VenueTrail"),
        ("ExclamationHigh", "ErrorHigh"),
        ("ExclamationMedium", "ErrorMedium"),
        ("WarningSignHigh", "ErrorHigh"),
        ("WarningSignMedium", "ErrorMedium"),
        ("TrajectoryCylinder", "ErrorLow"),
        ("TrajectorySphere", "ErrorLow"),
        ("Frustum", "ErrorLow"),
    ] {
        let text = std::fs::read_to_string(
            package().join(format!("Samples~/Recorder/Prefabs/{prefab}.prefab")),
        )
        .unwrap();
        let wanted = by_path[format!("{m}{material}.mat").as_str()];
        let used: BTreeSet<String> = references(&text)
            .into_iter()
            .filter_map(|(id, g)| (id == 2100000).then_some(g).flatten())
            .collect();
        assert_eq!(
            used,
            BTreeSet::from([wanted.to_owned()]),
            "{prefab} uses {material}"
        );
    }
}

/// A GUID's 32 hex digits as AR Foundation serializes a `System.Guid` (`GuidUtil`): the
/// .NET byte order (first three groups little-endian, the rest as written), read as two
/// little-endian 64-bit numbers, low then high.
fn guid_parts(guid: &str) -> (u64, u64) {
    let hex: Vec<u8> = (0..16)
        .map(|i| u8::from_str_radix(&guid[2 * i..2 * i + 2], 16).unwrap())
        .collect();
    let mut net = [0u8; 16];
    for (to, from) in [3, 2, 1, 0, 5, 4, 7, 6].into_iter().enumerate() {
        net[to] = hex[from];
    }
    net[8..].copy_from_slice(&hex[8..]);
    (
        u64::from_le_bytes(net[..8].try_into().unwrap()),
        u64::from_le_bytes(net[8..].try_into().unwrap()),
    )
}

#[test]
fn guid_parts_match_an_image_library_unity_wrote() {
    // arfoundation-samples' ReferenceImageLibrary.asset: the "Golden Trumpet" texture
    // 63f1cae56cf52304dbb8e0b11d46f01c as Unity serialized it.
    assert_eq!(
        guid_parts("63f1cae56cf52304dbb8e0b11d46f01c"),
        (2523261492433898213, 2085243720824830171)
    );
    assert_eq!(
        guid_parts("a6fd8503774c0402aa403884f5b77f39"),
        (288924497207985411, 4143232447317295274)
    );
}

/// `m_GuidLow`/`m_GuidHigh` of the nested block `key:` in a library's text.
fn serialized_guid(body: &str, key: &str) -> (u64, u64) {
    let at = body
        .find(&format!("{key}:\n"))
        .unwrap_or_else(|| panic!("{key}"));
    let mut lines = body[at..].lines().skip(1);
    let mut next = |name: &str| -> u64 {
        let line = lines.next().unwrap().trim();
        line.strip_prefix(&format!("{name}: "))
            .unwrap_or_else(|| panic!("{key}: {line}"))
            .parse()
            .unwrap()
    };
    (next("m_GuidLow"), next("m_GuidHigh"))
}

#[test]
fn the_recorder_tracks_the_venue_anchor_at_its_printed_size() {
    let guids = package_guids();
    let by_path: BTreeMap<&str, &str> = guids
        .iter()
        .map(|(g, p)| (p.as_str(), g.as_str()))
        .collect();
    let texture = "Samples~/Recorder/Venue/VenueAnchor.png";
    let library = "Samples~/Recorder/Venue/VenueAnchorLibrary.asset";
    // The committed anchor image, byte for byte, and square (so its height is its width).
    let png = std::fs::read(package().join(texture)).unwrap();
    assert_eq!(
        png,
        std::fs::read(package().join("Documentation~/venue-anchor/venue-anchor.png")).unwrap(),
        "the sample's anchor is the printable one"
    );
    assert_eq!(&png[12..16], b"IHDR");
    assert_eq!(png[16..20], png[20..24], "the anchor image is square");
    // Printed 180 mm wide on A4 by the script that makes the PDFs.
    let maker =
        std::fs::read_to_string(package().join("Documentation~/venue-anchor/make_venue_anchor.py"))
            .unwrap();
    assert!(maker.contains(r#"("A4", (210, 297), 180)"#), "A4 at 180 mm");

    // The library: AR Foundation's script, one image named as SitarVenue's anchor id, at 0.18 m,
    // its texture the PNG by its .meta GUID, in both of the forms AR Foundation keeps.
    let text = std::fs::read_to_string(package().join(library)).unwrap();
    let objs = objects(&text);
    assert_eq!(objs.len(), 1);
    let lib = &objs[0];
    assert_eq!((lib.class_id, lib.file_id), (114, 11400000));
    assert_eq!(
        value(&lib.body, "m_Script"),
        Some("{fileID: 11500000, guid: 848409ee8ba454f42a5ddff137688a27, type: 3}")
    );
    assert_eq!(lib.body.matches("  - m_SerializedGuid:").count(), 1);
    // The image's own keys, one level down.
    let image = |key: &str| {
        lib.body
            .lines()
            .find_map(|l| l.strip_prefix(&format!("    {key}: ")))
            .map(str::trim)
    };
    let texture_guid = by_path[texture];
    assert_eq!(
        image("m_Texture"),
        Some(format!("{{fileID: 2800000, guid: {texture_guid}, type: 3}}").as_str())
    );
    assert_eq!(
        serialized_guid(&lib.body, "m_SerializedTextureGuid"),
        guid_parts(texture_guid)
    );
    assert_ne!(serialized_guid(&lib.body, "- m_SerializedGuid"), (0, 0));
    assert_ne!(
        (
            value(&lib.body, "m_GuidLow").unwrap(),
            value(&lib.body, "m_GuidHigh").unwrap()
        ),
        ("0", "0"),
        "a library needs its own GUID"
    );
    assert_eq!(numbers(image("m_Size").unwrap()), [0.18, 0.18]);
    assert_eq!(image("m_SpecifySize"), Some("1"));
    let anchor = image("m_Name").unwrap();
    let source =
        std::fs::read_to_string(package().join("Runtime/Components/SitarVenue.cs")).unwrap();
    assert!(
        source.contains(&format!("public string anchorId = \"{anchor}\";")),
        "the image's name is SitarVenue's default anchor id"
    );

    // The scene: an ARTrackedImageManager on the XR Origin with that library, and SitarVenue
    // beside SitarRecorder naming it and the same anchor id.
    let scene =
        std::fs::read_to_string(package().join("Samples~/Recorder/Recorder.unity")).unwrap();
    let objs = objects(&scene);
    let script = |guid: &str| {
        objs.iter()
            .find(|o| o.class_id == 114 && o.body.contains(&format!("guid: {guid}, type: 3")))
            .unwrap_or_else(|| panic!("a MonoBehaviour of {guid}"))
    };
    let manager = script("4dea56a9eaadd1c439095de4f9a371cb");
    assert_eq!(
        value(&manager.body, "m_SerializedLibrary"),
        Some(format!("{{fileID: 11400000, guid: {}, type: 2}}", by_path[library]).as_str())
    );
    let owner = value(&manager.body, "m_GameObject").unwrap();
    let origin = script("e0cb9aa70a22847b5925ee5f067c10a9");
    assert_eq!(
        Some(owner),
        value(&origin.body, "m_GameObject"),
        "on the XR Origin"
    );
    let venue = script(by_path["Runtime/Components/SitarVenue.cs"]);
    assert_eq!(
        value(&venue.body, "trackedImageManager"),
        Some(format!("{{fileID: {}}}", manager.file_id).as_str())
    );
    assert_eq!(value(&venue.body, "anchorId"), Some(anchor));
    let recorder = script(by_path["Runtime/Components/SitarRecorder.cs"]);
    assert_eq!(
        value(&venue.body, "m_GameObject"),
        value(&recorder.body, "m_GameObject"),
        "SitarVenue requires SitarRecorder on its GameObject"
    );
}
