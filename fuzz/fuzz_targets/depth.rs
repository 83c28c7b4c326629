//! sitar-core's depth geometry: `DepthImage::new` with any size/stride/buffer, then
//! `get`, `optical_sample` and `sample_surface` with any intrinsics, pixel, display rotation,
//! convention and pose.
#![no_main]

use arbitrary::Arbitrary;
use glam::{DQuat, DVec3};
use libfuzzer_sys::fuzz_target;
use sitar_core::{Convention, DepthImage, DisplayRotation, Intrinsics, Pose, sample_surface};

#[derive(Arbitrary, Debug)]
enum Fill {
    Constant {
        mm: u16,
        len: u16,
    },
    /// A depth ramp `base + dx·x + dy·y` over rows of `stride` elements (a tilted plane).
    Ramp {
        base: u16,
        dx: i8,
        dy: i8,
        stride: u8,
        len: u16,
    },
    Data(Vec<u16>),
}

#[derive(Arbitrary, Debug)]
struct Input {
    width: u32,
    height: u32,
    stride_bytes: u32,
    fill: Fill,
    k: [f64; 4],
    degrees: i32,
    arcore: bool,
    position: [f64; 3],
    rotation: [f64; 4],
    pixel: Option<(u32, u32)>,
}

fuzz_target!(|input: Input| {
    let data = match input.fill {
        Fill::Constant { mm, len } => vec![mm; usize::from(len)],
        Fill::Ramp {
            base,
            dx,
            dy,
            stride,
            len,
        } => (0..usize::from(len))
            .map(|i| {
                let (x, y) = (
                    i % usize::from(stride.max(1)),
                    i / usize::from(stride.max(1)),
                );
                let d = i64::from(base) + i64::from(dx) * x as i64 + i64::from(dy) * y as i64;
                d.clamp(0, i64::from(u16::MAX)) as u16
            })
            .collect(),
        Fill::Data(v) => v,
    };
    let Ok(image) = DepthImage::new(&data, input.width, input.height, input.stride_bytes) else {
        return;
    };
    let (w, h) = (image.width(), image.height());
    let (cx, cy) = image.centre();
    assert!(cx < w && cy < h);
    for (x, y) in [
        (0, 0),
        (w - 1, h - 1),
        (cx, cy),
        (w, 0),
        (0, h),
        (u32::MAX, u32::MAX),
    ] {
        assert_eq!(image.get(x, y).is_some(), x < w && y < h);
    }
    let [fx, fy, cx, cy] = input.k;
    let k = Intrinsics { fx, fy, cx, cy };
    let (px, py) = input.pixel.unwrap_or(image.centre());
    let _ = k.validate();
    let _ = k.ray(f64::from(px), f64::from(py));
    let _ = image.optical_sample(&k, px, py);
    let Ok(rotation) = DisplayRotation::from_degrees(input.degrees) else {
        return;
    };
    let convention = if input.arcore {
        Convention::Arcore
    } else {
        Convention::Unity
    };
    let [x, y, z, qw] = input.rotation;
    let pose = Pose::new(
        DVec3::from_array(input.position),
        DQuat::from_xyzw(x, y, z, qw),
    );
    if let Ok(sample) = sample_surface(&image, &k, rotation, convention, &pose, input.pixel) {
        assert_eq!(sample.pixel, [px, py]);
        assert!(sample.depth_m > 0.0);
    }
});
