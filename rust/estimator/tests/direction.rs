//! The APE by direction (`direction_components`) against the independent numpy/scipy
//! implementation of `scripts/golden/make_direction_goldens.py` (tests/data/gt.txt and a
//! perturbed estimate, gravity along z and along y), to 1e-9.

use std::path::{Path, PathBuf};

use serde_json::Value;
use sitar_estimator::{
    DirectionRelation, GravityAxis, ape_by_direction, direction_components, read_tum,
};

const TOLERANCE: f64 = 1e-9;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn direction_components_match_numpy() {
    let golden: Value =
        serde_json::from_str(&std::fs::read_to_string(data("golden_direction.json")).unwrap())
            .unwrap();
    let reference = read_tum(&data("gt.txt")).unwrap();
    let estimate = read_tum(&data("direction/est.txt")).unwrap();
    assert_eq!(reference.stamps, estimate.stamps);
    for (key, axis) in [("z", GravityAxis::Z), ("y", GravityAxis::Y)] {
        let got = direction_components(&reference, &estimate, axis).unwrap();
        let want = &golden[key];
        let mut worst = 0.0f64;
        for name in [
            "along_track",
            "cross_track",
            "vertical",
            "yaw_deg",
            "roll_pitch_deg",
        ] {
            let expected = floats(&want[name]);
            assert_eq!(expected.len(), got.len());
            for (i, (c, w)) in got.iter().zip(&expected).enumerate() {
                let g = match name {
                    "along_track" => c.along_track,
                    "cross_track" => c.cross_track,
                    "vertical" => c.vertical,
                    "yaw_deg" => c.yaw_deg,
                    _ => c.roll_pitch_deg,
                };
                worst = worst.max((g - w).abs());
                assert!(
                    (g - w).abs() <= TOLERANCE,
                    "{key} {name}[{i}]: sitar {g}, numpy {w}"
                );
            }
            // The relation's values are the absolute values.
            let relation: DirectionRelation = name.parse().unwrap();
            let errors = ape_by_direction(&reference, &estimate, relation, axis).unwrap();
            for (e, w) in errors.errors.iter().zip(&expected) {
                assert!((e - w.abs()).abs() <= TOLERANCE);
            }
        }
        eprintln!("gravity {key}: largest difference from numpy {worst:e}");
    }
}
