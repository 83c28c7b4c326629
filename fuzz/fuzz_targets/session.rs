//! sitar-core's recorder `Session` driven by an arbitrary call sequence: any pose (NaN and
//! infinities included), any time step, any depth image size/stride/intrinsics/pixel/display
//! rotation, any results text. Calls may fail; none may panic. A session with a valid config
//! that saves must load back equal (checked once, after the last call, when any `SaveLoad`).
#![no_main]

use arbitrary::Arbitrary;
use glam::{DQuat, DVec3};
use libfuzzer_sys::fuzz_target;
use sitar_core::{
    Convention, DepthImage, DisplayRotation, Intrinsics, Pose, Session, SessionConfig,
};

#[derive(Arbitrary, Debug)]
struct Input {
    config: Config,
    ops: Vec<Op>,
}

/// Raw config values: `Session::new` takes a config as given, unvalidated.
#[derive(Arbitrary, Debug)]
struct Config {
    arcore: bool,
    subtrajectory_frames: u8,
    dedup_radius_m: f64,
    max_regions: u8,
    thresholds_m: Vec<f64>,
    high_threshold_m: f64,
    medium_threshold_m: f64,
    frustum_spacing_m: f64,
    unreliable_mean_error_m: f64,
}

#[derive(Arbitrary, Debug)]
enum P {
    /// On a line, 10 cm per step, identity rotation (reaches the happy paths).
    Step(i16),
    Raw([f64; 3], [f64; 4]),
}

#[derive(Arbitrary, Debug)]
enum Time {
    After(u32),
    At(i64),
}

#[derive(Arbitrary, Debug)]
enum Image {
    /// A fronto-parallel wall, tightly packed.
    Wall { width: u8, height: u8, mm: u16 },
    Raw {
        width: u32,
        height: u32,
        stride_bytes: u32,
        data: Fill,
    },
}

#[derive(Arbitrary, Debug)]
enum Fill {
    Constant { mm: u16, len: u16 },
    Data(Vec<u16>),
}

#[derive(Arbitrary, Debug)]
enum K {
    Phone,
    Raw([f64; 4]),
}

#[derive(Arbitrary, Debug)]
enum Op {
    Start(Time, P),
    Frame(Time, P),
    Depth {
        image: Image,
        k: K,
        degrees: i32,
        pixel: Option<(u32, u32)>,
    },
    Stop(Time, P),
    LoadResults(String),
    /// Results keyed by the sub-trajectory starts (reaches markers).
    LoadMatchingResults(Vec<u8>),
    SetTolerance(Option<i64>),
    ErrorAt(Time),
    SubtrajectoryClass(u32),
    Query,
    SaveLoad,
}

fn pose(p: &P) -> Pose {
    match *p {
        P::Step(i) => Pose::new(DVec3::new(0.1 * f64::from(i), 1.5, 0.0), DQuat::IDENTITY),
        P::Raw(t, [x, y, z, w]) => Pose::new(DVec3::from_array(t), DQuat::from_xyzw(x, y, z, w)),
    }
}

fn time(last: i64, t: &Time) -> i64 {
    match *t {
        Time::After(dt) => last.saturating_add(i64::from(dt)),
        Time::At(t) => t,
    }
}

fn depth(session: &mut Session, image: &Image, k: &K, degrees: i32, pixel: Option<(u32, u32)>) {
    let (data, width, height, stride) = match *image {
        Image::Wall { width, height, mm } => {
            let (w, h) = (u32::from(width), u32::from(height));
            (vec![mm; (w * h) as usize], w, h, 2 * w)
        }
        Image::Raw {
            width,
            height,
            stride_bytes,
            ref data,
        } => {
            let data = match data {
                Fill::Constant { mm, len } => vec![*mm; usize::from(*len)],
                Fill::Data(v) => v.clone(),
            };
            (data, width, height, stride_bytes)
        }
    };
    let k = match *k {
        K::Phone => Intrinsics {
            fx: 211.0,
            fy: 211.0,
            cx: 127.5,
            cy: 95.5,
        },
        K::Raw([fx, fy, cx, cy]) => Intrinsics { fx, fy, cx, cy },
    };
    let Ok(image) = DepthImage::new(&data, width, height, stride) else {
        return;
    };
    let Ok(rotation) = DisplayRotation::from_degrees(degrees) else {
        return;
    };
    let _ = session.depth_at(&image, &k, rotation, pixel);
}

fuzz_target!(|input: Input| {
    let c = &input.config;
    let config = SessionConfig {
        convention: if c.arcore {
            Convention::Arcore
        } else {
            Convention::Unity
        },
        subtrajectory_frames: u32::from(c.subtrajectory_frames),
        dedup_radius_m: c.dedup_radius_m,
        max_regions: usize::from(c.max_regions),
        thresholds_m: c.thresholds_m.clone(),
        high_threshold_m: c.high_threshold_m,
        medium_threshold_m: c.medium_threshold_m,
        frustum_spacing_m: c.frustum_spacing_m,
        unreliable_mean_error_m: c.unreliable_mean_error_m,
        ..SessionConfig::default()
    };
    let mut s = Session::new(config);
    let mut last = 0i64;
    let mut save_load = false;
    for op in &input.ops {
        match op {
            Op::Start(t, p) => {
                last = time(last, t);
                let _ = s.start(last, pose(p));
            }
            Op::Frame(t, p) => {
                last = time(last, t);
                let _ = s.frame(last, pose(p));
            }
            Op::Depth {
                image,
                k,
                degrees,
                pixel,
            } => depth(&mut s, image, k, *degrees, *pixel),
            Op::Stop(t, p) => {
                last = time(last, t);
                let _ = s.stop(last, pose(p));
            }
            Op::LoadResults(text) => {
                let _ = s.load_results(text);
            }
            Op::LoadMatchingResults(errors) => {
                let mut csv = String::from("start,error\n");
                for (sub, e) in s.subtrajectories().iter().zip(errors) {
                    csv.push_str(&format!("{},{}\n", sub.start_ns, f64::from(*e) / 100.0));
                }
                s.load_results(&csv).expect("well-formed results load");
            }
            Op::SetTolerance(t) => {
                let _ = s.set_lookup_tolerance_ns(*t);
            }
            Op::ErrorAt(t) => {
                let _ = s.error_at(time(last, t));
            }
            Op::SubtrajectoryClass(k) => {
                let _ = (s.subtrajectory_class(*k), s.subtrajectory_error(*k));
            }
            Op::Query => {
                let _ = s.markers();
                let _ = s.render_plan();
                let _ = s.subtrajectory_errors();
                let _ = s.results_unreliable();
                let _ = s.summary();
                let _ = s.lookup_tolerance_ns();
                let _ = s.trajectory_tum();
            }
            // File I/O is slow: one round trip per input, after the last call.
            Op::SaveLoad => save_load = true,
        }
        for (i, sub) in s.subtrajectories().iter().enumerate() {
            assert_eq!(sub.index as usize, i);
        }
    }
    if save_load {
        let dir = std::env::temp_dir().join(format!("sitar-fuzz-session-{}", std::process::id()));
        if s.save(&dir).is_ok() && s.config().validate().is_ok() {
            let loaded = Session::load(&dir);
            assert!(
                matches!(&loaded, Ok(l) if *l == s),
                "save/load round trip: {loaded:?}"
            );
        }
    }
});
