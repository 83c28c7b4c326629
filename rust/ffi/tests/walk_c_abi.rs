//! The estimate from one walk through the C entry points: `sitar_session_set_calibration`
//! colours the walk at stop, offline, with the numbers the calibration gives; the backend's
//! results replace it; `sitar_session_results_provenance` says which; a bad calibration is
//! an error code and a message naming what is wrong, and changes nothing.

use std::ffi::{c_char, CString};

use sitar::{
    sitar_session_bounds_at, sitar_session_depth, sitar_session_frame, sitar_session_free,
    sitar_session_load_results, sitar_session_markers, sitar_session_new,
    sitar_session_results_calibration, sitar_session_results_provenance,
    sitar_session_set_calibration, sitar_session_start, sitar_session_stop,
    sitar_session_subtrajectory_results, SitarHandle, SitarIntrinsics, SitarMarker, SitarPose,
    SitarSubtrajectoryResult, SitarSummary,
};

#[path = "support/c_abi.rs"]
mod c_abi;
#[path = "support/walk_calibration.rs"]
mod walk_calibration;

use c_abi::{last_error, ERR_INVALID_ARGUMENT, ERR_INVALID_HANDLE, ERR_NULL, ERR_PARSE, OK};
use walk_calibration::{
    expected_only_calibration, walk_calibration, walk_error, walk_x, WALK_FRAMES, WALK_FRAME_NS,
};

fn text(s: &str) -> CString {
    CString::new(s).unwrap()
}

fn new_session() -> SitarHandle {
    let mut h = 0;
    assert_eq!(sitar_session_new(c"{}".as_ptr(), &mut h), OK);
    h
}

fn set_calibration(h: SitarHandle, json: &str) -> i32 {
    sitar_session_set_calibration(h, text(json).as_ptr())
}

fn pose(i: i64) -> SitarPose {
    SitarPose {
        px: walk_x(i),
        py: 1.5,
        qw: 1.0,
        ..SitarPose::default()
    }
}

/// Records the test walk (depth at every midpoint) and stops.
fn walk(h: SitarHandle) {
    const W: i32 = 16;
    let depth = [2000u16; (W * W) as usize];
    let k = SitarIntrinsics {
        fx: 15.0,
        fy: 15.0,
        cx: 8.0,
        cy: 8.0,
    };
    assert_eq!(sitar_session_start(h, 0, &pose(0)), OK);
    for i in 1..=WALK_FRAMES {
        let mut flags = 0;
        assert_eq!(
            sitar_session_frame(h, i * WALK_FRAME_NS, &pose(i), &mut flags),
            OK
        );
        if flags & 1 != 0 {
            assert_eq!(
                sitar_session_depth(h, depth.as_ptr(), W, W, W * 2, &k, 0),
                OK,
                "{}",
                last_error()
            );
        }
    }
    let mut summary = SitarSummary::default();
    let stop = (WALK_FRAMES + 1) * WALK_FRAME_NS;
    assert_eq!(
        sitar_session_stop(h, stop, &pose(WALK_FRAMES), &mut summary),
        OK
    );
    assert_eq!((summary.subtrajectories, summary.depth_samples), (4, 4));
}

fn results(h: SitarHandle) -> Vec<SitarSubtrajectoryResult> {
    let mut items = [SitarSubtrajectoryResult::default(); 8];
    let mut len = 0;
    assert_eq!(
        sitar_session_subtrajectory_results(h, items.as_mut_ptr(), items.len(), &mut len),
        OK
    );
    items[..len].to_vec()
}

fn classes(h: SitarHandle) -> Vec<i32> {
    results(h).iter().map(|r| r.error_class).collect()
}

/// `(source, target, runs, informative)`.
fn provenance(h: SitarHandle) -> (i32, i32, u32, i32) {
    let (mut source, mut target, mut runs, mut informative) = (9, 9, 9, 9);
    assert_eq!(
        sitar_session_results_provenance(h, &mut source, &mut target, &mut runs, &mut informative),
        OK,
        "{}",
        last_error()
    );
    (source, target, runs, informative)
}

fn markers(h: SitarHandle) -> Vec<(u32, i32)> {
    let mut items = [SitarMarker::default(); 8];
    let mut len = 0;
    assert_eq!(
        sitar_session_markers(h, items.as_mut_ptr(), items.len(), &mut len),
        OK,
        "{}",
        last_error()
    );
    items[..len]
        .iter()
        .map(|m| (m.subtrajectory, m.error_class))
        .collect()
}

fn calibration_name(h: SitarHandle) -> String {
    let mut buf = [0 as c_char; 64];
    let mut len = 0;
    assert_eq!(
        sitar_session_results_calibration(h, buf.as_mut_ptr(), buf.len(), &mut len),
        OK
    );
    buf[..len].iter().map(|&c| c as u8 as char).collect()
}

#[test]
fn the_walk_is_coloured_at_stop_and_the_backends_results_replace_it() {
    let h = new_session();
    assert_eq!(provenance(h), (0, 0, 0, -1), "no results yet");
    let json = walk_calibration(10, true).to_json();
    assert_eq!(set_calibration(h, &json), OK, "{}", last_error());
    walk(h);

    // Offline, before any upload: every sub-trajectory has the calibration's error.
    let subs = results(h);
    assert_eq!(classes(h), [1, 1, 3, 3]);
    for (k, r) in subs.iter().enumerate() {
        let expected = walk_error(10 * k as i64);
        assert!(
            (r.error_m - expected).abs() < 1e-12,
            "sub {k}: {}",
            r.error_m
        );
    }
    assert_eq!(provenance(h), (1, 1, 1, 1), "from the walk, live, one run");
    assert_eq!(calibration_name(h), "on_device");
    let (mut present, mut lower, mut upper, mut raw) = (0, 0.0, 0.0, 0.0);
    assert_eq!(
        sitar_session_bounds_at(
            h,
            20 * WALK_FRAME_NS,
            &mut present,
            &mut lower,
            &mut upper,
            &mut raw
        ),
        OK
    );
    let e = walk_error(20);
    assert_eq!(present, 1);
    assert!((lower - e / 2.0).abs() < 1e-12 && (upper - 2.0 * e).abs() < 1e-12);
    // Markers in time order, as the original app: sub 2 is the first high place; sub 3 and
    // the low ones lie within 0.5 m of it.
    assert_eq!(markers(h), [(2, 3)]);

    // A refused calibration changes nothing.
    assert_eq!(set_calibration(h, "{"), ERR_PARSE);
    assert_eq!(provenance(h), (1, 1, 1, 1));

    // The backend's results replace the walk's: legacy CSV says nothing of its source.
    let csv = format!(
        "start,error\n0,0.2\n{},0.01\n{},0.01\n{},0.01\n",
        10 * WALK_FRAME_NS,
        20 * WALK_FRAME_NS,
        30 * WALK_FRAME_NS
    );
    assert_eq!(sitar_session_load_results(h, text(&csv).as_ptr()), OK);
    assert_eq!(classes(h), [3, 1, 1, 1]);
    assert_eq!(provenance(h), (0, 0, 0, -1));
    assert_eq!(calibration_name(h), "");
    // A calibration given now keeps the backend's results.
    assert_eq!(set_calibration(h, &json), OK);
    assert_eq!(classes(h), [3, 1, 1, 1]);

    // Results JSON that names its source, runs and the calibration's verdict.
    let windows: Vec<String> = (0..4)
        .map(|k| {
            let start = 10 * k * WALK_FRAME_NS;
            format!(
                r#"{{"start":{start},"error_m":0.06,"lower_m":0.03,"upper_m":0.12,"raw_m":0.01}}"#
            )
        })
        .collect();
    let replays = format!(
        r#"{{"version":1,"window_frames":10,"pose_relation":"trans_part","unit":"m","calibration":"pixel7","target":"live","source":"replays","runs":5,"informative":false,"windows":[{}]}}"#,
        windows.join(",")
    );
    assert_eq!(
        sitar_session_load_results(h, text(&replays).as_ptr()),
        OK,
        "{}",
        last_error()
    );
    assert_eq!(classes(h), [2, 2, 2, 2]);
    assert_eq!(
        provenance(h),
        (2, 1, 5, 0),
        "replays, live, 5 runs, a guess"
    );
    assert_eq!(sitar_session_free(h), OK);
}

#[test]
fn a_calibration_after_the_stop_colours_at_once_and_says_when_it_is_a_guess() {
    let h = new_session();
    walk(h);
    assert_eq!(classes(h), [0, 0, 0, 0], "nothing before a calibration");
    let guess = walk_calibration(10, false).to_json();
    assert_eq!(set_calibration(h, &guess), OK, "{}", last_error());
    assert_eq!(classes(h), [1, 1, 3, 3]);
    assert_eq!(
        provenance(h),
        (1, 1, 1, 0),
        "the runs do not predict the error"
    );
    // A newer calibration redoes the walk's own estimate.
    assert_eq!(
        set_calibration(h, &walk_calibration(10, true).to_json()),
        OK
    );
    assert_eq!(provenance(h).3, 1);
    assert_eq!(sitar_session_free(h), OK);
}

#[test]
fn a_bad_calibration_is_an_error_naming_what_is_wrong() {
    let h = new_session();
    let refused = |json: &str, code: i32, needles: &[&str]| {
        assert_eq!(set_calibration(h, json), code, "{}", last_error());
        let message = last_error();
        for needle in needles {
            assert!(
                message.contains(needle),
                "{message:?} should name {needle:?}"
            );
        }
    };
    refused("{", ERR_PARSE, &["calibration", "not a calibration file"]);
    refused(r#"{"version": 1}"#, ERR_PARSE, &["calibration"]);
    let mut bad_format = walk_calibration(10, true);
    bad_format.format = "something-else".into();
    refused(&bad_format.to_json(), ERR_PARSE, &["format"]);
    refused(
        &walk_calibration(20, true).to_json(),
        ERR_INVALID_ARGUMENT,
        &["20 window frames", "10 window frames"],
    );
    refused(
        &expected_only_calibration().to_json(),
        ERR_INVALID_ARGUMENT,
        &["no model for the live error from 1 run"],
    );
    // NULL, bad UTF-8, a freed handle.
    assert_eq!(sitar_session_set_calibration(h, std::ptr::null()), ERR_NULL);
    assert!(last_error().contains("json"), "{}", last_error());
    let bad_utf8 = [b'{', 0xff, b'}', 0];
    assert_eq!(
        sitar_session_set_calibration(h, bad_utf8.as_ptr().cast()),
        ERR_INVALID_ARGUMENT
    );
    assert!(last_error().contains("UTF-8"), "{}", last_error());
    // None of them took: the walk stays uncoloured.
    walk(h);
    assert_eq!(classes(h), [0, 0, 0, 0]);
    assert_eq!(provenance(h), (0, 0, 0, -1));
    assert_eq!(sitar_session_free(h), OK);
    let json = walk_calibration(10, true).to_json();
    assert_eq!(set_calibration(h, &json), ERR_INVALID_HANDLE);
    assert!(last_error().contains("session handle"), "{}", last_error());
    let (mut a, mut b, mut c, mut d) = (0, 0, 0, 0);
    assert_eq!(
        sitar_session_results_provenance(h, &mut a, &mut b, &mut c, &mut d),
        ERR_INVALID_HANDLE
    );
    let live = new_session();
    assert_eq!(
        sitar_session_results_provenance(live, &mut a, std::ptr::null_mut(), &mut c, &mut d),
        ERR_NULL
    );
    assert!(last_error().contains("out_target"), "{}", last_error());
    assert_eq!(sitar_session_free(live), OK);
}
