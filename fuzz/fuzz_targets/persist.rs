//! sitar-core's session folder reader (`Session::load`), then every call on what it loaded.
//! The input is the folder's files joined by a line `%%`: config.json, session.json,
//! trajectory.txt, subtrajectories.csv and, when there is a fifth part, results.json.
#![no_main]

use glam::{DQuat, DVec3};
use libfuzzer_sys::fuzz_target;
use sitar_core::{DepthImage, DisplayRotation, Intrinsics, Pose, Session};

const FILES: [&str; 5] = [
    "config.json",
    "session.json",
    "trajectory.txt",
    "subtrajectories.csv",
    "results.json",
];

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("sitar-fuzz-persist-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp folder");
    let mut parts = text.split("\n%%\n");
    for name in FILES {
        let path = dir.join(name);
        match parts.next() {
            Some(part) => std::fs::write(&path, part).expect("temp file"),
            None => {
                let _ = std::fs::remove_file(&path);
            }
        }
    }
    let Ok(mut s) = Session::load(&dir) else {
        return;
    };
    let _ = s.markers();
    let _ = s.render_plan();
    let _ = s.subtrajectory_errors();
    let _ = s.summary();
    let _ = s.results_unreliable();
    let _ = s.trajectory_tum();
    for k in 0..3 {
        let _ = s.subtrajectory_class(k);
    }
    if let Some(last) = s.logged().last().map(|l| l.t_ns) {
        let _ = s.error_at(last);
    }
    // Go on recording where the folder left off.
    let wall = vec![2000u16; 16 * 12];
    let image = DepthImage::new(&wall, 16, 12, 32).expect("valid image");
    let k = Intrinsics {
        fx: 13.0,
        fy: 13.0,
        cx: 7.5,
        cy: 5.5,
    };
    let start = s.logged().last().map_or(0, |l| l.t_ns);
    for i in 1..=12i64 {
        let t = start.saturating_add(i * 33_333_333);
        let pose = Pose::new(DVec3::new(0.1 * i as f64, 1.5, 0.0), DQuat::IDENTITY);
        if let Ok(flags) = s.frame(t, pose)
            && flags.is_midpoint()
        {
            let _ = s.depth(&image, &k, DisplayRotation::Deg90);
        }
    }
    let _ = s.stop(start.saturating_add(13 * 33_333_333), Pose::IDENTITY);
    let _ = s.markers();
    let _ = s.render_plan();
    let _ = s.summary();
});
