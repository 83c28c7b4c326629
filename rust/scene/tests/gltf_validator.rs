//! The exported scene of a simulated walk: node counts equal the render plan's, poses are
//! converted to glTF's frame, and the Khronos glTF validator (npm `gltf-validator`, pinned in
//! `tools/npm`) reports no errors.

use glam::DVec3;
use sitar_core::{Convention, DisplayRotation, Session, SessionConfig};
use sitar_scene::{SceneParts, to_glb};
use sitar_sim::Recording;
use support::document;

mod support;

/// A demo walk recorded by the phone logic, with results that make high, medium and low
/// sub-trajectories (so every class material and both marker classes appear).
fn walk(convention: &str) -> Session {
    let recording = Recording::demo(8.0, 30.0, 3).unwrap();
    let config = SessionConfig::from_json(&format!(r#"{{"convention":"{convention}"}}"#)).unwrap();
    let mut session = recording
        .phone_session(config, DisplayRotation::Deg90)
        .unwrap();
    let mut csv = String::from("start,error\n");
    for s in session.subtrajectories() {
        let error = match s.index % 7 {
            0 => 0.15,
            3 => 0.07,
            _ => 0.01,
        };
        csv.push_str(&format!("{},{error}\n", s.start_ns));
    }
    session.load_results(&csv).unwrap();
    session
}

/// The children of the root's group called `name`.
fn group<'a>(doc: &'a serde_json::Value, name: &str) -> Vec<&'a serde_json::Value> {
    let nodes = doc["nodes"].as_array().unwrap();
    let root = &nodes[doc["scenes"][0]["nodes"][0].as_u64().unwrap() as usize];
    let group = root["children"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| &nodes[i.as_u64().unwrap() as usize])
        .find(|n| n["name"] == name)
        .unwrap_or_else(|| panic!("no group {name}"));
    group["children"]
        .as_array()
        .map(|c| {
            c.iter()
                .map(|i| &nodes[i.as_u64().unwrap() as usize])
                .collect()
        })
        .unwrap_or_default()
}

fn translation(node: &serde_json::Value) -> DVec3 {
    let t = node["translation"].as_array().unwrap();
    DVec3::new(
        t[0].as_f64().unwrap(),
        t[1].as_f64().unwrap(),
        t[2].as_f64().unwrap(),
    )
}

#[test]
fn node_counts_equal_the_render_plan_and_poses_are_in_gltf_frame() {
    for convention in ["arcore", "unity"] {
        let session = walk(convention);
        let parts = SceneParts::from_session(&session);
        assert!(
            parts.markers.len() >= 2,
            "{convention}: {:?}",
            parts.markers
        );
        assert!(!parts.plan.frustums.is_empty());
        let doc = document(&to_glb(&parts).unwrap());
        assert_eq!(group(&doc, "trajectory").len(), parts.plan.segments.len());
        assert_eq!(group(&doc, "joints").len(), parts.plan.joints.len());
        assert_eq!(group(&doc, "frustums").len(), parts.plan.frustums.len());
        let markers = group(&doc, "markers");
        assert_eq!(markers.len(), parts.markers.len());
        // glTF frame = ARCore's: Unity's z is negated, ARCore's kept.
        let flip = if convention == "unity" { -1.0 } else { 1.0 };
        for (node, m) in markers.iter().zip(&parts.markers) {
            let expected = DVec3::new(m.position.x, m.position.y, flip * m.position.z);
            assert!((translation(node) - expected).length() < 1e-5);
            assert_eq!(node["extras"]["subtrajectory"], m.subtrajectory);
        }
        let joint = translation(group(&doc, "joints")[5]);
        let p = parts.plan.joints[5].position;
        assert!((joint - DVec3::new(p.x, p.y, flip * p.z)).length() < 1e-5);
        // Segment colours follow the sub-trajectory classes.
        let seg = group(&doc, "trajectory")[0];
        assert_eq!(seg["extras"]["class"], parts.class_of(0).name());
        assert_eq!(parts.convention.name(), convention);
    }
}

#[test]
fn the_same_walk_in_both_conventions_is_the_same_gltf_scene() {
    // A Unity session is the ARCore one reflected; both must land on the same glTF nodes.
    let arcore = SceneParts::from_session(&walk("arcore"));
    let mut unity = arcore.clone();
    unity.convention = Convention::Unity;
    let s = |p: DVec3| Convention::Arcore.convert_vector(p, Convention::Unity);
    let r = |q| Convention::Arcore.convert_rotation(q, Convention::Unity);
    for seg in &mut unity.plan.segments {
        seg.centre = s(seg.centre);
        seg.rotation = r(seg.rotation);
    }
    for j in &mut unity.plan.joints {
        j.position = s(j.position);
    }
    for f in &mut unity.plan.frustums {
        f.pose = Convention::Arcore.convert_pose(f.pose, Convention::Unity);
    }
    for m in &mut unity.markers {
        m.position = s(m.position);
        m.normal = s(m.normal);
        m.rotation = r(m.rotation);
    }
    for p in &mut unity.surface_points {
        p.1 = s(p.1);
    }
    unity.plan.start = unity
        .plan
        .start
        .map(|p| Convention::Arcore.convert_pose(p, Convention::Unity));
    unity.plan.stop = unity
        .plan
        .stop
        .map(|p| Convention::Arcore.convert_pose(p, Convention::Unity));
    let (a, u) = (
        document(&to_glb(&arcore).unwrap()),
        document(&to_glb(&unity).unwrap()),
    );
    let nodes = |d: &serde_json::Value| {
        let mut d = d["nodes"].clone();
        for n in d.as_array_mut().unwrap() {
            n.as_object_mut().unwrap().remove("extras");
        }
        d
    };
    let (na, nu) = (nodes(&a), nodes(&u));
    assert_eq!(na.as_array().unwrap().len(), nu.as_array().unwrap().len());
    for (x, y) in na.as_array().unwrap().iter().zip(nu.as_array().unwrap()) {
        for key in ["translation", "rotation", "scale"] {
            if let (Some(x), Some(y)) = (x[key].as_array(), y[key].as_array()) {
                for (p, q) in x.iter().zip(y) {
                    assert!(
                        (p.as_f64().unwrap() - q.as_f64().unwrap()).abs() < 1e-6,
                        "{key}: {x:?} vs {y:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn an_empty_session_is_a_clear_error() {
    let parts = SceneParts::from_session(&Session::new(SessionConfig::default()));
    let err = to_glb(&parts).unwrap_err();
    assert!(err.to_string().contains("no trajectory"), "{err}");
}

#[test]
fn the_khronos_validator_finds_no_errors() {
    // Before results: every sub-trajectory unknown, no markers.
    let mut bare = SceneParts::from_session(&walk("arcore"));
    bare.markers.clear();
    bare.classes.clear();
    let glb = |convention: &str| to_glb(&SceneParts::from_session(&walk(convention))).unwrap();
    support::assert_khronos_clean(&[
        ("arcore", glb("arcore")),
        ("unity", glb("unity")),
        ("bare", to_glb(&bare).unwrap()),
    ]);
}
