//! Criterion benches of the on-device hot paths (targets in README.md).
#![allow(missing_docs)]

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use glam::{DQuat, DVec3};
use sitar_core::{
    Convention, DepthImage, DisplayRotation, ImageProperties, Intrinsics, LumaImage,
    MarkerCandidate, Pose, Session, SessionConfig, downsample_rotated, encode_jpeg, sample_surface,
    select_markers,
};

/// Deterministic pseudo-random numbers in [0, 1) (no dependency needed for benches).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn pose_at(i: i64) -> Pose {
    let t = i as f64 / 30.0;
    Pose::new(
        DVec3::new(
            3.0 * (0.1 * t).cos(),
            1.5 + 0.02 * t.sin(),
            3.0 * (0.1 * t).sin(),
        ),
        DQuat::from_rotation_y(0.1 * t),
    )
}

/// Times `iters` frame calls in chunks of fresh sessions (so memory stays bounded).
fn time_frames(iters: u64, subtrajectory_frames: u32) -> Duration {
    // Ten minutes at 30 fps: the session's pre-reserved capacity.
    const CHUNK: u64 = 18_000;
    let poses: Vec<Pose> = (0..CHUNK as i64 + 1).map(pose_at).collect();
    let mut total = Duration::ZERO;
    let mut left = iters;
    while left > 0 {
        let n = left.min(CHUNK);
        let config = SessionConfig {
            subtrajectory_frames,
            ..SessionConfig::default()
        };
        let mut session = Session::new(config);
        session.start(0, poses[0]).unwrap();
        let start = Instant::now();
        for (i, pose) in poses.iter().enumerate().skip(1).take(n as usize) {
            black_box(
                session
                    .frame(i as i64 * 33_333_333, black_box(*pose))
                    .unwrap(),
            );
        }
        total += start.elapsed();
        left -= n;
    }
    total
}

fn bench_frame(c: &mut Criterion) {
    // A cadence that never logs isolates the non-logging path exactly.
    c.bench_function("frame/non_logging", |b| {
        b.iter_custom(|iters| time_frames(iters, 1 << 30))
    });
    c.bench_function("frame/mixed_10", |b| {
        b.iter_custom(|iters| time_frames(iters, 10))
    });
}

fn tilted_plane(width: u32, height: u32, k: &Intrinsics) -> Vec<u16> {
    let n = DQuat::from_rotation_y(30f64.to_radians()) * DVec3::NEG_Z;
    let mut out = Vec::with_capacity((width * height) as usize);
    for v in 0..height {
        for u in 0..width {
            let ray = k.ray(f64::from(u), f64::from(v));
            out.push((-2.0 / n.dot(ray) * 1000.0).round() as u16);
        }
    }
    out
}

fn bench_depth(c: &mut Criterion) {
    let k = Intrinsics {
        fx: 211.0,
        fy: 211.0,
        cx: 127.5,
        cy: 95.5,
    };
    let data = tilted_plane(256, 192, &k);
    let pose = pose_at(100);
    c.bench_function("depth/sample_with_normal_256x192", |b| {
        b.iter(|| {
            let image = DepthImage::new(black_box(&data), 256, 192, 512).unwrap();
            black_box(
                sample_surface(
                    &image,
                    &k,
                    DisplayRotation::Deg90,
                    Convention::Unity,
                    &pose,
                    None,
                )
                .unwrap(),
            )
        })
    });
}

fn bench_markers(c: &mut Criterion) {
    // 10 000 sub-trajectories of a walk through a room, every midpoint with depth.
    let subs = 10_000i64;
    let mut session = Session::new(SessionConfig::default());
    let k = Intrinsics {
        fx: 211.0,
        fy: 211.0,
        cx: 127.5,
        cy: 95.5,
    };
    let wall = vec![2000u16; 256 * 192];
    let image = DepthImage::new(&wall, 256, 192, 512).unwrap();
    session.start(0, pose_at(0)).unwrap();
    for i in 1..=subs * 10 {
        if session
            .frame(i * 33_333_333, pose_at(i))
            .unwrap()
            .is_midpoint()
        {
            session.depth(&image, &k, DisplayRotation::Deg0).unwrap();
        }
    }
    session
        .stop((subs * 10 + 1) * 33_333_333, pose_at(subs * 10 + 1))
        .unwrap();
    let mut rng = Lcg(7);
    let mut csv = String::from("start,error\n");
    for s in 0..subs {
        csv.push_str(&format!("{},{}\n", s * 10 * 33_333_333, 0.15 * rng.next()));
    }
    session.load_results(&csv).unwrap();
    assert_eq!(session.markers().unwrap().len(), 3);
    c.bench_function("markers/session_10000_subtrajectories", |b| {
        b.iter(|| black_box(session.markers().unwrap()))
    });

    c.bench_function("results/subtrajectory_errors_10000", |b| {
        b.iter(|| black_box(session.subtrajectory_errors()))
    });

    let candidates: Vec<MarkerCandidate> = (0..subs as u32)
        .map(|i| MarkerCandidate {
            subtrajectory: i,
            position: DVec3::new(10.0 * rng.next(), 3.0 * rng.next(), 10.0 * rng.next()),
            normal: DVec3::NEG_Z,
            error_m: 0.15 * rng.next(),
        })
        .collect();
    let config = SessionConfig::default();
    c.bench_function("markers/select_10000_candidates", |b| {
        b.iter(|| black_box(select_markers(&candidates, &config)))
    });
    let many = SessionConfig {
        max_regions: 1000,
        ..SessionConfig::default()
    };
    c.bench_function("markers/select_10000_candidates_max_1000", |b| {
        b.iter(|| black_box(select_markers(&candidates, &many)))
    });
}

/// A 640×480 camera-like plane: smooth shading, a few hundred edges, sensor noise.
fn camera_plane(rng: &mut Lcg) -> Vec<u8> {
    (0..640 * 480)
        .map(|i| {
            let (x, y) = (i % 640, i / 640);
            let shade = 60.0 + 0.15 * x as f64 + 0.1 * y as f64;
            let tile = if ((x / 23) + (y / 17)) % 5 == 0 {
                70.0
            } else {
                0.0
            };
            (shade + tile + 6.0 * rng.next()) as u8
        })
        .collect()
}

/// CPU time of the calling thread.
fn thread_cpu() -> Duration {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: a valid out-pointer; CLOCK_THREAD_CPUTIME_ID is always available on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

fn bench_image(c: &mut Criterion) {
    let mut rng = Lcg(7);
    let plane = camera_plane(&mut rng);
    let image = LumaImage::new(&plane, 640, 480, 640).unwrap();
    c.bench_function("image/properties_640x480", |b| {
        b.iter(|| black_box(ImageProperties::measure(black_box(&image))))
    });
    let mut pixels = Vec::new();
    c.bench_function("image/thumbnail_160_jpeg_640x480", |b| {
        b.iter(|| {
            let (w, h) = downsample_rotated(&image, 160, DisplayRotation::Deg90, &mut pixels);
            black_box(encode_jpeg(&pixels, w, h).unwrap())
        })
    });
    // The same as thread CPU time: on a shared machine the wall clock also counts the time
    // other processes hold the core.
    c.bench_function("image/properties_plus_thumbnail_640x480_cpu_time", |b| {
        b.iter_custom(|iters| {
            let start = thread_cpu();
            for _ in 0..iters {
                black_box(ImageProperties::measure(black_box(&image)));
                let (w, h) = downsample_rotated(&image, 160, DisplayRotation::Deg90, &mut pixels);
                black_box(encode_jpeg(&pixels, w, h).unwrap());
            }
            thread_cpu() - start
        })
    });
    // The whole midpoint call: properties + thumbnail into the session.
    c.bench_function("image/session_image_640x480", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            let mut session = Session::new(SessionConfig::default());
            session.start(0, pose_at(0)).unwrap();
            let mut i = 0;
            for _ in 0..iters {
                loop {
                    i += 1;
                    if session
                        .frame(i * 33_333_333, pose_at(i))
                        .unwrap()
                        .is_midpoint()
                    {
                        break;
                    }
                }
                let t = Instant::now();
                session.image(&image, DisplayRotation::Deg90).unwrap();
                total += t.elapsed();
            }
            total
        })
    });
}

/// The venue alignment the phone recomputes on every anchor observation: `align` over 300
/// (10 s at 30 Hz) and 18 000 (10 min) full observations.
fn bench_venue(c: &mut Criterion) {
    use sitar_core::Tracking;
    use sitar_core::venue::{AnchorObservation, align};
    for n in [300usize, 18_000] {
        let observations: Vec<AnchorObservation> = (0..n)
            .map(|i| {
                let e = ((i * 7919) % 1000) as f64 / 1000.0 - 0.5;
                AnchorObservation {
                    t_ns: i as i64,
                    anchor: "hall".to_owned(),
                    pose: Pose::new(
                        DVec3::new(1.0 + 0.01 * e, 1.5, 2.0 - 0.01 * e),
                        DQuat::from_rotation_y(0.4 + 0.01 * e),
                    ),
                    tracking: Tracking::Full,
                }
            })
            .collect();
        c.bench_function(&format!("venue/align_{n}_observations"), |b| {
            b.iter(|| align(black_box(&observations), "hall"))
        });
    }
}

/// A one-run calibration as `sitar calibrate` fits them: all four motion features, smoothed
/// over two neighbouring windows each side.
fn walk_calibration() -> String {
    use sitar_core::calibration::{
        CALIBRATION_FORMAT, Calibration, CalibrationModel, Feature, FittedOn, IntervalModel,
        RunCount, Target,
    };
    let features = vec![
        Feature::PathM,
        Feature::RotationDeg,
        Feature::DisplacementM,
        Feature::JitterMps2,
    ];
    Calibration {
        format: CALIBRATION_FORMAT.into(),
        version: 2,
        fitted_on: FittedOn {
            sequences: Vec::new(),
            setting: "trim_mean_30".into(),
            window_frames: 10,
            pose_relation: "trans_part".into(),
            unit: "m".into(),
            coverage: 0.8,
            t_max_diff_s: 0.01,
        },
        informative: true,
        models: vec![CalibrationModel {
            target: Target::Live,
            runs: RunCount::One,
            kind: "log_linear".into(),
            offsets: features.iter().map(|f| f.offset()).collect(),
            features,
            smoothing_windows: 2,
            coefficients: vec![0.3f64.ln(), 0.6, 0.2, -0.1, 0.1],
            spread_match: 0.0,
            center: 0.0,
            stretch: 1.0,
            interval: IntervalModel {
                method: "leave_one_sequence_out".into(),
                log_lower: 0.5f64.ln(),
                log_upper: 2.0f64.ln(),
                residuals: 1000,
            },
            informative: true,
            scores: None,
        }],
    }
    .to_json()
}

/// The estimate from one walk: `stop` on a 10-minute walk at 30 fps (18 000 frames, a depth
/// sample at every midpoint) with a calibration — every window's calibrated error and
/// interval, then the markers — against `stop` without one (issue 41: ≤ 50 ms).
fn bench_walk(c: &mut Criterion) {
    const FRAMES: i64 = 18_000;
    let k = Intrinsics {
        fx: 211.0,
        fy: 211.0,
        cx: 127.5,
        cy: 95.5,
    };
    let wall = vec![2000u16; 256 * 192];
    let image = DepthImage::new(&wall, 256, 192, 512).unwrap();
    let record = |calibration: Option<&str>| {
        let mut session = Session::new(SessionConfig::default());
        if let Some(json) = calibration {
            session.set_calibration(json).unwrap();
        }
        session.start(0, pose_at(0)).unwrap();
        for i in 1..=FRAMES {
            if session
                .frame(i * 33_333_333, pose_at(i))
                .unwrap()
                .is_midpoint()
            {
                session.depth(&image, &k, DisplayRotation::Deg0).unwrap();
            }
        }
        session
    };
    let stop_pose = pose_at(FRAMES + 1);
    let stop_ns = (FRAMES + 1) * 33_333_333;
    let calibrated = record(Some(&walk_calibration()));
    let mut check = calibrated.clone();
    check.stop(stop_ns, stop_pose).unwrap();
    let results = check.results().expect("coloured at stop");
    assert_eq!(results.windows.len(), FRAMES as usize + 1 - 10);
    // About 7 cm everywhere: the markers are placed too (at most 3).
    assert_eq!(check.markers().unwrap().len(), 3);
    c.bench_function("walk/stop_10min_with_calibration", |b| {
        b.iter_batched(
            || calibrated.clone(),
            |mut s| black_box(s.stop(stop_ns, stop_pose).unwrap()),
            BatchSize::LargeInput,
        )
    });
    // The same as thread CPU time: on a shared machine the wall clock also counts the time
    // other processes hold the core.
    c.bench_function("walk/stop_10min_with_calibration_cpu_time", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let mut s = calibrated.clone();
                let start = thread_cpu();
                black_box(s.stop(stop_ns, stop_pose).unwrap());
                total += thread_cpu() - start;
            }
            total
        })
    });
    let plain = record(None);
    c.bench_function("walk/stop_10min_without_calibration", |b| {
        b.iter_batched(
            || plain.clone(),
            |mut s| black_box(s.stop(stop_ns, stop_pose).unwrap()),
            BatchSize::LargeInput,
        )
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2)).sample_size(30);
    targets = bench_frame, bench_depth, bench_markers, bench_image, bench_venue, bench_walk
}
criterion_main!(benches);
