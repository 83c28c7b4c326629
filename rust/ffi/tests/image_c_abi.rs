//! `sitar_session_image`, `sitar_session_subtrajectory_evidence` and `sitar_session_thumbnail`
//! through their C entry points: every display rotation, every bad input the contract names
//! (NULL, sizes, stride, rotation, state, stale handle), and the evidence they lead to.

use sitar::{
    sitar_session_depth, sitar_session_frame, sitar_session_free, sitar_session_image,
    sitar_session_new, sitar_session_start, sitar_session_stop,
    sitar_session_subtrajectory_evidence, sitar_session_thumbnail, SitarEvidence, SitarIntrinsics,
    SitarPose,
};

#[path = "support/c_abi.rs"]
mod c_abi;

use c_abi::{
    last_error, ERR_BUFFER_TOO_SMALL, ERR_INVALID_ARGUMENT, ERR_INVALID_HANDLE, ERR_INVALID_STATE,
    ERR_NULL, OK,
};
const DT: i64 = 33_333_333;

const W: i32 = 64;
const H: i32 = 48;
const STRIDE: i32 = 72;

fn pose(i: i64) -> SitarPose {
    SitarPose {
        px: 0.01 * i as f64,
        py: 1.5,
        qw: 1.0,
        ..SitarPose::default()
    }
}

/// A padded plane: a bright top-left quadrant, dots for texture, 0xEE in the padding.
fn plane() -> Vec<u8> {
    let mut data = vec![0xEEu8; (STRIDE * H) as usize];
    for y in 0..H as usize {
        for x in 0..W as usize {
            data[y * STRIDE as usize + x] = if x % 7 == 3 && y % 5 == 2 {
                250
            } else if x < 32 && y < 24 {
                160
            } else {
                60
            };
        }
    }
    data
}

fn new_session(config: &std::ffi::CStr) -> u64 {
    let mut h = 0u64;
    assert_eq!(sitar_session_new(config.as_ptr(), &mut h), OK);
    h
}

/// Frames until the next midpoint; returns the frame number reached.
fn to_midpoint(h: u64, mut i: i64) -> i64 {
    loop {
        i += 1;
        let mut flags = 0u32;
        assert_eq!(sitar_session_frame(h, i * DT, &pose(i), &mut flags), OK);
        if flags & 1 != 0 {
            return i;
        }
    }
}

fn thumbnail(h: u64, k: u32) -> Vec<u8> {
    let mut len = 0usize;
    let status = sitar_session_thumbnail(h, k, std::ptr::null_mut(), 0, &mut len);
    assert_eq!(status, if len == 0 { OK } else { ERR_BUFFER_TOO_SMALL });
    let mut out = vec![0u8; len];
    assert_eq!(
        sitar_session_thumbnail(h, k, out.as_mut_ptr(), len, &mut len),
        OK
    );
    out
}

#[test]
fn every_rotation_is_accepted_and_turns_the_thumbnail() {
    let data = plane();
    let h = new_session(c"{\"thumbnail_px\": 32}");
    assert_eq!(sitar_session_start(h, 0, &pose(0)), OK);
    let mut i = 0;
    for (k, rotation) in [0, 90, 180, 270].into_iter().enumerate() {
        i = to_midpoint(h, i);
        assert_eq!(
            sitar_session_image(h, data.as_ptr(), W, H, STRIDE, rotation),
            OK
        );
        let mut e = SitarEvidence::default();
        assert_eq!(
            sitar_session_subtrajectory_evidence(h, k as u32, &mut e),
            OK
        );
        let size = (e.thumbnail_width, e.thumbnail_height);
        assert_eq!(
            size,
            if rotation % 180 == 0 {
                (32, 24)
            } else {
                (24, 32)
            }
        );
        assert_eq!(e.has_image, 1);
        // The padding (0xEE) is not part of the image: mean of the 64×48 pixels only.
        assert!(e.mean_brightness < 120.0, "{e:?}");
        let jpeg = thumbnail(h, k as u32);
        assert_eq!(&jpeg[..2], &[0xFF, 0xD8], "a JPEG starts with SOI");
    }
    sitar_session_free(h);
}

#[test]
fn bad_input_is_the_contracts_error_code() {
    let data = plane();
    let h = new_session(c"{}");
    let img = |h: u64, p: *const u8, w: i32, hh: i32, s: i32, r: i32| {
        sitar_session_image(h, p, w, hh, s, r)
    };
    // Before start: state.
    assert_eq!(img(h, data.as_ptr(), W, H, STRIDE, 0), ERR_INVALID_STATE);
    assert_eq!(sitar_session_start(h, 0, &pose(0)), OK);
    let i = to_midpoint(h, 0);
    assert_eq!(img(h, std::ptr::null(), W, H, STRIDE, 0), ERR_NULL);
    assert!(last_error().contains("luma"), "{}", last_error());
    for (w, hh, s) in [
        (0, H, STRIDE),
        (W, 0, STRIDE),
        (-5, H, STRIDE),
        (W, -1, STRIDE),
    ] {
        assert_eq!(img(h, data.as_ptr(), w, hh, s, 0), ERR_INVALID_ARGUMENT);
        assert!(last_error().contains("width/height"), "{}", last_error());
    }
    assert_eq!(img(h, data.as_ptr(), W, H, W - 1, 0), ERR_INVALID_ARGUMENT);
    assert!(
        last_error().contains("row_stride_bytes"),
        "{}",
        last_error()
    );
    for r in [-90, 1, 45, 360, i32::MAX] {
        assert_eq!(img(h, data.as_ptr(), W, H, STRIDE, r), ERR_INVALID_ARGUMENT);
        assert!(
            last_error().contains("display_rotation"),
            "{}",
            last_error()
        );
    }
    // Nothing was kept by the failed calls.
    let mut e = SitarEvidence::default();
    assert_eq!(sitar_session_subtrajectory_evidence(h, 0, &mut e), OK);
    assert_eq!(e.has_image, 0);
    assert_eq!(img(h, data.as_ptr(), W, H, STRIDE, 90), OK);
    // Evidence of a sub-trajectory that does not exist; NULL out.
    assert_eq!(
        sitar_session_subtrajectory_evidence(h, 5, &mut e),
        ERR_INVALID_ARGUMENT
    );
    assert_eq!(
        sitar_session_subtrajectory_evidence(h, 0, std::ptr::null_mut()),
        ERR_NULL
    );
    let mut len = 0usize;
    assert_eq!(
        sitar_session_thumbnail(h, 0, std::ptr::null_mut(), 0, &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    assert!(len > 100);
    assert_eq!(
        sitar_session_thumbnail(h, 3, std::ptr::null_mut(), 0, &mut len),
        ERR_INVALID_ARGUMENT
    );
    // After stop: state.
    let mut summary = Default::default();
    assert_eq!(
        sitar_session_stop(h, (i + 1) * DT, &pose(i + 1), &mut summary),
        OK
    );
    assert_eq!(img(h, data.as_ptr(), W, H, STRIDE, 0), ERR_INVALID_STATE);
    // A stale handle.
    assert_eq!(sitar_session_free(h), OK);
    assert_eq!(img(h, data.as_ptr(), W, H, STRIDE, 0), ERR_INVALID_HANDLE);
    assert_eq!(img(0, data.as_ptr(), W, H, STRIDE, 0), ERR_INVALID_HANDLE);
    assert_eq!(
        sitar_session_subtrajectory_evidence(h, 0, &mut e),
        ERR_INVALID_HANDLE
    );
}

#[test]
fn evidence_reports_plain_views_and_missing_depth() {
    let textured = plane();
    let plain = vec![128u8; (STRIDE * H) as usize];
    let wall = vec![1500u16; 32 * 24];
    let hole = vec![0u16; 32 * 24];
    let k = SitarIntrinsics {
        fx: 30.0,
        fy: 30.0,
        cx: 16.0,
        cy: 12.0,
    };
    let h = new_session(c"{}");
    assert_eq!(sitar_session_start(h, 0, &pose(0)), OK);
    let mut i = 0;
    for (luma, depth) in [(&textured, &wall), (&plain, &wall), (&textured, &hole)] {
        i = to_midpoint(h, i);
        assert_eq!(sitar_session_image(h, luma.as_ptr(), W, H, STRIDE, 0), OK);
        sitar_session_depth(h, depth.as_ptr(), 32, 24, 64, &k, 0);
    }
    let evidence = |k: u32| {
        let mut e = SitarEvidence::default();
        assert_eq!(sitar_session_subtrajectory_evidence(h, k, &mut e), OK);
        e
    };
    assert_eq!(evidence(0).causes, 0, "{:?}", evidence(0));
    assert_eq!(evidence(1).causes, 1, "low_texture");
    assert_eq!(evidence(2).causes, 64, "no_depth");
    assert_eq!((evidence(2).depth_given, evidence(2).depth_valid), (1, 0));
    assert!((evidence(0).distance_m - 1.5).abs() < 1e-9);
    assert!((evidence(0).linear_speed_m_s - 0.3).abs() < 1e-6);
    sitar_session_free(h);
}

#[test]
fn images_false_makes_the_call_a_no_op() {
    let data = plane();
    let h = new_session(c"{\"images\": false}");
    assert_eq!(sitar_session_start(h, 0, &pose(0)), OK);
    to_midpoint(h, 0);
    assert_eq!(sitar_session_image(h, data.as_ptr(), W, H, STRIDE, 0), OK);
    assert!(thumbnail(h, 0).is_empty());
    sitar_session_free(h);
}
