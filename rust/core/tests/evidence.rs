//! Camera images at midpoints: thumbnails, properties, evidence and causes through `Session`.
#![allow(missing_docs)]

use glam::{DQuat, DVec3};
use sitar_core::{
    Causes, DepthImage, DisplayRotation, Error, Intrinsics, LumaImage, Pose, Session, SessionConfig,
};

const DT: i64 = 33_333_333;

fn pose(i: i64) -> Pose {
    Pose::new(DVec3::new(0.01 * i as f64, 1.5, 0.0), DQuat::IDENTITY)
}

/// 64×48 with a bright top-left quadrant and scattered dots (texture).
fn textured() -> Vec<u8> {
    (0..64 * 48)
        .map(|i| {
            let (x, y) = (i % 64, i / 64);
            if x % 7 == 3 && y % 5 == 2 {
                250
            } else if x < 32 && y < 24 {
                160
            } else {
                60
            }
        })
        .collect()
}

fn recording(config: &str) -> Session {
    let mut s = Session::new(SessionConfig::from_json(config).unwrap());
    s.start(0, pose(0)).unwrap();
    s
}

fn to_midpoint(s: &mut Session, i: &mut i64) {
    loop {
        *i += 1;
        if s.frame(*i * DT, pose(*i)).unwrap().is_midpoint() {
            return;
        }
    }
}

fn decode(jpeg: &[u8]) -> (Vec<u8>, u16, u16) {
    let mut d = jpeg_decoder::Decoder::new(jpeg);
    let pixels = d.decode().unwrap();
    let info = d.info().unwrap();
    (pixels, info.width, info.height)
}

#[test]
fn every_rotation_gives_a_display_oriented_thumbnail_and_equal_properties() {
    let plane = textured();
    let image = LumaImage::new(&plane, 64, 48, 64).unwrap();
    let mut s = recording(r#"{"thumbnail_px": 32}"#);
    let mut i = 0;
    let rotations = [0, 90, 180, 270];
    for deg in rotations {
        to_midpoint(&mut s, &mut i);
        s.image(&image, DisplayRotation::from_degrees(deg).unwrap())
            .unwrap();
    }
    let inputs = s.midpoint_inputs();
    for (k, deg) in rotations.iter().enumerate() {
        let (pixels, w, h) = decode(s.thumbnail(k as u32).unwrap());
        let expected = if deg % 180 == 0 { (32, 24) } else { (24, 32) };
        assert_eq!((w, h), expected, "{deg}°");
        assert_eq!(inputs[k].thumbnail_size, (u32::from(w), u32::from(h)));
        // The bright sensor quadrant (top-left) lands where a clockwise turn puts it.
        let at = |x: usize, y: usize| pixels[y * w as usize + x];
        let (right, bottom) = (w as usize - 3, h as usize - 3);
        let bright_corner = match deg {
            0 => at(2, 2),
            90 => at(right, 2),
            180 => at(right, bottom),
            _ => at(2, bottom),
        };
        let dark_corner = match deg {
            0 => at(right, bottom),
            90 => at(2, bottom),
            180 => at(2, 2),
            _ => at(right, 2),
        };
        assert!(
            bright_corner > dark_corner + 50,
            "{deg}°: {bright_corner} vs {dark_corner}"
        );
        assert_eq!(inputs[k].image, inputs[0].image);
    }
}

#[test]
fn image_calls_outside_a_recording_are_state_errors() {
    let plane = textured();
    let image = LumaImage::new(&plane, 64, 48, 64).unwrap();
    let mut s = Session::new(SessionConfig::default());
    assert!(matches!(
        s.image(&image, DisplayRotation::Deg0),
        Err(Error::InvalidState(_))
    ));
    s.start(0, pose(0)).unwrap();
    // Before the first midpoint: kept for sub-trajectory 0.
    s.image(&image, DisplayRotation::Deg90).unwrap();
    let mut i = 0;
    to_midpoint(&mut s, &mut i);
    assert_eq!(s.midpoint_inputs()[0].thumbnail_size, (48, 64));
    s.image(&image, DisplayRotation::Deg0).unwrap();
    assert_eq!(s.midpoint_inputs()[0].thumbnail_size, (64, 48));
    s.stop(100 * DT, pose(100)).unwrap();
    assert!(matches!(
        s.image(&image, DisplayRotation::Deg0),
        Err(Error::InvalidState(_))
    ));
}

#[test]
fn images_false_keeps_no_image() {
    let plane = textured();
    let image = LumaImage::new(&plane, 64, 48, 64).unwrap();
    let mut s = recording(r#"{"images": false}"#);
    let mut i = 0;
    to_midpoint(&mut s, &mut i);
    s.image(&image, DisplayRotation::Deg0).unwrap();
    assert_eq!(s.thumbnail(0), None);
    assert_eq!(s.midpoint_inputs()[0].image, None);
    let err = SessionConfig::from_json(r#"{"thumbnail_px": 4}"#).unwrap_err();
    assert!(err.to_string().contains("thumbnail_px"), "{err}");
    assert!(SessionConfig::from_json(r#"{"images": "yes"}"#).is_err());
}

#[test]
fn evidence_names_plain_views_glass_and_fast_turns() {
    let rich = textured();
    let plain = vec![128u8; 64 * 48];
    let wall = vec![1500u16; 32 * 24];
    let mut glass = wall.clone();
    for y in 8..16 {
        for x in 12..20 {
            glass[y * 32 + x] = 0;
        }
    }
    let k = Intrinsics {
        fx: 30.0,
        fy: 30.0,
        cx: 16.0,
        cy: 12.0,
    };
    let mut s = recording("{}");
    let mut i = 0;
    // 0: textured, 1: plain wall, 2: textured but glass (depth hole), 3: textured.
    for (k_sub, (luma, depth)) in [
        (&rich, &wall),
        (&plain, &wall),
        (&rich, &glass),
        (&rich, &wall),
    ]
    .into_iter()
    .enumerate()
    {
        to_midpoint(&mut s, &mut i);
        let image = LumaImage::new(luma, 64, 48, 64).unwrap();
        s.image(&image, DisplayRotation::Deg0).unwrap();
        let d = DepthImage::new(depth, 32, 24, 64).unwrap();
        let r = s.depth(&d, &k, DisplayRotation::Deg0);
        assert_eq!(r.is_ok(), k_sub != 2, "{k_sub}: {r:?}");
    }
    s.stop(i * DT + DT, pose(i + 1)).unwrap();
    let ev = s.evidence();
    assert_eq!(ev.len(), 4);
    assert!(ev[0].causes.is_empty(), "{}", ev[0].causes);
    assert_eq!(ev[1].causes, Causes::LOW_TEXTURE);
    assert_eq!(ev[2].causes, Causes::NO_DEPTH);
    assert_eq!(ev[2].depth.valid_share, 0.0);
    assert_eq!(ev[0].depth.valid_share, 1.0);
    assert!((ev[0].depth.distance_m - 1.5).abs() < 1e-9);
    // 0.01 m per frame at 30 fps.
    assert!(
        (ev[0].motion.linear_speed_m_s - 0.3).abs() < 1e-6,
        "{:?}",
        ev[0].motion
    );
    assert_eq!(ev[0].motion.angular_speed_deg_s, 0.0);
    assert_eq!(s.evidence_of(1).unwrap(), ev[1]);
    assert!(s.evidence_of(9).unwrap_err().to_string().contains("9"));

    // The session folder keeps the thumbnails and the properties table.
    let dir = tempfile::tempdir().unwrap();
    s.save(dir.path()).unwrap();
    assert!(dir.path().join("thumbnails/1.jpg").exists());
    let table = std::fs::read_to_string(dir.path().join("evidence.csv")).unwrap();
    assert!(
        table.lines().nth(2).unwrap().ends_with(",low_texture"),
        "{table}"
    );
    let back = Session::load(dir.path()).unwrap();
    assert_eq!(back, s);
    assert_eq!(back.evidence(), ev);
}

#[test]
fn turning_fast_is_fast_motion() {
    let mut s = Session::new(SessionConfig::default());
    s.start(0, Pose::new(DVec3::ZERO, DQuat::IDENTITY)).unwrap();
    // 20 frames slow (0.3°/frame = 9°/s), 10 frames fast (5°/frame = 150°/s).
    let mut angle = 0.0f64;
    for i in 1..=30 {
        angle += if i <= 20 { 0.3 } else { 5.0 };
        let p = Pose::new(DVec3::ZERO, DQuat::from_rotation_y(angle.to_radians()));
        s.frame(i * DT, p).unwrap();
    }
    let ev = s.evidence();
    assert!(
        (ev[0].motion.angular_speed_deg_s - 9.0).abs() < 1e-3,
        "{:?}",
        ev[0].motion
    );
    assert!((ev[2].motion.angular_speed_deg_s - 150.0).abs() < 1e-3);
    assert!(!ev[0].causes.contains(Causes::FAST_MOTION));
    assert!(ev[2].causes.contains(Causes::FAST_MOTION));
}
