//! sitar-core geometry against independent numpy/scipy references
//! (`tests/golden/make_golden.py` wrote the CSV files).
#![allow(missing_docs)]

use glam::{DQuat, DVec3};
use sitar_core::{
    Convention, DepthImage, DisplayRotation, Error, Intrinsics, Pose, sample_surface,
    warning_sign_rotation,
};

fn rows(name: &str) -> Vec<Vec<String>> {
    let path = format!("{}/tests/golden/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect()
}

fn f(s: &str) -> f64 {
    s.parse().unwrap()
}

fn v3(r: &[String], i: usize) -> DVec3 {
    DVec3::new(f(&r[i]), f(&r[i + 1]), f(&r[i + 2]))
}

fn same_rotation(a: DQuat, b: DQuat) -> bool {
    a.dot(b).abs() > 1.0 - 1e-12
}

#[test]
fn warning_sign_rotation_matches_unity_look_rotation_via_scipy() {
    let rows = rows("look_rotation.csv");
    assert!(rows.len() >= 30);
    for r in rows {
        let n_unity = v3(&r, 0);
        let q_unity = DQuat::from_xyzw(f(&r[3]), f(&r[4]), f(&r[5]), f(&r[6]));
        let n_arcore = v3(&r, 7);
        let q_arcore = DQuat::from_xyzw(f(&r[10]), f(&r[11]), f(&r[12]), f(&r[13]));
        assert!(
            same_rotation(warning_sign_rotation(n_unity, Convention::Unity), q_unity),
            "{r:?}"
        );
        assert!(
            same_rotation(
                warning_sign_rotation(n_arcore, Convention::Arcore),
                q_arcore
            ),
            "{r:?}"
        );
    }
}

#[test]
fn depth_samples_match_an_independent_numpy_implementation() {
    let rows = rows("depth_sample.csv");
    assert_eq!(rows.len(), 60);
    let (width, height) = (256u32, 192u32);
    let mut checked_valid = 0;
    for r in rows {
        let (x, y): (u32, u32) = (r[1].parse().unwrap(), r[2].parse().unwrap());
        let k = Intrinsics {
            fx: f(&r[3]),
            fy: f(&r[4]),
            cx: f(&r[5]),
            cy: f(&r[6]),
        };
        let convention = if r[7] == "unity" {
            Convention::Unity
        } else {
            Convention::Arcore
        };
        let rotation = DisplayRotation::from_degrees(r[8].parse().unwrap()).unwrap();
        let pose = Pose::new(
            v3(&r, 9),
            DQuat::from_xyzw(f(&r[12]), f(&r[13]), f(&r[14]), f(&r[15])),
        );
        let window: Vec<u16> = r[16].split(' ').map(|d| d.parse().unwrap()).collect();
        // The window in a zero image (with a padded stride), clipped at the borders.
        let stride = width as usize + 3;
        let mut data = vec![0u16; stride * height as usize];
        for j in 0..5i64 {
            for i in 0..5i64 {
                let (u, v) = (i64::from(x) + i - 2, i64::from(y) + j - 2);
                if (0..i64::from(width)).contains(&u) && (0..i64::from(height)).contains(&v) {
                    data[v as usize * stride + u as usize] = window[(j * 5 + i) as usize];
                }
            }
        }
        let image = DepthImage::new(&data, width, height, 2 * stride as u32).unwrap();
        let got = sample_surface(&image, &k, rotation, convention, &pose, Some((x, y)));
        match (r[17].as_str(), got) {
            ("valid", Ok(s)) => {
                let close = |a: DVec3, b: DVec3| (a - b).length() < 1e-9;
                assert!(
                    close(s.camera_point, v3(&r, 18)),
                    "case {}: {} vs {}",
                    r[0],
                    s.camera_point,
                    v3(&r, 18)
                );
                assert!(close(s.camera_normal, v3(&r, 21)), "case {}", r[0]);
                assert!(close(s.point, v3(&r, 24)), "case {}", r[0]);
                assert!(close(s.normal, v3(&r, 27)), "case {}", r[0]);
                checked_valid += 1;
            }
            (code, Err(Error::InvalidDepth(why))) => assert_eq!(why.code(), code, "case {}", r[0]),
            (code, other) => panic!("case {}: expected {code}, got {other:?}", r[0]),
        }
    }
    assert_eq!(checked_valid, 57);
}
