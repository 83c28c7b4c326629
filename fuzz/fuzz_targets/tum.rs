//! Trajectory text parsers: sitar-estimator's TUM, EuRoC CSV and KITTI readers,
//! sitar-core's integer-nanosecond TUM reader, and the server's trial reader (its TUM parse
//! plus the checks a trial upload gets: at least 2 poses, positions finite and within 1e6 m).
//! Whatever parses must write back and parse again to the same trajectory (quaternions to 1e-12: reading renormalises them).
#![no_main]

use libfuzzer_sys::fuzz_target;
use sitar_estimator::{parse_euroc_csv, parse_kitti, parse_tum, write_tum};

fuzz_target!(|data: &[u8]| {
    // The server reads trial bytes, UTF-8 or not.
    if let Ok(poses) = sitar_server::fuzzing::trial(data) {
        assert!(poses >= 2);
    }
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(trajectory) = parse_tum(text, "fuzz.txt") {
        let mut out = Vec::new();
        write_tum(&trajectory, &mut out).expect("writing to a Vec cannot fail");
        let again = std::str::from_utf8(&out).expect("write_tum writes UTF-8");
        let back = parse_tum(again, "again.txt").expect("written TUM parses");
        // Stamps and positions are exact; reading normalises the quaternions again, which
        // may move their last bit.
        assert_eq!(
            (&back.stamps, &back.positions, back.time_unit),
            (
                &trajectory.stamps,
                &trajectory.positions,
                trajectory.time_unit
            )
        );
        for (a, b) in back.orientations.iter().zip(&trajectory.orientations) {
            assert!((*a - *b).length() < 1e-12, "{a} vs {b}");
        }
    }
    let _ = parse_euroc_csv(text, "fuzz.csv");
    let _ = parse_kitti(text, "fuzz.txt");
    if let Ok(poses) = sitar_core::parse_tum_ns(text, "fuzz.txt") {
        let again = sitar_core::to_tum(poses.iter().map(|(t, p)| (*t, p)));
        assert_eq!(
            sitar_core::parse_tum_ns(&again, "again.txt").ok(),
            Some(poses)
        );
    }
});
