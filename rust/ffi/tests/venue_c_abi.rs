//! `sitar_session_anchor`, `sitar_session_load_venue`, `sitar_session_venue_cells` and
//! `sitar_session_guide` through their C entry points: the argument checks and codes issue 25
//! fixes, the array convention, agreement with `sitar-core`, and no allocation per call.

use std::ffi::CString;

use sitar::{
    sitar_session_anchor, sitar_session_free, sitar_session_guide, sitar_session_load_venue,
    sitar_session_markers, sitar_session_new, sitar_session_start, sitar_session_venue_cells,
    SitarGuide, SitarMarker, SitarPose, SitarVenueCell,
};

#[path = "../../core/tests/support/counting_allocator.rs"]
mod counting_allocator;
#[path = "support/venue_session.rs"]
mod venue_session;

use venue_session::{anchor_pose, camera, map_json, venue_session};

#[path = "support/c_abi.rs"]
mod c_abi;

use c_abi::{
    last_error, ERR_BUFFER_TOO_SMALL, ERR_INVALID_ARGUMENT, ERR_INVALID_STATE, ERR_NULL, ERR_PARSE,
    OK,
};

#[test]
fn anchor_arguments_and_states_are_checked() {
    let mut h = 0u64;
    assert_eq!(sitar_session_new(c"{}".as_ptr(), &mut h), OK);
    let p = anchor_pose();
    assert_eq!(
        sitar_session_anchor(h, 0, c"hall".as_ptr(), &p, 2),
        ERR_INVALID_STATE
    );
    assert!(last_error().contains("not recording"), "{}", last_error());
    assert_eq!(sitar_session_start(h, 0, &camera(0)), OK);
    let long = CString::new("x".repeat(65)).unwrap();
    let exactly = CString::new("x".repeat(64)).unwrap();
    assert_eq!(sitar_session_anchor(h, 1, exactly.as_ptr(), &p, 2), OK);
    for (id, tracking, pose, needle) in [
        (c"".as_ptr(), 2, p, "anchor_id"),
        (long.as_ptr(), 2, p, "anchor_id"),
        (c"hall".as_ptr(), 3, p, "tracking"),
        (c"hall".as_ptr(), -1, p, "tracking"),
        (c"hall".as_ptr(), 2, SitarPose { px: f64::NAN, ..p }, "pose"),
        (
            c"hall".as_ptr(),
            2,
            SitarPose {
                qw: f64::INFINITY,
                ..p
            },
            "pose",
        ),
    ] {
        assert_eq!(
            sitar_session_anchor(h, 1, id, &pose, tracking),
            ERR_INVALID_ARGUMENT
        );
        assert!(last_error().contains(needle), "{needle}: {}", last_error());
    }
    assert_eq!(
        sitar_session_anchor(h, 1, std::ptr::null(), &p, 2),
        ERR_NULL
    );
    assert_eq!(
        sitar_session_anchor(h, 1, c"hall".as_ptr(), std::ptr::null(), 2),
        ERR_NULL
    );
    let mut s = sitar::SitarSummary::default();
    assert_eq!(sitar::sitar_session_stop(h, 10, &camera(1), &mut s), OK);
    assert_eq!(
        sitar_session_anchor(h, 11, c"hall".as_ptr(), &p, 2),
        ERR_INVALID_STATE
    );
    assert_eq!(sitar_session_free(h), OK);
}

#[test]
fn venue_cells_need_a_venue_and_a_full_observation() {
    let mut h = 0u64;
    assert_eq!(sitar_session_new(c"{}".as_ptr(), &mut h), OK);
    assert_eq!(sitar_session_start(h, 0, &camera(0)), OK);
    let mut len = 99usize;
    assert_eq!(
        sitar_session_venue_cells(h, std::ptr::null_mut(), 0, &mut len),
        ERR_INVALID_STATE
    );
    assert_eq!(
        sitar_session_load_venue(h, c"{\"id\":3}".as_ptr()),
        ERR_PARSE
    );
    assert!(last_error().contains("id"), "{}", last_error());
    let map = CString::new(map_json(50, false)).unwrap();
    assert_eq!(sitar_session_load_venue(h, map.as_ptr()), OK);
    assert_eq!(
        sitar_session_venue_cells(h, std::ptr::null_mut(), 0, &mut len),
        ERR_INVALID_STATE
    );
    assert_eq!(
        sitar_session_anchor(h, 1, c"hall".as_ptr(), &anchor_pose(), 1),
        OK
    );
    assert_eq!(
        sitar_session_venue_cells(h, std::ptr::null_mut(), 0, &mut len),
        ERR_INVALID_STATE
    );
    assert!(last_error().contains("full tracking"), "{}", last_error());
    assert_eq!(
        sitar_session_anchor(h, 2, c"hall".as_ptr(), &anchor_pose(), 2),
        OK
    );
    // Size query, too small (nothing written, count set), then the whole list.
    assert_eq!(
        sitar_session_venue_cells(h, std::ptr::null_mut(), 0, &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    assert_eq!(len, 50);
    let mut cells = vec![SitarVenueCell::default(); 50];
    len = 0;
    assert_eq!(
        sitar_session_venue_cells(h, cells.as_mut_ptr(), 49, &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    assert_eq!(len, 50);
    assert!(cells.iter().all(|c| *c == SitarVenueCell::default()));
    assert_eq!(
        sitar_session_venue_cells(h, cells.as_mut_ptr(), 50, &mut len),
        OK
    );
    // The anchor is 2 m along +z with no turn: cell 13 at venue (0.75, 1, 0.25) is there.
    let c = cells[13];
    assert_eq!((c.px, c.py, c.pz), (0.75, 1.0, 2.25));
    assert_eq!((c.kind, c.error_class, c.sessions), (0, 1, 2));
    assert_eq!(
        (cells[0].kind, cells[0].error_class, cells[0].error_m),
        (1, 3, 0.2)
    );
    assert_eq!(
        sitar_session_venue_cells(h, std::ptr::null_mut(), 5, &mut len),
        ERR_NULL
    );
    assert_eq!(sitar_session_free(h), OK);
}

#[test]
fn guide_lists_markers_then_high_surface_cells_as_core_computes_them() {
    let h = venue_session(&map_json(50, false));
    let mut markers = [SitarMarker::default(); 8];
    let mut n_markers = 0usize;
    assert_eq!(
        sitar_session_markers(h, markers.as_mut_ptr(), 8, &mut n_markers),
        OK
    );
    assert_eq!(n_markers, 3);
    let mut cells = vec![SitarVenueCell::default(); 50];
    let mut n_cells = 0usize;
    assert_eq!(
        sitar_session_venue_cells(h, cells.as_mut_ptr(), 50, &mut n_cells),
        OK
    );
    let targets: Vec<[f64; 3]> = markers[..3]
        .iter()
        .map(|m| [m.px, m.py, m.pz])
        .chain(
            cells
                .iter()
                .filter(|c| c.kind == 1 && c.error_class == 3)
                .map(|c| [c.px, c.py, c.pz]),
        )
        .collect();
    assert_eq!(targets.len(), 3 + 9); // cells 0, 6, 12, … (i % 6 == 0) are high surface ones

    let cam = camera(30);
    let guide = |out: *mut SitarGuide, capacity: usize, len: &mut usize| {
        sitar_session_guide(h, &cam, 60.0, 1080, 1920, 40.0, out, capacity, len)
    };
    let mut len = 0usize;
    assert_eq!(
        guide(std::ptr::null_mut(), 0, &mut len),
        ERR_BUFFER_TOO_SMALL
    );
    assert_eq!(len, targets.len());
    let mut out = vec![SitarGuide::default(); 16];
    assert_eq!(guide(out.as_mut_ptr(), 16, &mut len), OK);
    let view = sitar_core::ScreenView::new(
        cam.to_core(),
        sitar_core::Convention::Unity,
        60.0,
        1080,
        1920,
        40.0,
    )
    .unwrap();
    for (g, t) in out.iter().zip(&targets) {
        let expected = view.guide(glam::DVec3::from_array(*t));
        assert_eq!(*g, SitarGuide::from(expected));
    }
    // The camera at x = 3 faces +z: marker 0 at x = 0.5 on the wall 2 m ahead is off to the
    // left, the anchor cells at z ≈ 2 are ahead.
    assert_eq!((out[0].on_screen, out[0].x_px < 540.0), (0, true));
    for (vfov, w, hh, margin, needle) in [
        (0.0, 1080, 1920, 40.0, "vfov_deg"),
        (f64::NAN, 1080, 1920, 40.0, "vfov_deg"),
        (60.0, 0, 1920, 40.0, "width_px"),
        (60.0, 1080, 1920, 600.0, "margin_px"),
    ] {
        assert_eq!(
            sitar_session_guide(h, &cam, vfov, w, hh, margin, out.as_mut_ptr(), 16, &mut len),
            ERR_INVALID_ARGUMENT
        );
        assert!(last_error().contains(needle), "{needle}: {}", last_error());
    }
    assert_eq!(sitar_session_free(h), OK);
}

#[test]
fn guide_and_venue_cells_do_not_allocate() {
    let h = venue_session(&map_json(50, true));
    let mut guides = vec![SitarGuide::default(); 64];
    let mut cells = vec![SitarVenueCell::default(); 64];
    let (mut n_guides, mut n_cells) = (0usize, 0usize);
    let cam = camera(30);
    // One call each first: the thread's last-error buffer and logging set up once.
    sitar_session_guide(
        h,
        &cam,
        60.0,
        1080,
        1920,
        40.0,
        guides.as_mut_ptr(),
        1,
        &mut n_guides,
    );
    let guide = |cam: &SitarPose, capacity: usize, n: &mut usize, out: &mut [SitarGuide]| {
        sitar_session_guide(
            h,
            cam,
            60.0,
            1080,
            1920,
            40.0,
            out.as_mut_ptr(),
            capacity,
            n,
        )
    };
    let before = counting_allocator::allocations();
    for i in 0..1_000 {
        let cam = SitarPose {
            px: 0.01 * f64::from(i),
            ..cam
        };
        assert_eq!(guide(&cam, 64, &mut n_guides, &mut guides), OK);
        assert_eq!(
            sitar_session_venue_cells(h, cells.as_mut_ptr(), 64, &mut n_cells),
            OK
        );
        // Too small: the count is set, still nothing allocated.
        assert_eq!(
            guide(&cam, 2, &mut n_guides, &mut guides),
            ERR_BUFFER_TOO_SMALL
        );
    }
    let after = counting_allocator::allocations();
    assert_eq!((n_guides, n_cells), (53, 50));
    assert_eq!(after - before, 0, "guide / venue_cells allocated");
    assert_eq!(sitar_session_free(h), OK);
}
