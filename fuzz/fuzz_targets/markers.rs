//! sitar-core's marker selection and warning-sign orientation with any candidates (positions
//! far out, NaN, infinite) and any config values (`select_markers` takes the config as given).
#![no_main]

use arbitrary::Arbitrary;
use glam::DVec3;
use libfuzzer_sys::fuzz_target;
use sitar_core::{
    Convention, MarkerCandidate, SessionConfig, select_markers, warning_sign_rotation,
};

#[derive(Arbitrary, Debug)]
struct Candidate {
    subtrajectory: u32,
    position: [f64; 3],
    normal: [f64; 3],
    error_m: f64,
}

#[derive(Arbitrary, Debug)]
struct Input {
    arcore: bool,
    dedup_radius_m: f64,
    max_regions: u8,
    thresholds_m: Vec<f64>,
    high_threshold_m: f64,
    candidates: Vec<Candidate>,
}

fuzz_target!(|input: Input| {
    let convention = if input.arcore {
        Convention::Arcore
    } else {
        Convention::Unity
    };
    let config = SessionConfig {
        convention,
        dedup_radius_m: input.dedup_radius_m,
        max_regions: usize::from(input.max_regions),
        thresholds_m: input.thresholds_m,
        high_threshold_m: input.high_threshold_m,
        ..SessionConfig::default()
    };
    let candidates: Vec<MarkerCandidate> = input
        .candidates
        .iter()
        .map(|c| MarkerCandidate {
            subtrajectory: c.subtrajectory,
            position: DVec3::from_array(c.position),
            normal: DVec3::from_array(c.normal),
            error_m: c.error_m,
        })
        .collect();
    let markers = select_markers(&candidates, &config);
    assert!(markers.len() <= config.max_regions);
    for c in &candidates {
        let _ = warning_sign_rotation(c.normal, convention);
    }
});
