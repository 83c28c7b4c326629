//! Drives the C ABI of the host-built `libsitar.so` (feature `testing`)
//! through `libloading`, as Unity does: a whole session, then every error
//! path — NULLs, freed/garbage handles, too-small buffers, invalid UTF-8, bad
//! JSON, a panic. The structs are declared here from the header, so a layout
//! change on either side shows up as wrong numbers.

mod bindings_support;

use std::ffi::{CStr, c_char};
use std::net::TcpListener;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use bindings_support::{host_library, results_csv};

const OK: i32 = 0;
const ERR_NULL: i32 = -1;
const ERR_INVALID_ARGUMENT: i32 = -2;
const ERR_INVALID_HANDLE: i32 = -3;
const ERR_INVALID_STATE: i32 = -4;
const ERR_PARSE: i32 = -5;
const ERR_NETWORK: i32 = -7;
const ERR_BUFFER_TOO_SMALL: i32 = -8;
const ERR_PANIC: i32 = -99;

const JOB_UPLOADING: i32 = 1;
const JOB_PLAYING: i32 = 2;
const JOB_DONE: i32 = 5;
const JOB_FAILED: i32 = 6;
const JOB_CANCELLED: i32 = 7;

const FRAME_NS: i64 = 33_333_333;
const STEP_M: f64 = 0.1;

#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Pose {
    px: f64,
    py: f64,
    pz: f64,
    qx: f64,
    qy: f64,
    qz: f64,
    qw: f64,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
struct Intrinsics {
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Summary {
    frames: u32,
    midpoints: u32,
    subtrajectories: u32,
    depth_samples: u32,
    duration_s: f64,
    length_m: f64,
    mean_depth_m: f64,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Marker {
    px: f64,
    py: f64,
    pz: f64,
    qx: f64,
    qy: f64,
    qz: f64,
    qw: f64,
    nx: f64,
    ny: f64,
    nz: f64,
    error_class: i32,
    subtrajectory: u32,
    error_m: f64,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
struct Segment {
    cx: f64,
    cy: f64,
    cz: f64,
    qx: f64,
    qy: f64,
    qz: f64,
    qw: f64,
    length: f64,
    subtrajectory: u32,
    error_class: i32,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
struct SubResult {
    error_m: f64,
    subtrajectory: u32,
    error_class: i32,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
struct JobProgress {
    state: i32,
    error_code: i32,
    progress: f64,
    eta_s: f64,
    bytes_sent: u64,
    bytes_total: u64,
    trials_done: u32,
    trials_total: u32,
    results_revision: u32,
    results_trials: u32,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct VenueCell {
    px: f64,
    py: f64,
    pz: f64,
    kind: i32,
    error_class: i32,
    sessions: u32,
    error_m: f64,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Guide {
    on_screen: i32,
    x_px: f64,
    y_px: f64,
    angle_rad: f64,
    distance_m: f64,
}

type H = u64;

/// The C ABI as function pointers resolved from the library.
struct Api {
    version: extern "C" fn() -> *const c_char,
    last_error: extern "C" fn(*mut c_char, usize, *mut usize) -> i32,
    session_new: extern "C" fn(*const c_char, *mut H) -> i32,
    session_free: extern "C" fn(H) -> i32,
    start: extern "C" fn(H, i64, *const Pose) -> i32,
    frame: extern "C" fn(H, i64, *const Pose, *mut u32) -> i32,
    depth: extern "C" fn(H, *const u16, i32, i32, i32, *const Intrinsics, i32) -> i32,
    image: extern "C" fn(H, *const u8, i32, i32, i32, i32) -> i32,
    stop: extern "C" fn(H, i64, *const Pose, *mut Summary) -> i32,
    summary: extern "C" fn(H, *mut Summary) -> i32,
    load_results: extern "C" fn(H, *const c_char) -> i32,
    error_at: extern "C" fn(H, i64, *mut i32, *mut f64) -> i32,
    bounds_at: extern "C" fn(H, i64, *mut i32, *mut f64, *mut f64, *mut f64) -> i32,
    results_calibration: extern "C" fn(H, *mut c_char, usize, *mut usize) -> i32,
    markers: extern "C" fn(H, *mut Marker, usize, *mut usize) -> i32,
    unreliable: extern "C" fn(H, *mut i32) -> i32,
    sub_class: extern "C" fn(H, u32, *mut i32) -> i32,
    segments: extern "C" fn(H, *mut Segment, usize, *mut usize) -> i32,
    sub_results: extern "C" fn(H, *mut SubResult, usize, *mut usize) -> i32,
    plan_ends: extern "C" fn(H, *mut Pose, *mut Pose, *mut u32) -> i32,
    trajectory_tum: extern "C" fn(H, *mut c_char, usize, *mut usize) -> i32,
    save: extern "C" fn(H, *const c_char) -> i32,
    export_gltf: extern "C" fn(H, *const c_char) -> i32,
    load: extern "C" fn(*const c_char, *mut H) -> i32,
    playback_new: extern "C" fn(*const c_char, *mut H) -> i32,
    playback_log: extern "C" fn(H, i64, *const Pose) -> i32,
    playback_len: extern "C" fn(H, *mut usize) -> i32,
    playback_write: extern "C" fn(H, *const c_char, u32) -> i32,
    playback_free: extern "C" fn(H) -> i32,
    upload_start: extern "C" fn(H, *const c_char, *const c_char, *mut H) -> i32,
    upload_progress: extern "C" fn(H, *mut JobProgress) -> i32,
    upload_message: extern "C" fn(H, *mut c_char, usize, *mut usize) -> i32,
    upload_server_id: extern "C" fn(H, *mut c_char, usize, *mut usize) -> i32,
    upload_cancel: extern "C" fn(H) -> i32,
    upload_free: extern "C" fn(H) -> i32,
    anchor: extern "C" fn(H, i64, *const c_char, *const Pose, i32) -> i32,
    load_venue: extern "C" fn(H, *const c_char) -> i32,
    venue_cells: extern "C" fn(H, *mut VenueCell, usize, *mut usize) -> i32,
    #[allow(clippy::type_complexity)]
    guide: extern "C" fn(H, *const Pose, f64, i32, i32, f64, *mut Guide, usize, *mut usize) -> i32,
    testing_panic: extern "C" fn() -> i32,
}

fn api() -> &'static Api {
    static API: OnceLock<Api> = OnceLock::new();
    API.get_or_init(|| {
        // SAFETY: loading our own library; it has no unsound initialisers.
        let lib: &'static libloading::Library = Box::leak(Box::new(
            unsafe { libloading::Library::new(host_library()) }.expect("dlopen libsitar"),
        ));
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: the declared type matches the header's prototype.
                *unsafe { lib.get(concat!($name, "\0").as_bytes()) }.expect($name)
            };
        }
        Api {
            version: sym!("sitar_version"),
            last_error: sym!("sitar_last_error"),
            session_new: sym!("sitar_session_new"),
            session_free: sym!("sitar_session_free"),
            start: sym!("sitar_session_start"),
            frame: sym!("sitar_session_frame"),
            depth: sym!("sitar_session_depth"),
            image: sym!("sitar_session_image"),
            stop: sym!("sitar_session_stop"),
            summary: sym!("sitar_session_summary"),
            load_results: sym!("sitar_session_load_results"),
            error_at: sym!("sitar_session_error_at"),
            bounds_at: sym!("sitar_session_bounds_at"),
            results_calibration: sym!("sitar_session_results_calibration"),
            markers: sym!("sitar_session_markers"),
            unreliable: sym!("sitar_session_results_unreliable"),
            sub_class: sym!("sitar_session_subtrajectory_class"),
            segments: sym!("sitar_session_segments"),
            sub_results: sym!("sitar_session_subtrajectory_results"),
            plan_ends: sym!("sitar_session_plan_ends"),
            trajectory_tum: sym!("sitar_session_trajectory_tum"),
            save: sym!("sitar_session_save"),
            export_gltf: sym!("sitar_session_export_gltf"),
            load: sym!("sitar_session_load"),
            playback_new: sym!("sitar_playback_new"),
            playback_log: sym!("sitar_playback_log"),
            playback_len: sym!("sitar_playback_len"),
            playback_write: sym!("sitar_playback_write"),
            playback_free: sym!("sitar_playback_free"),
            upload_start: sym!("sitar_upload_start"),
            upload_progress: sym!("sitar_upload_progress"),
            upload_message: sym!("sitar_upload_message"),
            upload_server_id: sym!("sitar_upload_server_id"),
            upload_cancel: sym!("sitar_upload_cancel"),
            upload_free: sym!("sitar_upload_free"),
            anchor: sym!("sitar_session_anchor"),
            load_venue: sym!("sitar_session_load_venue"),
            venue_cells: sym!("sitar_session_venue_cells"),
            guide: sym!("sitar_session_guide"),
            testing_panic: sym!("sitar_testing_panic"),
        }
    })
}

fn c(s: &str) -> Vec<u8> {
    let mut v = s.as_bytes().to_vec();
    v.push(0);
    v
}

fn last_error() -> String {
    let a = api();
    let mut len = 0usize;
    let mut buf = vec![0u8; 1024];
    assert_eq!(
        (a.last_error)(buf.as_mut_ptr().cast(), buf.len(), &mut len),
        OK
    );
    String::from_utf8(buf[..len].to_vec()).unwrap()
}

/// Asserts `status == code` and that the last error mentions `needle`.
fn expect_err(status: i32, code: i32, needle: &str) {
    let message = last_error();
    assert_eq!(status, code, "message: {message}");
    assert!(
        message.contains(needle),
        "{message:?} should mention {needle:?}"
    );
}

fn pose_at(frame: i64) -> Pose {
    Pose {
        px: frame as f64 * STEP_M,
        py: 1.5,
        qw: 1.0,
        ..Pose::default()
    }
}

fn new_session(config: &str) -> H {
    let mut h = 0;
    assert_eq!(
        (api().session_new)(c(config).as_ptr().cast(), &mut h),
        OK,
        "{}",
        last_error()
    );
    assert_ne!(h, 0);
    h
}

const W: i32 = 160;
const HGT: i32 = 120;
const K: Intrinsics = Intrinsics {
    fx: 150.0,
    fy: 150.0,
    cx: 80.0,
    cy: 60.0,
};

/// Records 60 frames along +x with a wall 2 m ahead; returns the summary.
fn record(h: H) -> Summary {
    let a = api();
    let depth = vec![2000u16; (W * HGT) as usize];
    assert_eq!((a.start)(h, 0, &pose_at(0)), OK);
    for i in 1..=60 {
        let mut flags = 99;
        assert_eq!(
            (a.frame)(h, i * FRAME_NS, &pose_at(i), &mut flags),
            OK,
            "{}",
            last_error()
        );
        let expected = match i % 10 {
            5 => 1,
            0 => 2,
            _ => 0,
        };
        assert_eq!(flags, expected, "flags of frame {i}");
        if flags == 1 {
            assert_eq!(
                (a.depth)(h, depth.as_ptr(), W, HGT, W * 2, &K, 0),
                OK,
                "{}",
                last_error()
            );
        }
    }
    let mut summary = Summary::default();
    assert_eq!(
        (a.stop)(h, 61 * FRAME_NS, &pose_at(61), &mut summary),
        OK,
        "{}",
        last_error()
    );
    summary
}

/// v rotated by the unit quaternion q = (x, y, z, w): v + 2w(u×v) + 2u×(u×v).
fn rotate(q: (f64, f64, f64, f64), v: (f64, f64, f64)) -> (f64, f64, f64) {
    let (x, y, z, w) = q;
    let cross = |a: (f64, f64, f64), b: (f64, f64, f64)| {
        (
            a.1 * b.2 - a.2 * b.1,
            a.2 * b.0 - a.0 * b.2,
            a.0 * b.1 - a.1 * b.0,
        )
    };
    let t = cross((x, y, z), v);
    let t = (2.0 * t.0, 2.0 * t.1, 2.0 * t.2);
    let u = cross((x, y, z), t);
    (
        v.0 + w * t.0 + u.0,
        v.1 + w * t.1 + u.1,
        v.2 + w * t.2 + u.2,
    )
}

const ERRORS: [f64; 6] = [0.01, 0.12, 0.06, 0.01, 0.2, 0.03];

#[test]
fn version_is_the_crate_version() {
    // SAFETY: a static NUL-terminated string.
    let v = unsafe { CStr::from_ptr((api().version)()) };
    assert_eq!(v.to_str().unwrap(), env!("CARGO_PKG_VERSION"));
}

#[test]
fn whole_session_through_the_c_abi() {
    let a = api();
    let h = new_session(r#"{"convention":"unity"}"#);
    let summary = record(h);
    assert_eq!(
        summary,
        Summary {
            frames: 60,
            midpoints: 6,
            subtrajectories: 6,
            depth_samples: 6,
            duration_s: 61.0 * FRAME_NS as f64 / 1e9,
            length_m: summary.length_m,
            mean_depth_m: 2.0,
        }
    );
    assert!(
        (summary.length_m - 6.1).abs() < 1e-12,
        "{}",
        summary.length_m
    );
    let mut again = Summary::default();
    assert_eq!((a.summary)(h, &mut again), OK);
    assert_eq!(again, summary);

    // Before results: markers are an invalid state, error_at is unknown.
    let mut len = 0;
    expect_err(
        (a.markers)(h, std::ptr::null_mut(), 0, &mut len),
        ERR_INVALID_STATE,
        "",
    );
    let (mut class, mut err) = (-1, 0.0);
    assert_eq!((a.error_at)(h, 10 * FRAME_NS, &mut class, &mut err), OK);
    assert_eq!(class, 0);
    assert!(err.is_nan());

    assert_eq!(
        (a.load_results)(h, c(&results_csv(FRAME_NS, &ERRORS)).as_ptr().cast()),
        OK,
        "{}",
        last_error()
    );
    for (k, e) in ERRORS.iter().enumerate() {
        assert_eq!(
            (a.error_at)(h, 10 * k as i64 * FRAME_NS, &mut class, &mut err),
            OK
        );
        let expected = if *e >= 0.10 {
            3
        } else if *e >= 0.05 {
            2
        } else {
            1
        };
        assert_eq!((class, err), (expected, *e), "sub-trajectory {k}");
        let mut sub = -1;
        assert_eq!((a.sub_class)(h, k as u32, &mut sub), OK);
        assert_eq!(sub, expected);
    }
    assert_eq!((a.error_at)(h, 1_000 * FRAME_NS, &mut class, &mut err), OK);
    assert_eq!(class, 0);
    assert!(err.is_nan());
    let mut results = [SubResult::default(); 8];
    assert_eq!((a.sub_results)(h, results.as_mut_ptr(), 8, &mut len), OK);
    assert_eq!(len, ERRORS.len());
    for (k, r) in results[..len].iter().enumerate() {
        assert_eq!(
            (r.subtrajectory, r.error_m, r.error_class),
            (k as u32, ERRORS[k], class_of(ERRORS[k]))
        );
    }
    let mut unreliable = -1;
    assert_eq!((a.unreliable)(h, &mut unreliable), OK);
    assert_eq!(unreliable, 0);

    // Markers: size query, too small (untouched, needed length), exact.
    assert_eq!(
        (a.markers)(h, std::ptr::null_mut(), 0, &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    assert_eq!(len, 3);
    let sentinel = Marker {
        error_m: -7.0,
        ..Marker::default()
    };
    let mut small = [sentinel; 2];
    len = 0;
    expect_err(
        (a.markers)(h, small.as_mut_ptr(), 2, &mut len),
        ERR_BUFFER_TOO_SMALL,
        "buffer too small",
    );
    assert_eq!(len, 3);
    assert_eq!(small, [sentinel; 2]);
    let mut markers = [Marker::default(); 8];
    assert_eq!((a.markers)(h, markers.as_mut_ptr(), 8, &mut len), OK);
    assert_eq!(len, 3);
    let mut markers = markers[..len].to_vec();
    markers.sort_by_key(|m| m.subtrajectory);
    let subs: Vec<u32> = markers.iter().map(|m| m.subtrajectory).collect();
    assert_eq!(subs, [1, 2, 4], "≥10 cm first (1, 4), then ≥5 cm (2)");
    for m in &markers {
        let k = m.subtrajectory as usize;
        assert_eq!(m.error_m, ERRORS[k]);
        assert_eq!(m.error_class, if ERRORS[k] >= 0.10 { 3 } else { 2 });
        // The wall point straight ahead of the sub-trajectory's midpoint (frame 10k+5).
        let mid_x = (10 * k + 5) as f64 * STEP_M;
        assert!(
            (m.px - mid_x).abs() < 1e-9 && (m.py - 1.5).abs() < 1e-9 && (m.pz - 2.0).abs() < 1e-9,
            "{m:?}"
        );
        assert!(
            (m.nx.abs() + m.ny.abs() + (m.nz + 1.0).abs()) < 1e-9,
            "normal faces the camera: {m:?}"
        );
        let qn = (m.qx * m.qx + m.qy * m.qy + m.qz * m.qz + m.qw * m.qw).sqrt();
        assert!((qn - 1.0).abs() < 1e-9);
        // Warning signs: the rotation takes local +Y onto the surface normal.
        let up = rotate((m.qx, m.qy, m.qz, m.qw), (0.0, 1.0, 0.0));
        assert!(
            (up.0 - m.nx).abs() < 1e-9 && (up.1 - m.ny).abs() < 1e-9 && (up.2 - m.nz).abs() < 1e-9,
            "{up:?} vs {m:?}"
        );
    }

    // Render plan: segments carry their sub-trajectory's class.
    assert_eq!(
        (a.segments)(h, std::ptr::null_mut(), 0, &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    assert!(len > 0);
    let mut segments = vec![Segment::default(); len];
    assert_eq!(
        (a.segments)(h, segments.as_mut_ptr(), segments.len(), &mut len),
        OK
    );
    for s in &segments {
        let e = ERRORS[s.subtrajectory as usize];
        assert_eq!(
            s.error_class,
            if e >= 0.10 {
                3
            } else if e >= 0.05 {
                2
            } else {
                1
            }
        );
        assert!(s.length > 0.0 && (s.cy - 1.5).abs() < 1e-9);
    }
    let (mut start, mut stop, mut mask) = (Pose::default(), Pose::default(), 0u32);
    assert_eq!((a.plan_ends)(h, &mut start, &mut stop, &mut mask), OK);
    assert_eq!(mask, 3);
    assert_eq!(start, pose_at(0));
    assert_eq!(stop, pose_at(61));

    // Trajectory text: exact size works, one byte less is too small and truncates.
    assert_eq!(
        (a.trajectory_tum)(h, std::ptr::null_mut(), 0, &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    let mut buf = vec![0u8; len + 1];
    assert_eq!(
        (a.trajectory_tum)(h, buf.as_mut_ptr().cast(), buf.len(), &mut len),
        OK
    );
    let tum = String::from_utf8(buf[..len].to_vec()).unwrap();
    assert_eq!(buf[len], 0);
    assert_eq!(
        tum.lines().count(),
        1 + 6 + 6,
        "start, midpoints and endpoints are logged"
    );
    assert!(tum.lines().next().unwrap().starts_with("0 0"), "{tum}");
    let mut short = vec![0xAAu8; len];
    assert_eq!(
        (a.trajectory_tum)(h, short.as_mut_ptr().cast(), short.len(), &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    assert_eq!(&short[..len - 1], &tum.as_bytes()[..len - 1]);
    assert_eq!(short[len - 1], 0);

    // Save and load the session folder: same summary and results.
    let dir = tempfile::tempdir().unwrap();
    let folder = dir.path().join("session");
    assert_eq!(
        (a.save)(h, c(folder.to_str().unwrap()).as_ptr().cast()),
        OK,
        "{}",
        last_error()
    );
    // The scene as glTF binary: a GLB header whose length is the file's.
    let glb_path = dir.path().join("scene.glb");
    assert_eq!(
        (a.export_gltf)(h, c(glb_path.to_str().unwrap()).as_ptr().cast()),
        OK,
        "{}",
        last_error()
    );
    let glb = std::fs::read(&glb_path).unwrap();
    assert_eq!(&glb[..4], b"glTF");
    assert_eq!(
        u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize,
        glb.len()
    );
    assert_eq!(
        (a.export_gltf)(h, std::ptr::null()),
        ERR_NULL,
        "a NULL path is refused"
    );
    let mut loaded = 0;
    assert_eq!(
        (a.load)(c(folder.to_str().unwrap()).as_ptr().cast(), &mut loaded),
        OK,
        "{}",
        last_error()
    );
    assert_ne!(loaded, h);
    assert_eq!((a.summary)(loaded, &mut again), OK);
    assert_eq!(again, summary);
    assert_eq!(
        (a.error_at)(loaded, 40 * FRAME_NS, &mut class, &mut err),
        OK
    );
    assert_eq!((class, err), (3, 0.2));

    assert_eq!((a.session_free)(loaded), OK);
    assert_eq!((a.session_free)(h), OK);
}

/// A venue of two cells around its anchor `hall`: a low path cell and a high surface cell.
const VENUE_MAP: &str = r#"{"id":"v0123456789abcdef","name":"Hall","anchor":"hall","cell_m":0.25,
    "convention":"unity","unit":"m","sessions":[],"cells":[
    {"center":[1.0,0.0,0.5],"kind":"path","sessions":1,"subtrajectories":2,"error_m":0.02,"class":"low","directions":[2,0,0,0,0,0,0,0]},
    {"center":[0.0,1.0,0.0],"kind":"surface","sessions":2,"subtrajectories":3,"error_m":0.3,"class":"high","directions":[0,0,3,0,0,0,0,0]}]}"#;

#[test]
fn venue_anchor_cells_and_guide_through_the_c_abi() {
    let a = api();
    let h = new_session("{}");
    // The image on the floor 2 m ahead, its +X turned 90° about +Y (to −Z).
    let q = 0.5f64.sqrt();
    let image = Pose {
        pz: 2.0,
        qy: q,
        qw: q,
        ..Pose::default()
    };
    let hall = c("hall");
    expect_err(
        (a.anchor)(h, 0, hall.as_ptr().cast(), &image, 2),
        ERR_INVALID_STATE,
        "not recording",
    );
    assert_eq!((a.start)(h, 0, &pose_at(0)), OK);
    let long = c(&"x".repeat(65));
    expect_err(
        (a.anchor)(h, 1, long.as_ptr().cast(), &image, 2),
        ERR_INVALID_ARGUMENT,
        "anchor_id",
    );
    expect_err(
        (a.anchor)(h, 1, hall.as_ptr().cast(), &image, 3),
        ERR_INVALID_ARGUMENT,
        "tracking",
    );
    let mut len = 7usize;
    let mut cells = [VenueCell::default(); 4];
    expect_err(
        (a.venue_cells)(h, cells.as_mut_ptr(), 4, &mut len),
        ERR_INVALID_STATE,
        "no venue",
    );
    let map = c(VENUE_MAP);
    assert_eq!((a.load_venue)(h, map.as_ptr().cast()), OK);
    let bad = c(&VENUE_MAP.replace("\"surface\"", "\"wall\""));
    expect_err(
        (a.load_venue)(h, bad.as_ptr().cast()),
        ERR_PARSE,
        "cells[1].kind",
    );
    assert_eq!((a.anchor)(h, 1, hall.as_ptr().cast(), &image, 1), OK);
    expect_err(
        (a.venue_cells)(h, cells.as_mut_ptr(), 4, &mut len),
        ERR_INVALID_STATE,
        "full tracking",
    );
    assert_eq!((a.anchor)(h, 2, hall.as_ptr().cast(), &image, 2), OK);
    assert_eq!(
        (a.venue_cells)(h, cells.as_mut_ptr(), 1, &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    assert_eq!(len, 2);
    assert_eq!((a.venue_cells)(h, cells.as_mut_ptr(), 4, &mut len), OK);
    // Venue (1, 0, 0.5) turned 90° about +Y is (0.5, 0, −1); the anchor is at (0, 0, 2).
    let c0 = cells[0];
    assert!(
        (c0.px - 0.5).abs() < 1e-12 && c0.py.abs() < 1e-12 && (c0.pz - 1.0).abs() < 1e-12,
        "{c0:?}"
    );
    assert_eq!(
        (c0.kind, c0.error_class, c0.sessions, c0.error_m),
        (0, 1, 1, 0.02)
    );
    assert_eq!(
        (cells[1].kind, cells[1].error_class, cells[1].sessions),
        (1, 3, 2)
    );

    // No markers (no results): one guide entry, the high surface cell at (0, 1, 2).
    let ahead = Pose {
        py: 1.0,
        qw: 1.0,
        ..Pose::default()
    };
    let mut guides = [Guide::default(); 2];
    // A 1080 × 1920 portrait screen with a 40 px margin, as in every call below.
    let guide =
        |camera: &Pose, vfov_deg: f64, out: *mut Guide, capacity: usize, len: &mut usize| {
            (a.guide)(h, camera, vfov_deg, 1080, 1920, 40.0, out, capacity, len)
        };
    assert_eq!(guide(&ahead, 60.0, guides.as_mut_ptr(), 2, &mut len), OK);
    assert_eq!(len, 1);
    let g = guides[0];
    assert_eq!(g.on_screen, 1);
    assert!(
        (g.x_px - 540.0).abs() < 1e-9
            && (g.y_px - 960.0).abs() < 1e-9
            && (g.distance_m - 2.0).abs() < 1e-12,
        "{g:?}"
    );
    // Turned around, 0.3 m to the side: the cell is behind, on the right; pinned to the ellipse.
    let behind = Pose {
        px: 0.3,
        py: 1.0,
        qy: 1.0,
        ..Pose::default()
    };
    assert_eq!(guide(&behind, 60.0, guides.as_mut_ptr(), 2, &mut len), OK);
    let g = guides[0];
    assert_eq!(g.on_screen, 0);
    assert!(g.x_px > 540.0 && g.angle_rad.abs() < 1e-12, "{g:?}");
    let (ex, ey) = ((g.x_px - 540.0) / 500.0, (g.y_px - 960.0) / 920.0);
    assert!(
        (ex * ex + ey * ey - 1.0).abs() < 1e-9,
        "on the ellipse: {g:?}"
    );
    assert_eq!(
        guide(&ahead, 60.0, std::ptr::null_mut(), 2, &mut len),
        ERR_NULL
    );
    assert_eq!(
        guide(&ahead, 60.0, std::ptr::null_mut(), 0, &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    expect_err(
        guide(&ahead, 190.0, guides.as_mut_ptr(), 2, &mut len),
        ERR_INVALID_ARGUMENT,
        "vfov_deg",
    );
    assert_eq!((a.session_free)(h), OK);
}

#[test]
fn null_arguments_are_errors() {
    let a = api();
    let mut h = 0;
    expect_err(
        (a.session_new)(std::ptr::null(), &mut h),
        ERR_NULL,
        "config_json",
    );
    expect_err(
        (a.session_new)(c("{}").as_ptr().cast(), std::ptr::null_mut()),
        ERR_NULL,
        "`out`",
    );
    let h = new_session("");
    expect_err((a.start)(h, 0, std::ptr::null()), ERR_NULL, "pose");
    assert_eq!((a.start)(h, 0, &pose_at(0)), OK);
    let mut flags = 0;
    expect_err(
        (a.frame)(h, FRAME_NS, std::ptr::null(), &mut flags),
        ERR_NULL,
        "pose",
    );
    expect_err(
        (a.frame)(h, FRAME_NS, &pose_at(1), std::ptr::null_mut()),
        ERR_NULL,
        "out_flags",
    );
    expect_err(
        (a.depth)(h, std::ptr::null(), W, HGT, W * 2, &K, 0),
        ERR_NULL,
        "depth_mm",
    );
    let depth = vec![2000u16; (W * HGT) as usize];
    expect_err(
        (a.depth)(h, depth.as_ptr(), W, HGT, W * 2, std::ptr::null(), 0),
        ERR_NULL,
        "`k`",
    );
    let mut len = 0;
    expect_err(
        (a.markers)(h, std::ptr::null_mut(), 4, &mut len),
        ERR_NULL,
        "`out`",
    );
    expect_err(
        (a.markers)(h, std::ptr::null_mut(), 0, std::ptr::null_mut()),
        ERR_NULL,
        "out_len",
    );
    expect_err(
        (a.load_results)(h, std::ptr::null()),
        ERR_NULL,
        "csv_or_json",
    );
    let mut class = 0;
    expect_err(
        (a.error_at)(h, 0, &mut class, std::ptr::null_mut()),
        ERR_NULL,
        "out_error_m",
    );
    // sitar_last_error reports its own NULL but keeps the stored message.
    expect_err(
        (a.last_error)(std::ptr::null_mut(), 0, std::ptr::null_mut()),
        ERR_NULL,
        "out_error_m",
    );
    assert_eq!((a.session_free)(h), OK);
}

#[test]
fn freed_zero_garbage_and_wrong_kind_handles_are_invalid() {
    let a = api();
    let h = new_session("{}");
    assert_eq!((a.session_free)(h), OK);
    let mut flags = 0;
    expect_err(
        (a.frame)(h, 1, &pose_at(1), &mut flags),
        ERR_INVALID_HANDLE,
        &format!("handle {h}"),
    );
    expect_err(
        (a.start)(h, 0, &pose_at(0)),
        ERR_INVALID_HANDLE,
        "session handle",
    );
    expect_err((a.session_free)(h), ERR_INVALID_HANDLE, "already freed");
    for garbage in [0u64, 1, 2, 12_345, u64::MAX, h ^ 1] {
        expect_err(
            (a.session_free)(garbage),
            ERR_INVALID_HANDLE,
            &format!("handle {garbage}"),
        );
        let mut s = Summary::default();
        expect_err((a.summary)(garbage, &mut s), ERR_INVALID_HANDLE, "session");
    }
    // A live session handle is not a playback logger.
    let live = new_session("{}");
    expect_err(
        (a.playback_log)(live, 0, &pose_at(0)),
        ERR_INVALID_HANDLE,
        "playback handle",
    );
    assert_eq!((a.session_free)(live), OK);
}

#[test]
fn bad_text_and_bad_arguments_are_errors() {
    let a = api();
    let mut h = 0;
    let invalid_utf8 = [b'{', 0xFF, b'}', 0];
    expect_err(
        (a.session_new)(invalid_utf8.as_ptr().cast(), &mut h),
        ERR_INVALID_ARGUMENT,
        "UTF-8",
    );
    expect_err(
        (a.session_new)(c("{").as_ptr().cast(), &mut h),
        ERR_PARSE,
        "",
    );
    expect_err(
        (a.session_new)(c(r#"{"bogus": 1}"#).as_ptr().cast(), &mut h),
        ERR_PARSE,
        "bogus",
    );
    expect_err(
        (a.session_new)(c(r#"{"max_regions": "three"}"#).as_ptr().cast(), &mut h),
        ERR_PARSE,
        "max_regions",
    );

    let h = new_session("{}");
    let mut flags = 0;
    expect_err(
        (a.frame)(h, FRAME_NS, &pose_at(1), &mut flags),
        ERR_INVALID_STATE,
        "start",
    );
    assert_eq!((a.start)(h, 0, &pose_at(0)), OK);
    let nan = Pose {
        px: f64::NAN,
        ..pose_at(1)
    };
    expect_err(
        (a.frame)(h, FRAME_NS, &nan, &mut flags),
        ERR_INVALID_ARGUMENT,
        "pose",
    );
    for i in 1..=5 {
        assert_eq!((a.frame)(h, i * FRAME_NS, &pose_at(i), &mut flags), OK);
    }
    let depth = vec![2000u16; (W * HGT) as usize];
    expect_err(
        (a.depth)(h, depth.as_ptr(), W, HGT, W, &K, 0),
        ERR_INVALID_ARGUMENT,
        "row_stride_bytes",
    );
    expect_err(
        (a.depth)(h, depth.as_ptr(), W, -1, W * 2, &K, 0),
        ERR_INVALID_ARGUMENT,
        "width/height",
    );
    expect_err(
        (a.depth)(h, depth.as_ptr(), W, HGT, W * 2, &K, 45),
        ERR_INVALID_ARGUMENT,
        "45",
    );
    expect_err(
        (a.load_results)(h, c("start,error\n12,abc\n").as_ptr().cast()),
        ERR_PARSE,
        "line 2",
    );
    expect_err(
        (a.load_results)(h, invalid_utf8.as_ptr().cast()),
        ERR_INVALID_ARGUMENT,
        "csv_or_json",
    );
    assert_eq!((a.session_free)(h), OK);
}

#[test]
fn last_error_reports_size_and_truncates() {
    let a = api();
    expect_err((a.session_free)(0), ERR_INVALID_HANDLE, "session handle 0");
    let full = last_error();
    let mut len = 0;
    assert_eq!(
        (a.last_error)(std::ptr::null_mut(), 0, &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    assert_eq!(len, full.len());
    let mut buf = [0x55u8; 8];
    assert_eq!(
        (a.last_error)(buf.as_mut_ptr().cast(), buf.len(), &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    assert_eq!(&buf[..7], &full.as_bytes()[..7]);
    assert_eq!(buf[7], 0);
    // Reading the message does not change it.
    assert_eq!(last_error(), full);
}

#[test]
fn a_panic_becomes_an_error_and_the_library_keeps_working() {
    let a = api();
    expect_err((a.testing_panic)(), ERR_PANIC, "on purpose");
    let h = new_session("{}");
    assert_eq!((a.start)(h, 0, &pose_at(0)), OK);
    assert_eq!((a.session_free)(h), OK);
}

#[test]
fn a_session_is_shared_safely_between_threads() {
    let a = api();
    let h = new_session("{}");
    record(h);
    assert_eq!(
        (a.load_results)(h, c(&results_csv(FRAME_NS, &ERRORS)).as_ptr().cast()),
        OK
    );
    let threads: Vec<_> = (0..4)
        .map(|t| {
            std::thread::spawn(move || {
                let a = api();
                for i in 0..2_000 {
                    let k = (i + t) % 6;
                    let (mut class, mut err) = (0, 0.0);
                    assert_eq!(
                        (a.error_at)(h, 10 * k as i64 * FRAME_NS, &mut class, &mut err),
                        OK
                    );
                    assert_eq!(err, ERRORS[k]);
                }
            })
        })
        .collect();
    for t in threads {
        t.join().unwrap();
    }
    // Freeing while another thread hammers the handle: it sees OK, then INVALID_HANDLE, never UB.
    let hammer = std::thread::spawn(move || {
        let a = api();
        let mut seen_invalid = false;
        for _ in 0..100_000 {
            let mut s = Summary::default();
            match (a.summary)(h, &mut s) {
                OK => assert_eq!(s.frames, 60),
                ERR_INVALID_HANDLE => {
                    seen_invalid = true;
                    break;
                }
                other => panic!("unexpected status {other}"),
            }
        }
        seen_invalid
    });
    std::thread::sleep(Duration::from_millis(5));
    assert_eq!((a.session_free)(h), OK);
    assert!(hammer.join().unwrap());
}

#[test]
fn playback_logger_writes_trajectory_n() {
    let a = api();
    let mut p = 0;
    assert_eq!(
        (a.playback_new)(c(r#"{"convention":"arcore"}"#).as_ptr().cast(), &mut p),
        OK,
        "{}",
        last_error()
    );
    for i in 0..3 {
        assert_eq!(
            (a.playback_log)(p, 1_000 + i * FRAME_NS, &pose_at(i)),
            OK,
            "{}",
            last_error()
        );
    }
    let mut len = 0;
    assert_eq!((a.playback_len)(p, &mut len), OK);
    assert_eq!(len, 3);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("logs");
    assert_eq!(
        (a.playback_write)(p, c(out.to_str().unwrap()).as_ptr().cast(), 2),
        OK,
        "{}",
        last_error()
    );
    let text = std::fs::read_to_string(out.join("trajectory_2.txt")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    assert!(
        lines[1].starts_with(&format!("{} ", 1_000 + FRAME_NS)),
        "{text}"
    );
    assert_eq!((a.playback_free)(p), OK);
    expect_err((a.playback_free)(p), ERR_INVALID_HANDLE, "playback handle");
}

fn wait_for_state(job: H, wanted: i32, timeout: Duration) -> JobProgress {
    let a = api();
    let start = Instant::now();
    loop {
        let mut p = JobProgress::default();
        assert_eq!((a.upload_progress)(job, &mut p), OK);
        if p.state == wanted || start.elapsed() > timeout {
            return p;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn upload_needs_a_server_and_reports_failure_and_cancel() {
    let a = api();
    let h = new_session("{}");
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec.mp4");
    std::fs::write(&rec, b"not really an mp4").unwrap();
    let rec_c = c(rec.to_str().unwrap());
    let mut job = 0;
    expect_err(
        (a.upload_start)(h, rec_c.as_ptr().cast(), std::ptr::null(), &mut job),
        ERR_INVALID_ARGUMENT,
        "server_url",
    );
    expect_err(
        (a.upload_start)(
            h,
            rec_c.as_ptr().cast(),
            c(r#"{"trials": "ten"}"#).as_ptr().cast(),
            &mut job,
        ),
        ERR_PARSE,
        "upload options",
    );
    expect_err(
        (a.upload_start)(h, std::ptr::null(), std::ptr::null(), &mut job),
        ERR_NULL,
        "recording_path",
    );

    // A port nobody listens on: the job fails with a network error and says why.
    let closed = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}", closed.local_addr().unwrap());
    drop(closed);
    let options = c(&format!(
        r#"{{"server_url":"{url}","trials":3,"playback":"sim"}}"#
    ));
    assert_eq!(
        (a.upload_start)(h, rec_c.as_ptr().cast(), options.as_ptr().cast(), &mut job),
        OK,
        "{}",
        last_error()
    );
    let p = wait_for_state(job, JOB_FAILED, Duration::from_secs(60));
    assert_eq!(p.state, JOB_FAILED);
    assert_eq!(p.error_code, -7, "SITAR_ERR_NETWORK");
    let mut len = 0;
    let mut buf = vec![0u8; 512];
    assert_eq!(
        (a.upload_message)(job, buf.as_mut_ptr().cast(), buf.len(), &mut len),
        OK
    );
    assert!(String::from_utf8_lossy(&buf[..len]).contains("127.0.0.1"));
    assert_eq!((a.upload_free)(job), OK);

    // A server that accepts and never answers: cancel takes effect at once.
    let silent = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}", silent.local_addr().unwrap());
    let options = c(&format!(r#"{{"server_url":"{url}","trials":3}}"#));
    assert_eq!(
        (a.upload_start)(h, rec_c.as_ptr().cast(), options.as_ptr().cast(), &mut job),
        OK
    );
    assert_eq!((a.upload_cancel)(job), OK);
    let mut p = JobProgress::default();
    assert_eq!((a.upload_progress)(job, &mut p), OK);
    assert_eq!(p.state, JOB_CANCELLED);
    assert_eq!(p.results_revision, 0);
    assert_eq!((a.upload_free)(job), OK);
    expect_err(
        (a.upload_progress)(job, &mut p),
        ERR_INVALID_HANDLE,
        "upload handle",
    );
    assert_eq!((a.session_free)(h), OK);
}

/// A cancel during the transfer drops the connection: the server stops receiving long
/// before the end of the file, and the job ends cancelled.
#[test]
fn upload_cancel_stops_a_transfer_in_flight() {
    use std::io::{BufRead, BufReader, Read, Write};
    let a = api();
    let h = new_session("{}");
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("big.mp4");
    let total = 512u64 << 20;
    std::fs::File::create(&rec).unwrap().set_len(total).unwrap();
    // A server that creates session "s1", says it kept nothing, then reads the upload
    // slowly (about 20 MB/s) and reports how many bytes arrived before the connection closed.
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}", listener.local_addr().unwrap());
    let (tx, rx) = std::sync::mpsc::channel::<u64>();
    std::thread::spawn(move || {
        for (k, stream) in listener.incoming().enumerate() {
            let Ok(mut stream) = stream else { return };
            let mut reader = BufReader::new(stream.try_clone().unwrap());
            let mut head = String::new();
            while reader.read_line(&mut head).map(|n| n > 2).unwrap_or(false) {}
            if k == 0 {
                let mut body = [0u8; 4096];
                let len: usize = head
                    .lines()
                    .find_map(|l| {
                        l.to_ascii_lowercase()
                            .strip_prefix("content-length:")
                            .map(|v| v.trim().parse().unwrap())
                    })
                    .unwrap_or(0);
                reader.read_exact(&mut body[..len]).unwrap();
                let answer = r#"{"id":"s1","state":"created"}"#;
                let _ = write!(
                    stream,
                    "HTTP/1.1 201 Created\r\ncontent-type: application/json\r\ncontent-length: {}\r\nconnection: close\r\n\r\n{answer}",
                    answer.len()
                );
                continue;
            }
            if head.starts_with("HEAD ") {
                // No kept prefix to resume from.
                let _ = write!(
                    stream,
                    "HTTP/1.1 200 OK\r\nupload-offset: 0\r\ncontent-length: 0\r\nconnection: close\r\n\r\n"
                );
                continue;
            }
            let mut buf = vec![0u8; 1 << 16];
            let mut received = 0u64;
            while let Ok(n @ 1..) = reader.read(&mut buf) {
                received += n as u64;
                std::thread::sleep(Duration::from_millis(3));
            }
            let _ = tx.send(received);
            return;
        }
    });
    let options = c(&format!(
        r#"{{"server_url":"{url}","trials":3,"playback":"sim"}}"#
    ));
    let job = start_upload(h, &rec, &options);
    let start = Instant::now();
    let mut p = JobProgress::default();
    while start.elapsed() < Duration::from_secs(60) {
        assert_eq!((a.upload_progress)(job, &mut p), OK);
        if p.state == JOB_UPLOADING && p.bytes_sent >= 8 << 20 {
            break;
        }
        assert!(p.state <= JOB_UPLOADING, "{p:?}: {}", message(job));
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(p.bytes_total, total);
    assert_eq!((a.upload_cancel)(job), OK);
    let received = rx
        .recv_timeout(Duration::from_secs(20))
        .expect("the connection is closed after a cancel");
    assert!(
        received < total / 4,
        "the server received {received} of {total} bytes"
    );
    assert_eq!((a.upload_progress)(job, &mut p), OK);
    assert_eq!(p.state, JOB_CANCELLED);
    assert!(p.bytes_sent < total / 4, "{p:?}");
    assert_eq!((a.upload_free)(job), OK);
    assert_eq!((a.session_free)(h), OK);
}

/// Starts an upload job of `recording` with `options` (a C string); panics with the
/// library's last error if it does not start.
fn start_upload(h: H, recording: &std::path::Path, options: &[u8]) -> H {
    let mut job = 0;
    assert_eq!(
        (api().upload_start)(
            h,
            c(recording.to_str().unwrap()).as_ptr().cast(),
            options.as_ptr().cast(),
            &mut job
        ),
        OK,
        "{}",
        last_error()
    );
    job
}

fn message(job: H) -> String {
    let mut len = 0;
    let mut buf = vec![0u8; 512];
    (api().upload_message)(job, buf.as_mut_ptr().cast(), buf.len(), &mut len);
    String::from_utf8_lossy(&buf[..len.min(buf.len())]).into_owned()
}

fn class_of(e: f64) -> i32 {
    if e >= 0.10 {
        3
    } else if e >= 0.05 {
        2
    } else {
        1
    }
}

#[test]
fn upload_against_a_sim_server_loads_progressive_then_final_results() {
    let a = api();
    let dir = tempfile::tempdir().unwrap();
    // 6 s recording, 6 trials at 10× real time: about 0.6 s per trial.
    let rec = sitar_tests::sim_recording(dir.path(), "walk.rec", 6.0, 11);
    let server = sitar_tests::start(sitar_tests::sim_config(&dir.path().join("data"), 10.0, 1));
    let h = new_session(&format!(r#"{{"server_url":"{}"}}"#, server.url()));
    record(h);
    // The backend's token goes with the upload options.
    let options = c(&format!(
        r#"{{"trials":6,"setting":"trim_mean_30","playback":"sim","poll_interval_ms":10,"server_token":"{}"}}"#,
        sitar_tests::APP_TOKEN
    ));
    let job = start_upload(h, &rec, &options);
    let start = Instant::now();
    let mut progressive = false;
    let mut last = JobProgress::default();
    let mut states = Vec::new();
    while start.elapsed() < Duration::from_secs(120) {
        let mut p = JobProgress::default();
        assert_eq!((a.upload_progress)(job, &mut p), OK);
        assert!(
            p.progress >= last.progress - 1e-12,
            "progress never goes back: {last:?} → {p:?}"
        );
        if p.results_revision > 0 && p.results_trials < 6 && p.state != 5 {
            progressive = true;
        }
        if states.last() != Some(&p.state) {
            states.push(p.state);
        }
        last = p;
        if p.state >= 5 {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let mut len = 0;
    let mut buf = vec![0u8; 512];
    assert_eq!(
        (a.upload_message)(job, buf.as_mut_ptr().cast(), buf.len(), &mut len),
        OK
    );
    assert_eq!(
        last.state,
        5,
        "job ended as {last:?}: {}",
        String::from_utf8_lossy(&buf[..len])
    );
    assert_eq!(last.error_code, 0);
    assert_eq!(last.progress, 1.0);
    let size = std::fs::metadata(&rec).unwrap().len();
    assert_eq!((last.bytes_sent, last.bytes_total), (size, size));
    assert_eq!(
        (last.trials_done, last.trials_total, last.results_trials),
        (6, 6, 6)
    );
    assert!(
        last.results_revision >= 2,
        "progressive and final loads: {last:?}"
    );
    assert!(
        progressive,
        "saw results of fewer than 6 trials while playing (states {states:?})"
    );
    assert!(
        states.windows(2).all(|w| w[0] < w[1]),
        "states advance: {states:?}"
    );

    // The session now holds exactly the server's final results.
    let mut id = vec![0u8; 256];
    assert_eq!(
        (a.upload_server_id)(job, id.as_mut_ptr().cast(), id.len(), &mut len),
        OK
    );
    let server_id = String::from_utf8(id[..len].to_vec()).unwrap();
    let json = sitar_tests::client(&server)
        .results_json(&server_id)
        .unwrap();
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let windows = v["windows"].as_array().unwrap();
    assert!(windows.len() > 100, "{} windows", windows.len());
    for w in windows {
        let start = match w["start"].as_i64() {
            Some(ns) => ns,
            None => (w["start"].as_f64().unwrap() * 1e9).round() as i64,
        };
        let e = w["error_m"].as_f64().unwrap();
        let (mut class, mut err) = (0, 0.0);
        assert_eq!((a.error_at)(h, start, &mut class, &mut err), OK);
        assert_eq!((class, err), (class_of(e), e), "window at {start}");
    }
    assert_eq!((a.upload_free)(job), OK);
    assert_eq!((a.session_free)(h), OK);
}

#[test]
fn a_job_for_an_existing_server_session_resumes_its_upload() {
    let a = api();
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let server = sitar_tests::start(sitar_tests::sim_config(&data, 10.0, 1));
    let id = sitar_tests::upload_session(&sitar_tests::client(&server), 3);
    let rec = dir.path().join("big.mp4");
    let total = 96u64 << 20;
    std::fs::File::create(&rec).unwrap().set_len(total).unwrap();
    let h = new_session("{}");
    let options = c(&format!(
        r#"{{"server_url":"{}","session_id":"{id}","poll_interval_ms":10,"server_token":"{}"}}"#,
        server.url(),
        sitar_tests::ADMIN_TOKEN
    ));
    let session_dir = data.join("sessions").join(&id);

    // A first job is cut off mid-transfer (here by a cancel): the server keeps a prefix.
    let job = start_upload(h, &rec, &options);
    let start = Instant::now();
    let mut p = JobProgress::default();
    while start.elapsed() < Duration::from_secs(60) {
        assert_eq!((a.upload_progress)(job, &mut p), OK);
        if p.bytes_sent >= 8 << 20 {
            break;
        }
        assert!(p.state <= JOB_UPLOADING, "{p:?}: {}", message(job));
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!((a.upload_cancel)(job), OK);
    assert_eq!((a.upload_free)(job), OK);
    // The key file is written as the upload begins and the prefix grows after it: wait for
    // bytes in the prefix, not for the key alone.
    let kept_now = || {
        session_dir.join("recording.part.key").exists()
            && std::fs::metadata(session_dir.join("recording.part")).is_ok_and(|m| m.len() > 0)
    };
    let deadline = Instant::now() + Duration::from_secs(20);
    while !kept_now() {
        assert!(Instant::now() < deadline, "the server kept nothing");
        std::thread::sleep(Duration::from_millis(5));
    }
    let kept = std::fs::metadata(session_dir.join("recording.part"))
        .unwrap()
        .len();
    assert!(kept > 0 && kept < total, "kept {kept}");

    // A second job for the same session and file resumes: no byte count below the kept one.
    let job = start_upload(h, &rec, &options);
    let mut lowest = u64::MAX;
    let p = loop {
        let mut p = JobProgress::default();
        assert_eq!((a.upload_progress)(job, &mut p), OK);
        if p.state == JOB_UPLOADING && p.bytes_sent > 0 {
            lowest = lowest.min(p.bytes_sent);
        }
        if p.state >= JOB_PLAYING {
            break p;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "{p:?}");
        std::thread::yield_now();
    };
    assert_eq!(p.state, JOB_PLAYING, "{p:?}: {}", message(job));
    assert!(lowest >= kept, "sent from {lowest}, kept {kept}");
    assert_eq!((p.bytes_sent, p.bytes_total), (total, total));
    assert_eq!(
        std::fs::metadata(session_dir.join("recording"))
            .unwrap()
            .len(),
        total
    );
    assert!(!session_dir.join("recording.part").exists());
    assert_eq!((a.upload_free)(job), OK);

    // A third job finds the recording on the server and sends nothing.
    let job = start_upload(h, &rec, &options);
    let p = wait_for_state(job, JOB_PLAYING, Duration::from_secs(20));
    assert_eq!(p.state, JOB_PLAYING, "{p:?}: {}", message(job));
    assert_eq!((p.bytes_sent, p.bytes_total), (total, total));
    assert_eq!((a.upload_free)(job), OK);

    // A session id that is not server-made is refused at once.
    let mut job = 0;
    expect_err(
        (a.upload_start)(
            h,
            c(rec.to_str().unwrap()).as_ptr().cast(),
            c(&format!(
                r#"{{"server_url":"{}","session_id":"../x"}}"#,
                server.url()
            ))
            .as_ptr()
            .cast(),
            &mut job,
        ),
        ERR_INVALID_ARGUMENT,
        "session_id",
    );
    server.stop();
}

/// Results JSON as the backend writes it, one window per 10-frame sub-trajectory.
fn results_json(window_frames: u32, relation: &str, unit: &str, errors: &[f64]) -> String {
    let key = if unit == "deg" {
        "error_deg"
    } else {
        "error_m"
    };
    let windows: Vec<String> = errors
        .iter()
        .enumerate()
        .map(|(k, e)| {
            format!(
                r#"{{"start":{},"{key}":{e},"pairs":3}}"#,
                10 * k as i64 * FRAME_NS
            )
        })
        .collect();
    format!(
        r#"{{"version":1,"trials":3,"window_frames":{window_frames},"pose_relation":"{relation}","unit":"{unit}","windows":[{}]}}"#,
        windows.join(",")
    )
}

#[test]
fn angle_deg_results_use_the_degree_thresholds_and_unfit_results_are_refused() {
    let a = api();
    let h = new_session(r#"{"convention":"unity","pose_relation":"angle_deg"}"#);
    record(h);
    let degrees = [1.0, 5.0, 3.0, 0.5, 8.0, 2.5];
    let json = c(&results_json(10, "angle_deg", "deg", &degrees));
    assert_eq!(
        (a.load_results)(h, json.as_ptr().cast()),
        OK,
        "{}",
        last_error()
    );
    for (k, e) in degrees.iter().enumerate() {
        let (mut class, mut err) = (0, 0.0);
        assert_eq!(
            (a.error_at)(h, 10 * k as i64 * FRAME_NS, &mut class, &mut err),
            OK
        );
        let expected = if *e >= 4.0 {
            3
        } else if *e >= 2.0 {
            2
        } else {
            1
        };
        assert_eq!((class, err), (expected, *e), "sub-trajectory {k}");
    }
    // Markers search 4° then 2°: subs 1 and 4, then 2 (in metres all six pass 0.10).
    let mut markers = [Marker::default(); 8];
    let mut len = 0;
    assert_eq!((a.markers)(h, markers.as_mut_ptr(), 8, &mut len), OK);
    let mut found: Vec<(u32, i32, f64)> = markers[..len]
        .iter()
        .map(|m| (m.subtrajectory, m.error_class, m.error_m))
        .collect();
    found.sort_by_key(|m| m.0);
    assert_eq!(found, [(1, 3, 5.0), (2, 2, 3.0), (4, 3, 8.0)]);
    let mut unreliable = -1;
    assert_eq!((a.unreliable)(h, &mut unreliable), OK);
    assert_eq!(unreliable, 0, "a mean of 3.3° is below 8°");

    // Other windows, another relation, legacy CSV (metres): refused naming both values.
    for (text, needles) in [
        (
            results_json(20, "angle_deg", "deg", &degrees),
            ["window_frames 20", "subtrajectory_frames 10"],
        ),
        (
            results_json(10, "trans_part", "m", &ERRORS),
            ["pose_relation trans_part", "pose_relation angle_deg"],
        ),
        (
            results_csv(FRAME_NS, &ERRORS),
            ["pose_relation trans_part", "pose_relation angle_deg"],
        ),
    ] {
        let status = (a.load_results)(h, c(&text).as_ptr().cast());
        for needle in needles {
            expect_err(status, ERR_INVALID_ARGUMENT, needle);
        }
    }
    // The degree results stay.
    let (mut class, mut err) = (0, 0.0);
    assert_eq!((a.error_at)(h, 40 * FRAME_NS, &mut class, &mut err), OK);
    assert_eq!((class, err), (3, 8.0));
    // Config keys: wrong values name the key.
    let mut other = 0;
    for (config, key) in [
        (r#"{"pose_relation":"angle_rad"}"#, "pose_relation"),
        (r#"{"thresholds_deg":[4,"2"]}"#, "thresholds_deg"),
        (r#"{"medium_threshold_deg":5}"#, "medium_threshold_deg"),
    ] {
        expect_err(
            (a.session_new)(c(config).as_ptr().cast(), &mut other),
            ERR_PARSE,
            key,
        );
    }
    assert_eq!((a.session_free)(h), OK);
}

/// Calibrated results as the backend writes them: per window the calibrated error, its
/// interval (`None`: no interval) and the raw value (half the error), keys alphabetical.
fn calibrated_json(windows: &[(f64, Option<(f64, f64)>)]) -> String {
    let windows: Vec<String> = windows
        .iter()
        .enumerate()
        .map(|(k, (e, bounds))| {
            let start = 10 * k as i64 * FRAME_NS;
            let end = start + 10 * FRAME_NS;
            match bounds {
                Some((lower, upper)) => format!(
                    r#"{{"start":{start},"end":{end},"class":"low","error_m":{e},"lower_m":{lower},"pairs":3,"raw_m":{},"spread_m":0.01,"upper_m":{upper}}}"#,
                    e / 2.0
                ),
                None => format!(
                    r#"{{"start":{start},"end":{end},"error_m":{e},"pairs":3,"raw_m":null,"spread_m":0.01}}"#
                ),
            }
        })
        .collect();
    format!(
        r#"{{"version":1,"setting":"trim_mean_30","trials":3,"time_unit":"ns","pose_relation":"trans_part","window_frames":10,"unit":"m","calibration":"pixel7-arcore","windows":[{}]}}"#,
        windows.join(",")
    )
}

/// `(present, lower, upper, raw)` of `sitar_session_bounds_at`.
fn bounds_at(h: H, t_ns: i64) -> (i32, f64, f64, f64) {
    let (mut present, mut lower, mut upper, mut raw) = (-1, 0.0, 0.0, 0.0);
    assert_eq!(
        (api().bounds_at)(h, t_ns, &mut present, &mut lower, &mut upper, &mut raw),
        OK,
        "{}",
        last_error()
    );
    (present, lower, upper, raw)
}

fn calibration_name(h: H) -> String {
    let mut buf = [0u8; 64];
    let mut len = usize::MAX;
    assert_eq!(
        (api().results_calibration)(h, buf.as_mut_ptr().cast(), buf.len(), &mut len),
        OK,
        "{}",
        last_error()
    );
    assert_eq!(buf[len], 0, "NUL-terminated");
    String::from_utf8(buf[..len].to_vec()).unwrap()
}

#[test]
fn calibrated_results_give_bounds_and_classify_by_upper_moves_classes_and_markers() {
    let a = api();
    let windows = [
        (0.01, Some((0.005, 0.02))),
        (0.12, Some((0.05, 0.3))),
        (0.03, Some((0.01, 0.15))),
        (0.015, Some((0.005, 0.12))),
        (0.025, Some((0.01, 0.04))),
        (0.03, None),
    ];
    let json = c(&calibrated_json(&windows));
    let classes = |h: H| -> Vec<i32> {
        let mut items = [SubResult::default(); 8];
        let mut len = 0;
        assert_eq!((a.sub_results)(h, items.as_mut_ptr(), 8, &mut len), OK);
        items[..len].iter().map(|r| r.error_class).collect()
    };
    let placed = |h: H| -> Vec<(u32, i32, f64)> {
        let mut markers = [Marker::default(); 8];
        let mut len = 0;
        assert_eq!((a.markers)(h, markers.as_mut_ptr(), 8, &mut len), OK);
        let mut found: Vec<_> = markers[..len]
            .iter()
            .map(|m| (m.subtrajectory, m.error_class, m.error_m))
            .collect();
        found.sort_by_key(|m| m.0);
        found
    };

    // classify_by "estimate" (the default): the errors colour and place markers.
    let h = new_session(r#"{"convention":"unity"}"#);
    record(h);
    let (present, lower, upper, raw) = bounds_at(h, 0);
    assert!(present == 0 && lower.is_nan() && upper.is_nan() && raw.is_nan());
    assert_eq!(calibration_name(h), "");
    assert_eq!(
        (a.load_results)(h, json.as_ptr().cast()),
        OK,
        "{}",
        last_error()
    );
    assert_eq!(calibration_name(h), "pixel7-arcore");
    for (k, (e, bounds)) in windows.iter().enumerate().take(5) {
        let (l, u) = bounds.unwrap();
        // Anywhere within the lookup tolerance of the window's start.
        let t = 10 * k as i64 * FRAME_NS + FRAME_NS / 3;
        assert_eq!(bounds_at(h, t), (1, l, u, e / 2.0), "sub-trajectory {k}");
    }
    for t in [50 * FRAME_NS, 1_000 * FRAME_NS] {
        let (present, lower, upper, raw) = bounds_at(h, t);
        assert!(
            present == 0 && lower.is_nan() && upper.is_nan() && raw.is_nan(),
            "{t}"
        );
    }
    assert_eq!(classes(h), [1, 3, 1, 1, 1, 1]);
    // 10 cm: sub 1; 5 cm: none; 2 cm: subs 2 and 4.
    assert_eq!(placed(h), [(1, 3, 0.12), (2, 2, 0.03), (4, 2, 0.025)]);

    // classify_by "upper": the upper bounds do; sub 5 has none and keeps its error.
    let cautious = new_session(r#"{"convention":"unity","classify_by":"upper"}"#);
    record(cautious);
    assert_eq!((a.load_results)(cautious, json.as_ptr().cast()), OK);
    assert_eq!(classes(cautious), [1, 3, 3, 3, 1, 1]);
    let (mut class, mut err) = (0, 0.0);
    assert_eq!(
        (a.error_at)(cautious, 30 * FRAME_NS, &mut class, &mut err),
        OK
    );
    assert_eq!((class, err), (3, 0.015), "the error stays the estimate");
    // 10 cm finds subs 1, 2 and 3: sub 3 gets the marker sub 4 had.
    assert_eq!(
        placed(cautious),
        [(1, 3, 0.12), (2, 3, 0.03), (3, 3, 0.015)]
    );
    let mut segments = [Segment::default(); 32];
    let mut len = 0;
    assert_eq!(
        (a.segments)(cautious, segments.as_mut_ptr(), 32, &mut len),
        OK
    );
    let class_of_sub = |k: u32| -> Vec<i32> {
        segments[..len]
            .iter()
            .filter(|s| s.subtrajectory == k)
            .map(|s| s.error_class)
            .collect()
    };
    assert!(!class_of_sub(3).is_empty() && class_of_sub(3).iter().all(|&c| c == 3));
    assert!(class_of_sub(4).iter().all(|&c| c == 1));

    // Uncalibrated results replace them: no bounds, no name, the estimate's classes.
    assert_eq!(
        (a.load_results)(cautious, c(&results_csv(FRAME_NS, &ERRORS)).as_ptr().cast()),
        OK
    );
    assert_eq!(bounds_at(cautious, 10 * FRAME_NS).0, 0);
    assert_eq!(calibration_name(cautious), "");
    assert_eq!(classes(cautious), [1, 3, 2, 1, 3, 1]);

    // Bad bounds name the key and the window; the earlier results stay.
    let text = calibrated_json(&windows);
    for (bad, needle) in [
        (
            text.replace(r#""lower_m":0.05"#, r#""lower_m":0.5"#),
            "windows[1].lower_m",
        ),
        (
            text.replace(r#""upper_m":0.02"#, r#""upper_m":-0.02"#),
            "windows[0].upper_m",
        ),
        (
            text.replace(r#""upper_m":0.04"#, r#""upper_m":null"#),
            "windows[4].upper_m",
        ),
    ] {
        assert_ne!(bad, text);
        expect_err(
            (a.load_results)(h, c(&bad).as_ptr().cast()),
            ERR_PARSE,
            needle,
        );
    }
    assert_eq!(calibration_name(h), "pixel7-arcore");
    // NULL outputs, a too-small name buffer, a freed handle.
    let (mut present, mut lower, mut upper, mut raw) = (0, 0.0, 0.0, 0.0);
    expect_err(
        (a.bounds_at)(
            h,
            0,
            &mut present,
            &mut lower,
            std::ptr::null_mut(),
            &mut raw,
        ),
        ERR_NULL,
        "out_upper_m",
    );
    let mut small = [0x55u8; 4];
    let mut len = 0;
    assert_eq!(
        (a.results_calibration)(h, small.as_mut_ptr().cast(), small.len(), &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    assert_eq!((len, &small), (13, b"pix\0"));
    // A config naming another choice is refused, naming the key and the choices.
    let mut other = 0;
    expect_err(
        (a.session_new)(c(r#"{"classify_by":"lower"}"#).as_ptr().cast(), &mut other),
        ERR_PARSE,
        r#"classify_by`: `lower` is not allowed; use "estimate" or "upper""#,
    );
    assert_eq!((a.session_free)(h), OK);
    assert_eq!((a.session_free)(cautious), OK);
    expect_err(
        (a.bounds_at)(h, 0, &mut present, &mut lower, &mut upper, &mut raw),
        ERR_INVALID_HANDLE,
        "",
    );
}

/// A server that answers the session request with a 400 and hands over its body.
fn capture_session_request() -> (String, std::sync::mpsc::Receiver<String>) {
    use std::io::{BufRead, BufReader, Read, Write};
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}", listener.local_addr().unwrap());
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let Ok((mut stream, _)) = listener.accept() else {
            return;
        };
        let mut reader = BufReader::new(stream.try_clone().unwrap());
        let mut length = 0;
        let mut line = String::new();
        while reader.read_line(&mut line).map(|n| n > 2).unwrap_or(false) {
            if let Some(v) = line.to_ascii_lowercase().strip_prefix("content-length:") {
                length = v.trim().parse().unwrap();
            }
            line.clear();
        }
        let mut body = vec![0u8; length];
        reader.read_exact(&mut body).unwrap();
        let answer = r#"{"error":{"code":"bad_request","message":"captured"}}"#;
        let _ = write!(
            stream,
            "HTTP/1.1 400 Bad Request\r\ncontent-type: application/json\r\ncontent-length: {}\r\nconnection: close\r\n\r\n{answer}",
            answer.len()
        );
        let _ = tx.send(String::from_utf8(body).unwrap());
    });
    (url, rx)
}

#[test]
fn an_upload_asks_the_backend_for_the_session_window_settings() {
    let a = api();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("rec.mp4");
    std::fs::write(&rec, b"not really an mp4").unwrap();
    for (config, options, expected) in [
        (
            r#"{"subtrajectory_frames":20,"pose_relation":"angle_deg"}"#,
            r#""trials":4"#,
            serde_json::json!({"trials":4,"setting":"trim_mean_30","playback":"adb",
                               "window_frames":20,"pose_relation":"angle_deg"}),
        ),
        // Equal to the backend's defaults: not sent, so older backends take the session.
        (
            "{}",
            r#""trials":4,"window_frames":10,"pose_relation":"trans_part""#,
            serde_json::json!({"trials":4,"setting":"trim_mean_30","playback":"adb"}),
        ),
        (
            r#"{"convention":"unity"}"#,
            r#""trials":4"#,
            serde_json::json!({"trials":4,"setting":"trim_mean_30","playback":"adb"}),
        ),
        // ARCore poses and a venue: the backend learns where each camera looks and which
        // venue's frame the session joins.
        (
            r#"{"convention":"arcore","venue":"v0123456789abcdef"}"#,
            r#""trials":4"#,
            serde_json::json!({"trials":4,"setting":"trim_mean_30","playback":"adb",
                               "convention":"arcore","venue":"v0123456789abcdef"}),
        ),
        (
            r#"{"convention":"arcore"}"#,
            r#""trials":3,"playback":"sim""#,
            serde_json::json!({"trials":3,"setting":"trim_mean_30","playback":"sim",
                               "convention":"arcore"}),
        ),
        (
            r#"{"venue":"v00000000000000ff","subtrajectory_frames":20}"#,
            r#""trials":4"#,
            serde_json::json!({"trials":4,"setting":"trim_mean_30","playback":"adb",
                               "window_frames":20,"venue":"v00000000000000ff"}),
        ),
    ] {
        let h = new_session(config);
        let (url, body) = capture_session_request();
        let options = c(&format!(r#"{{"server_url":"{url}",{options}}}"#));
        let job = start_upload(h, &rec, &options);
        let body = body
            .recv_timeout(Duration::from_secs(20))
            .expect("a session request");
        let body: serde_json::Value = serde_json::from_str(&body).unwrap();
        assert_eq!(body, expected, "{config}");
        let p = wait_for_state(job, JOB_FAILED, Duration::from_secs(20));
        assert_eq!(p.state, JOB_FAILED, "{p:?}");
        assert!(message(job).contains("captured"), "{}", message(job));
        assert_eq!((a.upload_free)(job), OK);
        assert_eq!((a.session_free)(h), OK);
    }
    // Options that do not fit the session config are refused at once, naming both values.
    let h = new_session(r#"{"subtrajectory_frames":20}"#);
    let mut job = 0;
    for (options, needles) in [
        (
            r#"{"server_url":"http://127.0.0.1:9","window_frames":10}"#,
            ["window_frames 10", "subtrajectory_frames 20"],
        ),
        (
            r#"{"server_url":"http://127.0.0.1:9","pose_relation":"angle_deg"}"#,
            ["pose_relation angle_deg", "pose_relation trans_part"],
        ),
    ] {
        let status = (a.upload_start)(
            h,
            c(rec.to_str().unwrap()).as_ptr().cast(),
            c(options).as_ptr().cast(),
            &mut job,
        );
        for needle in needles {
            expect_err(status, ERR_INVALID_ARGUMENT, needle);
        }
    }
    assert_eq!((a.session_free)(h), OK);
}

/// One request as a capturing server saw it.
#[derive(Debug, Clone)]
struct Captured {
    method: String,
    path: String,
    body: Vec<u8>,
}

/// A backend stand-in that records every request: it creates session `s1`, answers each PUT
/// of the phone's log with `log_status` (`refused` with a 422 naming a cell, to that file),
/// and every other request with a 400 "captured" that ends the job.
fn capture_phone_logs(
    refused: Option<&'static str>,
) -> (String, std::sync::Arc<std::sync::Mutex<Vec<Captured>>>) {
    use std::io::{BufRead, BufReader, Read, Write};
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}", listener.local_addr().unwrap());
    let seen = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let log = seen.clone();
    std::thread::spawn(move || {
        for stream in listener.incoming() {
            let Ok(mut stream) = stream else { return };
            let mut reader = BufReader::new(stream.try_clone().unwrap());
            let mut request = String::new();
            if reader.read_line(&mut request).unwrap_or(0) == 0 {
                continue;
            }
            let mut parts = request.split_whitespace();
            let method = parts.next().unwrap_or_default().to_owned();
            let path = parts.next().unwrap_or_default().to_owned();
            let mut length = 0;
            let mut line = String::new();
            while reader.read_line(&mut line).map(|n| n > 2).unwrap_or(false) {
                if let Some(v) = line.to_ascii_lowercase().strip_prefix("content-length:") {
                    length = v.trim().parse().unwrap();
                }
                line.clear();
            }
            let mut body = vec![0u8; length];
            reader.read_exact(&mut body).unwrap();
            let file = path.strip_prefix("/v1/sessions/s1/").unwrap_or_default();
            let (status, answer) = match (method.as_str(), path.as_str()) {
                ("POST", "/v1/sessions") => ("201 Created", r#"{"id":"s1"}"#.to_owned()),
                ("PUT", _) if Some(file) == refused => (
                    "422 Unprocessable Entity",
                    format!(
                        r#"{{"error":{{"code":"invalid_content","message":"{file} line 2, column qw: not a number"}}}}"#
                    ),
                ),
                ("PUT", _)
                    if [
                        "trajectory.txt",
                        "subtrajectories.csv",
                        "anchors.csv",
                        "walk.txt",
                    ]
                    .contains(&file) =>
                {
                    ("200 OK", r#"{"stored":true}"#.to_owned())
                }
                _ => (
                    "400 Bad Request",
                    r#"{"error":{"code":"bad_request","message":"captured"}}"#.to_owned(),
                ),
            };
            log.lock().unwrap().push(Captured { method, path, body });
            let _ = write!(
                stream,
                "HTTP/1.1 {status}\r\ncontent-type: application/json\r\ncontent-length: {}\r\nconnection: close\r\n\r\n{answer}",
                answer.len()
            );
        }
    });
    (url, seen)
}

/// Records 20 frames with depth at the midpoints and three observations of the anchor
/// `hall` (two full, one limited).
fn record_in_venue(h: H) {
    let a = api();
    let depth = vec![2000u16; (W * HGT) as usize];
    let hall = c("hall");
    let image = Pose {
        pz: 2.0,
        qw: 1.0,
        ..Pose::default()
    };
    assert_eq!((a.start)(h, 0, &pose_at(0)), OK);
    for i in 1..=20 {
        let mut flags = 0;
        assert_eq!((a.frame)(h, i * FRAME_NS, &pose_at(i), &mut flags), OK);
        if flags == 1 {
            assert_eq!((a.depth)(h, depth.as_ptr(), W, HGT, W * 2, &K, 0), OK);
        }
        if let Some(tracking) = match i {
            3 | 12 => Some(2),
            7 => Some(1),
            _ => None,
        } {
            let r = (a.anchor)(h, i * FRAME_NS, hall.as_ptr().cast(), &image, tracking);
            assert_eq!(r, OK, "{}", last_error());
        }
    }
    let mut summary = Summary::default();
    assert_eq!((a.stop)(h, 21 * FRAME_NS, &pose_at(21), &mut summary), OK);
}

/// The upload job of a session in a venue: the session request names the venue and the
/// ARCore convention, then the phone's log goes whole, file by file, from the session folder
/// it saved beside the recording — `trajectory.txt`, `subtrajectories.csv`, `anchors.csv` with
/// every observation, `walk.txt` with every frame's pose — before the recording.
#[test]
fn an_upload_sends_the_phones_log_and_venue_before_the_recording() {
    let a = api();
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("walk.mp4");
    std::fs::write(&rec, b"not really an mp4").unwrap();
    let h = new_session(r#"{"convention":"arcore","venue":"v0123456789abcdef"}"#);
    record_in_venue(h);
    let (url, seen) = capture_phone_logs(None);
    let job = start_upload(
        h,
        &rec,
        &c(&format!(r#"{{"server_url":"{url}","trials":3}}"#)),
    );
    let p = wait_for_state(job, JOB_FAILED, Duration::from_secs(20));
    assert_eq!(p.state, JOB_FAILED, "{p:?}");
    assert!(message(job).contains("captured"), "{}", message(job));
    let seen = seen.lock().unwrap().clone();
    let routes: Vec<String> = seen
        .iter()
        .map(|s| format!("{} {}", s.method, s.path))
        .collect();
    assert_eq!(
        routes[..5],
        [
            "POST /v1/sessions",
            "PUT /v1/sessions/s1/trajectory.txt",
            "PUT /v1/sessions/s1/subtrajectories.csv",
            "PUT /v1/sessions/s1/anchors.csv",
            "PUT /v1/sessions/s1/walk.txt",
        ]
    );
    assert!(
        routes[5..].iter().all(|r| r.ends_with("/recording")),
        "{routes:?}"
    );
    let body: serde_json::Value = serde_json::from_slice(&seen[0].body).unwrap();
    assert_eq!(
        body,
        serde_json::json!({"trials":3,"setting":"trim_mean_30","playback":"adb",
                           "convention":"arcore","venue":"v0123456789abcdef"})
    );
    // Each file as the session folder holds it, whole.
    let folder = dir.path().join("walk.mp4.session");
    for (s, name) in seen[1..5].iter().zip([
        "trajectory.txt",
        "subtrajectories.csv",
        "anchors.csv",
        "walk.txt",
    ]) {
        assert_eq!(s.body, std::fs::read(folder.join(name)).unwrap(), "{name}");
    }
    // The start, two midpoints and two endpoints: integer nanoseconds.
    let tum = String::from_utf8(seen[1].body.clone()).unwrap();
    let stamps: Vec<&str> = tum.lines().map(|l| l.split(' ').next().unwrap()).collect();
    assert_eq!(stamps.len(), 5, "{tum}");
    assert!(stamps.iter().all(|t| t.parse::<i64>().is_ok()), "{tum}");
    let table = String::from_utf8(seen[2].body.clone()).unwrap();
    assert_eq!(table.lines().count(), 1 + 2, "{table}");
    let anchors = String::from_utf8(seen[3].body.clone()).unwrap();
    let lines: Vec<&str> = anchors.lines().collect();
    assert_eq!(lines[0], "t_ns,anchor,px,py,pz,qx,qy,qz,qw,tracking");
    let tracking: Vec<&str> = lines[1..]
        .iter()
        .map(|l| {
            assert!(l.split(',').nth(1) == Some("hall"), "{l}");
            l.rsplit(',').next().unwrap()
        })
        .collect();
    assert_eq!(tracking, ["full", "limited", "full"]);
    // The walk: the start and all 20 frames.
    let walk = String::from_utf8(seen[4].body.clone()).unwrap();
    assert_eq!(walk.lines().count(), 21, "{walk}");
    assert_eq!((a.upload_free)(job), OK);

    // A file the backend refuses fails the job, naming it with the server's message; the
    // recording is not sent.
    let (url, seen) = capture_phone_logs(Some("anchors.csv"));
    let job = start_upload(h, &rec, &c(&format!(r#"{{"server_url":"{url}"}}"#)));
    let p = wait_for_state(job, JOB_FAILED, Duration::from_secs(20));
    assert_eq!(p.state, JOB_FAILED, "{p:?}");
    assert_eq!(p.error_code, ERR_NETWORK, "{}", message(job));
    assert_eq!(
        message(job),
        "the server refused anchors.csv (422 invalid_content): anchors.csv line 2, column qw: \
         not a number"
    );
    assert_eq!(p.bytes_sent, 0);
    let seen = seen.lock().unwrap();
    assert_eq!(seen.len(), 4, "{seen:?}");
    assert!(seen.iter().all(|s| !s.path.ends_with("/recording")));
    assert_eq!((a.upload_free)(job), OK);
    assert_eq!((a.session_free)(h), OK);
}

/// The upload options' `server_token` and `server_cert_sha256` against a real HTTPS backend:
/// the pinned job uploads and finishes; another fingerprint fails the job with
/// SITAR_ERR_NETWORK and a message naming both fingerprints; no token is a 401 failure.
#[test]
fn an_upload_pins_the_backends_certificate_and_sends_its_token() {
    let dir = tempfile::tempdir().unwrap();
    let rec = sitar_tests::sim_recording(dir.path(), "walk.rec", 3.0, 5);
    let mut config = sitar_tests::sim_config(&dir.path().join("data"), 20.0, 1);
    config.tls = Some(sitar_server::TlsConfig {
        names: vec!["127.0.0.1".into()],
        ..sitar_server::TlsConfig::default()
    });
    let server = sitar_tests::start(config);
    let url = server.url();
    assert!(url.starts_with("https://"), "{url}");
    let pin = server.tls_fingerprint().unwrap().to_owned();
    let h = new_session(&format!(r#"{{"server_url":"{url}"}}"#));
    record(h);
    let run = |options: String| {
        let job = start_upload(h, &rec, &c(&options));
        let p = wait_for_state_any(job, &[JOB_DONE, JOB_FAILED], Duration::from_secs(60));
        let text = message(job);
        assert_eq!((api().upload_free)(job), OK);
        (p, text)
    };
    let token = sitar_tests::APP_TOKEN;
    let (p, text) = run(format!(
        r#"{{"trials":2,"playback":"sim","poll_interval_ms":10,"server_token":"{token}","server_cert_sha256":"{pin}"}}"#
    ));
    assert_eq!(p.state, JOB_DONE, "{text}");
    let other = "AA:".repeat(31) + "AA";
    let (p, text) = run(format!(
        r#"{{"trials":2,"playback":"sim","server_token":"{token}","server_cert_sha256":"{other}"}}"#
    ));
    assert_eq!(p.state, JOB_FAILED);
    assert_eq!(p.error_code, -7, "SITAR_ERR_NETWORK: {text}");
    assert!(text.contains(&pin) && text.contains(&other), "{text}");
    let (p, text) = run(format!(
        r#"{{"trials":2,"playback":"sim","server_cert_sha256":"{pin}"}}"#
    ));
    assert_eq!(p.state, JOB_FAILED);
    assert!(text.contains("401"), "{text}");
    assert_eq!((api().session_free)(h), OK);
}

fn wait_for_state_any(job: H, wanted: &[i32], timeout: Duration) -> JobProgress {
    let start = Instant::now();
    loop {
        let mut p = JobProgress::default();
        assert_eq!((api().upload_progress)(job, &mut p), OK);
        if wanted.contains(&p.state) || start.elapsed() > timeout {
            return p;
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// A session given camera images: the upload job saves the session beside the recording
/// (`walk.rec.session/`) and sends its evidence, and the backend serves every thumbnail.
#[test]
fn an_upload_sends_the_camera_evidence_of_the_session() {
    let a = api();
    let dir = tempfile::tempdir().unwrap();
    let rec = sitar_tests::sim_recording(dir.path(), "walk.rec", 6.0, 12);
    let server = sitar_tests::start(sitar_tests::sim_config(&dir.path().join("data"), 10.0, 1));
    let h = new_session(&format!(r#"{{"server_url":"{}"}}"#, server.url()));
    // A textured 64×48 luminance plane (a checkerboard) at every midpoint.
    let (w, hgt) = (64, 48);
    let luma: Vec<u8> = (0..w * hgt)
        .map(|i| {
            if (i % w / 8 + i / w / 8) % 2 == 0 {
                40
            } else {
                200
            }
        })
        .collect();
    let depth = vec![2000u16; (W * HGT) as usize];
    assert_eq!((a.start)(h, 0, &pose_at(0)), OK);
    for i in 1..=60 {
        let mut flags = 0;
        assert_eq!((a.frame)(h, i * FRAME_NS, &pose_at(i), &mut flags), OK);
        if flags == 1 {
            assert_eq!(
                (a.image)(h, luma.as_ptr(), w, hgt, w, 0),
                OK,
                "{}",
                last_error()
            );
            assert_eq!((a.depth)(h, depth.as_ptr(), W, HGT, W * 2, &K, 0), OK);
        }
    }
    let mut summary = Summary::default();
    assert_eq!((a.stop)(h, 61 * FRAME_NS, &pose_at(61), &mut summary), OK);
    let options = c(&format!(
        r#"{{"trials":2,"playback":"sim","poll_interval_ms":10,"server_token":"{}"}}"#,
        sitar_tests::APP_TOKEN
    ));
    let job = start_upload(h, &rec, &options);
    let last = wait_for_state(job, 5, Duration::from_secs(120));
    assert_eq!(last.state, 5, "job done: {}", message(job));
    let saved = dir.path().join("walk.rec.session");
    assert!(
        saved.join("evidence.csv").is_file(),
        "evidence saved beside the recording"
    );
    let mut id = vec![0u8; 64];
    let mut len = 0;
    assert_eq!(
        (a.upload_server_id)(job, id.as_mut_ptr().cast(), id.len(), &mut len),
        OK
    );
    let id = String::from_utf8(id[..len].to_vec()).unwrap();
    let client = sitar_tests::client(&server);
    let list: serde_json::Value =
        serde_json::from_str(&client.subtrajectories_json(&id).unwrap()).unwrap();
    let subs = list["subtrajectories"].as_array().unwrap();
    assert_eq!(subs.len(), summary.midpoints as usize, "{list}");
    for sub in subs {
        let k = sub["index"].as_u64().unwrap();
        let served = client.subtrajectory_image(&id, k as u32).unwrap();
        let phone = std::fs::read(saved.join(format!("thumbnails/{k}.jpg"))).unwrap();
        assert_eq!(served, phone, "thumbnail {k} as the phone made it");
    }
    (a.upload_free)(job);
    (a.session_free)(h);
}
