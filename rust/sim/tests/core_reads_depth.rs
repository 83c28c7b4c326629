//! The depth renderer speaks sitar-core's language: core's surface sampling of a rendered
//! image (ARCore convention, display rotation 0) lands on the surface the simulator hits.

use glam::DVec3;
use sitar_core::{Convention, DepthImage, DisplayRotation, Pose, sample_surface};
use sitar_sim::{DepthCamera, Recording};

#[test]
fn core_samples_the_surface_the_camera_faces() {
    let rec = Recording::demo(15.0, 30.0, 4).unwrap();
    // Glass with full depth: this checks the geometry (the phone's glass speckle has its own test).
    let camera = DepthCamera {
        glass_valid_share: 1.0,
        ..DepthCamera::phone()
    };
    let k = camera.intrinsics;
    let gt = &rec.walk().ground_truth;
    let mut angles = Vec::new();
    for f in (5..gt.len()).step_by(10) {
        let (position, rotation) = (gt.positions[f], gt.orientations[f]);
        let depth = rec.room().render_depth_mm(position, rotation, &camera);
        let image = DepthImage::new(&depth, camera.width, camera.height, camera.width * 2).unwrap();
        let pose = Pose { position, rotation };
        let Ok(sample) = sample_surface(
            &image,
            &k,
            DisplayRotation::Deg0,
            Convention::Arcore,
            &pose,
            None,
        ) else {
            continue; // e.g. a corner inside the normal window
        };
        let hit = rec.room().raycast(position, rotation * -DVec3::Z).unwrap();
        // Millimetre depth quantisation: the point is within a few millimetres of the hit.
        assert!(
            sample.point.distance(hit.point) < 0.005,
            "frame {f}: {} vs {}",
            sample.point,
            hit.point
        );
        assert!((sample.depth_m - depth[60 * 160 + 80] as f64 / 1000.0).abs() < 1e-12);
        // The normal comes from millimetre-quantised gradients over a 5x5 window (about 1 cm
        // per pixel at 1.3 m), so it agrees only roughly with the true normal.
        let angle = sample.normal.angle_between(hit.normal).to_degrees();
        assert!(
            angle < 15.0,
            "frame {f}: normal off by {angle} degrees on {}",
            hit.surface_name
        );
        angles.push(angle);
    }
    assert!(angles.len() >= 40, "only {} samples checked", angles.len());
    let mean = angles.iter().sum::<f64>() / angles.len() as f64;
    assert!(mean < 5.0, "mean normal error {mean} degrees");
}
