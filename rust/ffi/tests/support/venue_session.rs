//! A stopped session through the C ABI with three markers, one full observation of the
//! venue's anchor `hall` and a venue map of 50 high surface cells: what the venue tests and
//! the guide benchmark use.

use std::ffi::CString;

use sitar::{
    sitar_session_anchor, sitar_session_depth, sitar_session_frame, sitar_session_load_results,
    sitar_session_load_venue, sitar_session_new, sitar_session_start, sitar_session_stop,
    SitarIntrinsics, SitarPose,
};

pub const DT: i64 = 33_333_333;

/// The camera walks along +x at 0.1 m per frame, facing a wall 2 m ahead.
pub fn camera(i: i64) -> SitarPose {
    SitarPose {
        px: 0.1 * i as f64,
        py: 1.5,
        qw: 1.0,
        ..SitarPose::default()
    }
}

/// The anchor image on the floor 2 m ahead of the start, its +X along world +X.
pub fn anchor_pose() -> SitarPose {
    SitarPose {
        pz: 2.0,
        qw: 1.0,
        ..SitarPose::default()
    }
}

/// A map of `n` cells (every one a high surface cell when `all_high`, else alternately
/// path and surface) on a 10-wide grid of 0.25 m, 1 m up.
pub fn map_json(n: u32, all_high: bool) -> String {
    let cells: Vec<String> = (0..n)
        .map(|i| {
            let surface = all_high || i % 2 == 0;
            format!(
                r#"{{"center":[{},1.0,{}],"kind":"{}","sessions":2,"subtrajectories":3,"error_m":{},"class":"{}","directions":[0,0,0,0,0,0,0,3]}}"#,
                0.25 * f64::from(i % 10),
                0.25 * f64::from(i / 10),
                if surface { "surface" } else { "path" },
                if i % 3 == 0 || all_high { 0.2 } else { 0.03 },
                if i % 3 == 0 || all_high { "high" } else { "low" },
            )
        })
        .collect();
    format!(
        r#"{{"id":"v0123456789abcdef","name":"Hall","anchor":"hall","cell_m":0.25,"convention":"unity","unit":"m","sessions":[{{"id":"s1","aligned":true,"observations":3,"position_spread_m":0.01,"heading_spread_deg":0.3,"subtrajectories":6}}],"cells":[{}]}}"#,
        cells.join(",")
    )
}

/// Records 60 frames with depth, one full anchor observation, stops, loads results giving
/// markers at sub-trajectories 0, 2 and 3, and loads `map`. Returns the handle.
pub fn venue_session(map: &str) -> u64 {
    let mut h = 0u64;
    assert_eq!(sitar_session_new(c"{}".as_ptr(), &mut h), 0);
    assert_eq!(sitar_session_start(h, 1_000, &camera(0)), 0);
    assert_eq!(
        sitar_session_anchor(h, 1_500, c"hall".as_ptr(), &anchor_pose(), 2),
        0
    );
    let wall = vec![2000u16; 256 * 192];
    let k = SitarIntrinsics {
        fx: 211.0,
        fy: 211.0,
        cx: 128.0,
        cy: 96.0,
    };
    let mut flags = 0u32;
    for i in 1..=60 {
        assert_eq!(
            sitar_session_frame(h, 1_000 + i * DT, &camera(i), &mut flags),
            0
        );
        if flags & 1 != 0 {
            assert_eq!(
                sitar_session_depth(h, wall.as_ptr(), 256, 192, 512, &k, 0),
                0
            );
        }
    }
    let mut summary = sitar::SitarSummary::default();
    assert_eq!(
        sitar_session_stop(h, 1_000 + 61 * DT, &camera(61), &mut summary),
        0
    );
    let errors = [0.12, 0.03, 0.3, 0.11, 0.02, 0.06];
    let csv: String = std::iter::once("start,error\n".to_owned())
        .chain(
            errors
                .iter()
                .enumerate()
                .map(|(k, e)| format!("{},{e}\n", 1_000 + 10 * k as i64 * DT)),
        )
        .collect();
    let csv = CString::new(csv).unwrap();
    assert_eq!(sitar_session_load_results(h, csv.as_ptr()), 0);
    let map = CString::new(map).unwrap();
    assert_eq!(sitar_session_load_venue(h, map.as_ptr()), 0);
    h
}
