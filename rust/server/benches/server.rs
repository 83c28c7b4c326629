//! Backend figures: overhead beyond playback, upload throughput, 50 concurrent sessions,
//! uploading a 15 s walk's evidence.
//!
//! `cargo bench -p sitar-server`

use std::cell::OnceCell;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use sitar_client::{Client, NewSession, SessionState};
use sitar_server::{Limits, PlaybackKind, PresetToken, Role, Server, ServerConfig, ServerHandle};

fn sim_server(data: &Path, speed: f64, devices: u32) -> ServerHandle {
    let mut config = ServerConfig::new(data);
    config.playback = PlaybackKind::Sim;
    config.sim.speed = speed;
    config.sim.devices = devices;
    config.preset_tokens = vec![PresetToken {
        name: "bench".into(),
        role: Role::App,
        token: BENCH_TOKEN.into(),
    }];
    // 50 sessions at once, many times over: no per-token limit in the way, and a playback
    // worker for each.
    config.playback_workers = 50;
    config.jobs_per_token = 50;
    config.limits = Limits {
        sessions_per_hour: u32::MAX,
        upload_bytes_per_day: u64::MAX,
        concurrent_uploads: u32::MAX,
    };
    Server::spawn(config, "127.0.0.1:0".parse().unwrap()).unwrap()
}

const BENCH_TOKEN: &str = "sitar_bench_0123456789abcdef0123456789";

fn client(url: &str) -> Client {
    Client::new(url)
        .unwrap()
        .with_server_token(BENCH_TOKEN)
        .unwrap()
}

/// A server at 1× with one simulated phone, its client, and a session whose trials the
/// client uploads (`playback: upload`), for benchmarks of the upload routes.
fn upload_session(data: &Path) -> (ServerHandle, Client, String) {
    let server = sim_server(data, 1.0, 1);
    let client = client(&server.url());
    let id = client
        .create_session(&NewSession {
            trials: 2,
            setting: "mean".into(),
            playback: "upload".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    (server, client, id)
}

fn run_session(client: &Client, recording: &Path, trials: u32) -> Duration {
    let id = client
        .create_session(&NewSession {
            trials,
            setting: "trim_mean_30".into(),
            playback: "sim".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    client
        .upload_recording(&id, recording, &mut |_, _| {})
        .unwrap();
    let started = Instant::now();
    let status = client
        .wait(
            &id,
            Duration::from_millis(5),
            Duration::from_secs(300),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(status.state, SessionState::Done, "{status:?}");
    assert_eq!(status.trials_done, trials);
    started.elapsed()
}

/// 20 trials × 450 poses (15 s at 30 fps) on one simulated phone at 300× (50 ms a trial):
/// the figure is the session's wall time minus the playback time d·⌈T/D⌉ = 1 s.
fn overhead_beyond_playback(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let recording = dir.path().join("walk.rec");
    let rec = sitar_sim::Recording::demo(15.0, 30.0, 42).unwrap();
    assert_eq!(rec.frames(), 450);
    std::fs::write(&recording, rec.to_bytes()).unwrap();
    let speed = 300.0;
    let playback = Duration::from_secs_f64(rec.duration_s() / speed * 20.0);
    let server = sim_server(&dir.path().join("data"), speed, 1);
    let client = client(&server.url());
    let mut group = c.benchmark_group("server");
    group.sample_size(10);
    group.bench_function("overhead_beyond_playback_20x450", |b| {
        b.iter_custom(|iters| {
            (0..iters)
                .map(|_| run_session(&client, &recording, 20).saturating_sub(playback))
                .sum()
        })
    });
    group.finish();
}

/// What a benchmark uploads to: a temporary folder (kept while it runs), the server, a client,
/// the session, and the file or folder sent.
type UploadSetup = (tempfile::TempDir, ServerHandle, Client, String, PathBuf);

/// PUT of a 256 MiB recording over loopback, streamed from disk to the data directory.
fn upload_throughput(c: &mut Criterion) {
    // Set up only when the benchmark runs (not when a filter skips it).
    let setup = OnceCell::new();
    let size: u64 = 256 << 20;
    let mut group = c.benchmark_group("server");
    group.sample_size(10);
    group.throughput(Throughput::Bytes(size));
    group.bench_function("upload_256MiB", |b| {
        let (_, _, client, id, file) = setup.get_or_init(|| upload_setup(size));
        b.iter(|| client.upload_recording(id, file, &mut |_, _| {}).unwrap())
    });
    group.finish();
}

/// A file of `size` bytes and an `upload` session to send it to.
fn upload_setup(size: u64) -> UploadSetup {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("big.bin");
    {
        use std::io::Write;
        let mut f = std::io::BufWriter::new(std::fs::File::create(&file).unwrap());
        let block: Vec<u8> = (0..1 << 20).map(|i: u32| (i * 31 % 251) as u8).collect();
        for _ in 0..size >> 20 {
            f.write_all(&block).unwrap();
        }
    }
    let (server, client, id) = upload_session(&dir.path().join("data"));
    (dir, server, client, id, file)
}

/// 50 sessions at once (5 trials × 90 poses each, 2 simulated phones per session):
/// every one must finish with all its trials.
fn concurrent_sessions(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let recording = dir.path().join("walk.rec");
    std::fs::write(
        &recording,
        sitar_sim::Recording::demo(3.0, 30.0, 5).unwrap().to_bytes(),
    )
    .unwrap();
    let server = sim_server(&dir.path().join("data"), 30.0, 2);
    let url = server.url();
    let mut group = c.benchmark_group("server");
    group.sample_size(10);
    group.bench_function("concurrent_50_sessions", |b| {
        b.iter_custom(|iters| {
            let started = Instant::now();
            for _ in 0..iters {
                std::thread::scope(|scope| {
                    for _ in 0..50 {
                        let (url, recording) = (&url, &recording);
                        scope.spawn(move || {
                            let client = client(url);
                            run_session(&client, recording, 5);
                        });
                    }
                });
            }
            started.elapsed()
        })
    });
    group.finish();
}

/// A 15 s walk recorded by the phone logic (sitar-core) with the simulator's rendered
/// images and depth at every midpoint; its session folder's evidence is uploaded.
fn evidence_upload(c: &mut Criterion) {
    // Rendering the walk takes minutes in a debug build: only when the benchmark runs.
    let setup = OnceCell::new();
    let mut group = c.benchmark_group("server");
    group.sample_size(20);
    group.bench_function("evidence_upload_15s_walk", |b| {
        let (_, _, client, id, folder) = setup.get_or_init(evidence_setup);
        b.iter(|| client.upload_evidence(id, folder).unwrap())
    });
    group.finish();
}

/// The walk's phone session folder and an `upload` session to send its evidence to.
fn evidence_setup() -> UploadSetup {
    use sitar_core::{DepthImage, DisplayRotation, LumaImage, Pose, Session, SessionConfig};
    let dir = tempfile::tempdir().unwrap();
    let recording = sitar_sim::Recording::demo(15.0, 30.0, 5).unwrap();
    let gt = &recording.walk().ground_truth;
    let (depth_camera, luma_camera) = (
        sitar_sim::DepthCamera::phone(),
        sitar_sim::LumaCamera::phone(),
    );
    let display = DisplayRotation::Deg0;
    let mut phone = Session::new(SessionConfig::from_json(r#"{"convention":"arcore"}"#).unwrap());
    let pose = |i: usize| Pose::new(gt.positions[i], gt.orientations[i]);
    let last = gt.len() - 1;
    phone.start(gt.stamps[0], pose(0)).unwrap();
    for i in 1..last {
        if phone.frame(gt.stamps[i], pose(i)).unwrap().is_midpoint() {
            let (p, q) = (gt.positions[i], gt.orientations[i]);
            let luma = recording
                .room()
                .render_luma_rotated(p, q, &luma_camera, display, i as u64);
            let (w, h) = (luma_camera.width, luma_camera.height);
            phone
                .image(&LumaImage::new(&luma, w, h, w).unwrap(), display)
                .unwrap();
            let depth = recording
                .room()
                .render_depth_mm_rotated(p, q, &depth_camera, display);
            let image = DepthImage::new(
                &depth,
                depth_camera.width,
                depth_camera.height,
                depth_camera.width * 2,
            )
            .unwrap();
            let _ = phone.depth(&image, &depth_camera.intrinsics, display);
        }
    }
    phone.stop(gt.stamps[last], pose(last)).unwrap();
    let folder = dir.path().join("phone");
    phone.save(&folder).unwrap();
    let (server, client, id) = upload_session(&dir.path().join("data"));
    let sent = client.upload_evidence(&id, &folder).unwrap().unwrap();
    let bytes: u64 = std::fs::read_dir(folder.join("thumbnails"))
        .unwrap()
        .map(|e| e.unwrap().metadata().unwrap().len())
        .sum();
    eprintln!(
        "evidence of a 15 s walk: {} sub-trajectories, {sent} thumbnails, {bytes} thumbnail bytes",
        phone.subtrajectories().len()
    );
    (dir, server, client, id, folder)
}

criterion_group!(
    benches,
    overhead_beyond_playback,
    upload_throughput,
    concurrent_sessions,
    evidence_upload
);
criterion_main!(benches);
