//! A depth sample for a midpoint whose distance to the surface is known but whose depth
//! image is not (a reference trial, the phone's own log): a flat wall at that distance,
//! handed to the phone logic so it samples it as it samples a real image.

use sitar_core::{DisplayRotation, Session};

/// A constant depth image (a wall facing the camera) at `distance_m`, for the phone logic's
/// own sampling: 16 × 16 px, a pinhole of 16 px focal length.
const FLAT_SIDE: u32 = 16;

pub(super) fn flat_depth_sample(session: &mut Session, distance_m: f64) {
    let mm = (distance_m * 1000.0).round();
    // sitar-core reads depth in millimetres within u16 (65 m).
    if !(100.0..65_000.0).contains(&mm) {
        return;
    }
    let pixels = vec![mm as u16; (FLAT_SIDE * FLAT_SIDE) as usize];
    // The principal point on the pixel sitar-core samples (`DepthImage::centre`): the
    // sample's ray is the optical axis, as the phone's distance was measured along it.
    let half = f64::from(FLAT_SIDE / 2);
    let k = sitar_core::Intrinsics {
        fx: 16.0,
        fy: 16.0,
        cx: half,
        cy: half,
    };
    let Ok(image) = sitar_core::DepthImage::new(&pixels, FLAT_SIDE, FLAT_SIDE, FLAT_SIDE * 2)
    else {
        return;
    };
    // An unusable sample only leaves this midpoint without a surface point.
    let _ = session.depth(&image, &k, DisplayRotation::Deg0);
}
