//! Criterion benches of the venue map (issue 24's targets): a map of 1 000 sessions × 500
//! sub-trajectories rebuilt from their contributions (≤ 1 s), and a session joining that
//! venue — its files parsed and aligned, added, the map produced — (≤ 50 ms).
#![allow(missing_docs)]

use std::fmt::Write as _;
use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{DQuat, DVec3};
use sitar_core::venue::{
    AnchorObservation, Contribution, MapBuilder, Sample, SessionFiles, Tracking, VenueSpec, align,
    anchors_csv, build_map,
};
use sitar_core::{Convention, Pose, to_tum};

const SESSIONS: usize = 1_000;
const SUBTRAJECTORIES: usize = 500;

/// Deterministic pseudo-random numbers in [0, 1).
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

fn spec() -> VenueSpec {
    VenueSpec {
        id: "v0000000000000001".into(),
        name: "Hall".into(),
        anchor: "a".into(),
        cell_m: 0.25,
        convention: Convention::Unity,
    }
}

/// One session's walk in a 30 m × 30 m hall (venue frame): a random walk at eye height, the
/// camera turning, surfaces 0.5–4 m ahead (a third of the samples without depth).
fn walk(rng: &mut Lcg) -> Vec<(Pose, Option<DVec3>, f64)> {
    let mut p = DVec3::new(30.0 * rng.next() - 15.0, 1.5, 30.0 * rng.next() - 15.0);
    let mut yaw = std::f64::consts::TAU * rng.next();
    (0..SUBTRAJECTORIES)
        .map(|_| {
            yaw += 0.6 * (rng.next() - 0.5);
            let step = DVec3::new(yaw.sin(), 0.0, yaw.cos()) * 0.15;
            p = (p + step).clamp(DVec3::new(-15.0, 1.2, -15.0), DVec3::new(15.0, 1.8, 15.0));
            p.y = 1.2 + 0.6 * rng.next();
            let rotation = DQuat::from_rotation_y(yaw) * DQuat::from_rotation_x(rng.next() - 0.5);
            let surface =
                (rng.next() > 0.33).then(|| p + rotation * DVec3::Z * (0.5 + 3.5 * rng.next()));
            (
                Pose::new(p, rotation),
                surface,
                0.2 * rng.next() * rng.next(),
            )
        })
        .collect()
}

/// A contribution made directly from a walk (the venue frame is the world frame).
fn contribution(i: usize, rng: &mut Lcg) -> Contribution {
    let alignment = align(
        &[AnchorObservation {
            t_ns: 0,
            anchor: "a".into(),
            pose: Pose::IDENTITY,
            tracking: Tracking::Full,
        }],
        "a",
    )
    .unwrap();
    let samples = walk(rng)
        .into_iter()
        .enumerate()
        .map(|(k, (pose, surface, error_m))| {
            let f = pose.rotation * DVec3::Z;
            Sample {
                subtrajectory: k as u32,
                position: pose.position,
                heading_rad: Some(f.z.atan2(f.x)),
                surface,
                error_m,
            }
        })
        .collect();
    Contribution::InMap {
        session: format!("s{i:04}"),
        convention: Convention::Unity,
        alignment,
        samples,
    }
}

/// The files a joining session uploads: 40 anchor observations, the TUM log, the table,
/// results at every frame (legacy CSV).
struct Files {
    anchors: String,
    trajectory: String,
    subs: String,
    results: String,
}

fn files(rng: &mut Lcg) -> Files {
    let t0 = 1_700_000_000_000_000_000i64;
    let half = 166_666_665i64;
    let observations: Vec<AnchorObservation> = (0..40)
        .map(|i| AnchorObservation {
            t_ns: t0 + i,
            anchor: "a".into(),
            pose: Pose::new(
                DVec3::new(0.001 * rng.next(), 0.0, 0.0),
                DQuat::from_rotation_x(1.5),
            ),
            tracking: Tracking::Full,
        })
        .collect();
    let walk = walk(rng);
    let mut logged = vec![(t0, walk[0].0)];
    let mut subs = String::from(
        "index,start_ns,mid_ns,end_ns,depth,pixel_x,pixel_y,depth_m,distance_m,cam_x,cam_y,cam_z,\
         cam_nx,cam_ny,cam_nz,x,y,z,nx,ny,nz,error_m,class\n",
    );
    let mut results = String::from("start,error\n");
    for (k, (pose, surface, error)) in walk.iter().enumerate() {
        let start = t0 + 2 * k as i64 * half;
        logged.push((start + half, *pose));
        logged.push((start + 2 * half, *pose));
        let _ = write!(subs, "{k},{start},{},{},", start + half, start + 2 * half);
        match surface {
            Some(s) => {
                let _ = writeln!(
                    subs,
                    "valid,128,96,1,1,0,0,1,0,0,-1,{},{},{},0,1,0,,",
                    s.x, s.y, s.z
                );
            }
            None => {
                let _ = writeln!(subs, "no_depth,128,96{}", ",".repeat(16));
            }
        }
        for j in 0..10 {
            let _ = writeln!(results, "{},{error}", start + j * half / 5);
        }
    }
    Files {
        anchors: anchors_csv(&observations),
        trajectory: to_tum(logged.iter().map(|(t, p)| (*t, p))),
        subs,
        results,
    }
}

/// CPU time of the calling thread (the machine is shared: wall time counts others' work).
fn thread_cpu() -> Duration {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: a valid out-pointer; CLOCK_THREAD_CPUTIME_ID is always available on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

fn bench_venue_map(c: &mut Criterion) {
    let mut rng = Lcg(24);
    let contributions: Vec<Contribution> =
        (0..SESSIONS).map(|i| contribution(i, &mut rng)).collect();
    let joining = files(&mut rng);
    let spec = spec();
    let reference = build_map(&spec, &contributions, 1);
    eprintln!(
        "venue: {SESSIONS} sessions × {SUBTRAJECTORIES} sub-trajectories → {} cells",
        reference.cells.len()
    );

    let mut group = c.benchmark_group("venue_map");
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(8));
    group.bench_function("rebuild_1000x500_cpu_time", |b| {
        b.iter_custom(|iters| {
            let start = thread_cpu();
            for _ in 0..iters {
                black_box(build_map(&spec, black_box(&contributions), 1));
            }
            thread_cpu() - start
        })
    });
    group.bench_function("rebuild_1000x500_wall", |b| {
        b.iter(|| black_box(build_map(&spec, black_box(&contributions), 1)))
    });

    let mut builder = MapBuilder::new(spec.clone());
    for c in &contributions {
        builder.add(c);
    }
    let _ = builder.map(1);
    let join = |builder: &mut MapBuilder| {
        let files = SessionFiles {
            session: "joining",
            convention: Convention::Unity,
            anchors_csv: Some(&joining.anchors),
            trajectory_txt: Some(&joining.trajectory),
            subtrajectories_csv: Some(&joining.subs),
            results_json: Some(&joining.results),
        };
        let contribution = Contribution::from_files(&files, "a").unwrap();
        assert_eq!(contribution.samples().len(), SUBTRAJECTORIES);
        builder.add(&contribution);
        black_box(builder.map(1));
    };
    // Timed: the join (parse, align, add, map); not timed: the leave that restores the venue.
    group.bench_function("join_1000_sessions_cpu_time", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let start = thread_cpu();
                join(&mut builder);
                total += thread_cpu() - start;
                builder.remove("joining");
                let _ = builder.map(1);
            }
            total
        })
    });
    group.bench_function("join_1000_sessions_wall", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                let start = Instant::now();
                join(&mut builder);
                total += start.elapsed();
                builder.remove("joining");
                let _ = builder.map(1);
            }
            total
        })
    });
    group.finish();
}

criterion_group!(benches, bench_venue_map);
criterion_main!(benches);
