//! Shared helpers of the cross-crate tests.
#![allow(missing_docs)]

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::time::Duration;

use sitar_server::{PlaybackKind, ServerConfig, ServerHandle};

/// A `sitar-sim` demo recording written to `dir/name`.
pub fn sim_recording(dir: &Path, name: &str, seconds: f64, seed: u64) -> PathBuf {
    let rec = sitar_sim::Recording::demo(seconds, 30.0, seed).expect("demo recording");
    let path = dir.join(name);
    std::fs::write(&path, rec.to_bytes()).expect("write recording");
    path
}

/// Server config on `data` with sim playback at `speed` times real time.
pub fn sim_config(data: &Path, speed: f64, devices: u32) -> ServerConfig {
    let mut config = ServerConfig::new(data);
    config.playback = PlaybackKind::Sim;
    config.sim.speed = speed;
    config.sim.devices = devices;
    config
}

/// The admin token every test server knows (see [`with_test_tokens`]).
pub const ADMIN_TOKEN: &str = "sitar_test_admin_5f0c2a9e81d34b7a9c1e6d20";
/// An app token every test server knows.
pub const APP_TOKEN: &str = "sitar_test_app_one_7b3e91c04a2f4d8e9a6b1c55";
/// A second app token, for "another app's session" checks.
pub const APP2_TOKEN: &str = "sitar_test_app_two_d41e8f2b6c9a4e0f8b3d7a19";

/// `config` with the test tokens registered: `test-admin` ([`ADMIN_TOKEN`]), `test-app`
/// ([`APP_TOKEN`]) and `test-app-2` ([`APP2_TOKEN`]).
pub fn with_test_tokens(mut config: ServerConfig) -> ServerConfig {
    use sitar_server::{PresetToken, Role};
    for (name, role, token) in [
        ("test-admin", Role::Admin, ADMIN_TOKEN),
        ("test-app", Role::App, APP_TOKEN),
        ("test-app-2", Role::App, APP2_TOKEN),
    ] {
        config.preset_tokens.push(PresetToken {
            name: name.into(),
            role,
            token: token.into(),
        });
    }
    config
}

/// Starts `config` on a free loopback port, with the test tokens (unless it has its own).
pub fn start(config: ServerConfig) -> ServerHandle {
    let config = if config.preset_tokens.is_empty() {
        with_test_tokens(config)
    } else {
        config
    };
    sitar_server::Server::spawn(config, "127.0.0.1:0".parse().unwrap()).expect("server starts")
}

/// Waits (polling every 20 ms, up to 60 s) until session `id` is done or failed.
pub fn wait_done(client: &sitar_client::Client, id: &str) -> sitar_client::SessionStatus {
    client
        .wait(
            id,
            Duration::from_millis(20),
            Duration::from_secs(60),
            &mut |_| {},
        )
        .expect("the session finishes")
}

/// Creates an `upload` session of `trials` trials with the median: the plain session most
/// route tests need.
pub fn upload_session(client: &sitar_client::Client, trials: u32) -> String {
    client
        .create_session(&sitar_client::NewSession {
            trials,
            setting: "median".into(),
            playback: "upload".into(),
            window_frames: None,
            pose_relation: None,
        })
        .expect("an upload session is created")
}

/// A TUM trajectory of `n` poses (about 60 bytes each) walking along x at 0.5 m/s, 30 Hz;
/// `wobble` shifts it a little per pose, so trials differ.
pub fn tum_walk(n: usize, wobble: f64) -> String {
    (0..n)
        .map(|i| {
            let t = i as f64 / 30.0;
            let x = t * 0.5 + wobble * (i as f64 * 0.37).sin();
            format!("{t:.6} {x:.6} 0.000000 1.500000 0 0 0 1\n")
        })
        .collect()
}

/// Deterministic, non-repeating bytes: a misplaced byte range cannot compare equal.
pub fn recording_bytes(len: usize) -> Vec<u8> {
    (0..len as u64)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect()
}

/// Sends `head` (a request head, `\r\n\r\n` included) and `body`, then reads the answer until
/// the server closes or 20 s pass: (status, whole answer).
pub fn exchange(addr: SocketAddr, head: &str, body: &[u8]) -> (u16, String) {
    let mut stream = TcpStream::connect(addr).unwrap();
    stream
        .set_read_timeout(Some(Duration::from_secs(20)))
        .unwrap();
    stream.write_all(head.as_bytes()).unwrap();
    let _ = stream.write_all(body);
    read_answer(&mut stream)
}

/// Reads an answer from `stream` until it is whole (head and declared body) or the server
/// closes: (status, whole answer).
pub fn read_answer(stream: &mut TcpStream) -> (u16, String) {
    let mut answer = Vec::new();
    let mut buf = [0u8; 4096];
    loop {
        match stream.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => answer.extend_from_slice(&buf[..n]),
        }
        if complete(&answer) {
            break;
        }
    }
    let text = String::from_utf8_lossy(&answer).into_owned();
    let status = text
        .get(9..12)
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no status in {text:?}"));
    (status, text)
}

/// Whether `answer` holds a whole head and the body its `content-length` declares.
fn complete(answer: &[u8]) -> bool {
    let text = String::from_utf8_lossy(answer);
    let Some((head, body)) = text.split_once("\r\n\r\n") else {
        return false;
    };
    let length = head
        .lines()
        .find_map(|l| {
            let (k, v) = l.split_once(':')?;
            k.eq_ignore_ascii_case("content-length")
                .then(|| v.trim().parse::<usize>().ok())?
        })
        .unwrap_or(0);
    body.len() >= length
}

/// GET `url` with `token` (`None`: no credentials at all): (status, content type, body
/// bytes, up to 64 MiB).
pub fn get_bytes(url: &str, token: Option<&str>) -> (u16, String, Vec<u8>) {
    let agent = if token.is_some() {
        agent()
    } else {
        bare_agent()
    };
    let mut request = agent.get(url);
    if let Some(token) = token {
        request = request.header("authorization", format!("Bearer {token}"));
    }
    let mut response = request.call().expect("request goes through");
    let ct = content_type_of(&response);
    let status = response.status().as_u16();
    let body = response
        .body_mut()
        .with_config()
        .limit(64 << 20)
        .read_to_vec()
        .unwrap_or_default();
    (status, ct, body)
}

/// An answer's `Content-Type` ("" when it has none).
fn content_type_of<B>(response: &ureq::http::Response<B>) -> String {
    response
        .headers()
        .get("content-type")
        .and_then(|v| v.to_str().ok())
        .unwrap_or_default()
        .to_string()
}

/// A client of `server` with the admin token.
pub fn client(server: &ServerHandle) -> sitar_client::Client {
    client_with(server, ADMIN_TOKEN)
}

/// A client of `server` with `token`.
pub fn client_with(server: &ServerHandle, token: &str) -> sitar_client::Client {
    sitar_client::Client::new(&server.url())
        .unwrap()
        .with_timeout(Duration::from_secs(20))
        .with_server_token(token)
        .unwrap()
}

/// Adds `Authorization: Bearer ADMIN_TOKEN` to a request that carries none.
struct AdminUnlessSaidOtherwise;

impl ureq::middleware::Middleware for AdminUnlessSaidOtherwise {
    fn handle(
        &self,
        mut request: ureq::http::Request<ureq::SendBody<'_>>,
        next: ureq::middleware::MiddlewareNext<'_>,
    ) -> Result<ureq::http::Response<ureq::Body>, ureq::Error> {
        let headers = request.headers_mut();
        if !headers.contains_key("authorization") {
            let value = format!("Bearer {ADMIN_TOKEN}");
            headers.insert("authorization", value.parse().expect("header value"));
        }
        next.handle(request)
    }
}

/// A plain HTTP agent for requests the typed client never sends: statuses are answers,
/// not errors; 20 s at most; the admin token unless a request sets `Authorization` itself.
pub fn agent() -> ureq::Agent {
    ureq::Agent::config_builder()
        .http_status_as_error(false)
        .timeout_global(Some(Duration::from_secs(20)))
        .middleware(AdminUnlessSaidOtherwise)
        .build()
        .into()
}

/// Like [`agent`], without any token: for the access-control tests.
pub fn bare_agent() -> ureq::Agent {
    ureq::Agent::config_builder()
        .http_status_as_error(false)
        .timeout_global(Some(Duration::from_secs(20)))
        .max_redirects(0)
        .build()
        .into()
}

/// A raw request: (status, content type, body). For what the typed client never sends.
pub fn raw(
    method: &str,
    url: &str,
    content_type: Option<&str>,
    body: &[u8],
    headers: &[(&str, &str)],
) -> (u16, String, String) {
    let agent = agent();
    let result = match method {
        "GET" | "DELETE" => {
            let mut r = if method == "GET" {
                agent.get(url)
            } else {
                agent.delete(url)
            };
            for (k, v) in headers {
                r = r.header(*k, *v);
            }
            r.call()
        }
        _ => {
            let mut r = match method {
                "PUT" => agent.put(url),
                _ => agent.post(url),
            };
            if let Some(ct) = content_type {
                r = r.header("content-type", ct);
            }
            for (k, v) in headers {
                r = r.header(*k, *v);
            }
            r.send(body)
        }
    };
    let mut response = result.expect("request goes through");
    let status = response.status().as_u16();
    let ct = content_type_of(&response);
    let text = response.body_mut().read_to_string().unwrap_or_default();
    (status, ct, text)
}

/// A multipart/form-data body with one file field, as Unity's `WWWForm.AddBinaryData` sends it.
pub fn multipart(field: &str, file_name: &str, data: &[u8]) -> (String, Vec<u8>) {
    let boundary = "----sitar-test-boundary-7MA4YWxkTrZu0gW";
    let mut body = Vec::new();
    body.extend_from_slice(
        format!(
            "--{boundary}\r\nContent-Disposition: form-data; name=\"{field}\"; filename=\"{file_name}\"\r\nContent-Type: application/octet-stream\r\n\r\n"
        )
        .as_bytes(),
    );
    body.extend_from_slice(data);
    body.extend_from_slice(format!("\r\n--{boundary}--\r\n").as_bytes());
    (format!("multipart/form-data; boundary={boundary}"), body)
}

/// Asserts a JSON error body `{"error":{"code","message"}}` and returns the code.
pub fn error_code(status: u16, ct: &str, body: &str, expected: u16) -> String {
    assert_eq!(status, expected, "body: {body}");
    assert!(
        ct.starts_with("application/json"),
        "content type {ct} for {body}"
    );
    let v: serde_json::Value = serde_json::from_str(body).unwrap_or_else(|e| panic!("{e}: {body}"));
    assert!(
        v["error"]["message"]
            .as_str()
            .is_some_and(|m| !m.is_empty()),
        "{body}"
    );
    v["error"]["code"].as_str().expect("code").to_string()
}

/// Every file under `dir`, relative, sorted.
pub fn tree(dir: &Path) -> Vec<PathBuf> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) {
        if let Ok(entries) = std::fs::read_dir(dir) {
            for e in entries.flatten() {
                let p = e.path();
                if p.is_dir() {
                    walk(root, &p, out);
                } else {
                    out.push(p.strip_prefix(root).unwrap().to_path_buf());
                }
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// The estimator run directly on the same trials, as TUM text like a phone sends
/// them: the reference for the server's results.
pub fn direct_estimate(
    trials: &[sitar_estimator::Trajectory],
    options: &sitar_estimator::EstimateOptions,
) -> sitar_estimator::Estimate {
    let trials: Vec<_> = trials
        .iter()
        .map(|t| sitar_estimator::parse_tum(&tum_text(t), "trial").unwrap())
        .collect();
    sitar_estimator::estimate(&trials, options).unwrap()
}

/// [`direct_estimate`] with `setting` and the defaults, as legacy CSV.
pub fn direct_csv(trials: &[sitar_estimator::Trajectory], setting: &str) -> String {
    let options = sitar_estimator::EstimateOptions {
        setting: setting.parse().unwrap(),
        ..Default::default()
    };
    direct_estimate(trials, &options).to_legacy_csv()
}

/// Waits (polling every 5 ms, up to 60 s) until session `id` has published results over
/// `trials` trials; panics if it publishes more or fails.
pub fn wait_results(client: &sitar_client::Client, id: &str, trials: u32) {
    let deadline = std::time::Instant::now() + Duration::from_secs(60);
    loop {
        let status = client.status(id).expect("status");
        assert!(status.results_trials <= trials, "{status:?}");
        assert_ne!(
            status.state,
            sitar_client::SessionState::Failed,
            "{status:?}"
        );
        if status.results_trials == trials {
            return;
        }
        assert!(std::time::Instant::now() < deadline, "{status:?}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Asserts two results texts are equal without printing kilobytes of numbers.
pub fn assert_same_results(got: &str, expected: &str) {
    if got != expected {
        let line = got.lines().zip(expected.lines()).position(|(a, b)| a != b);
        panic!(
            "results differ ({} vs {} lines), first difference at line {line:?}: {:?} vs {:?}",
            got.lines().count(),
            expected.lines().count(),
            line.and_then(|l| got.lines().nth(l)),
            line.and_then(|l| expected.lines().nth(l))
        );
    }
}

pub fn tum_text(trajectory: &sitar_estimator::Trajectory) -> String {
    let mut out = Vec::new();
    sitar_estimator::write_tum(trajectory, &mut out).unwrap();
    String::from_utf8(out).unwrap()
}

#[path = "../rust/server/src/ingest/minimal_mp4.rs"]
mod mp4_header;

/// ftyp + moov(mvhd v0): the smallest file whose mp4 header says `duration_ms`.
pub fn minimal_mp4(duration_ms: u32) -> Vec<u8> {
    mp4_header::minimal_mp4(1000, duration_ms)
}

/// Writes at `path` an MP4 of `len` bytes shaped as a phone's recording: `ftyp`, an `mdat`
/// of zeros (a sparse file: no disk and no time to write, however long), then `moov` at the
/// end, as Android's muxer writes it, with a header saying `duration_ms`.
pub fn sparse_mp4(path: &Path, len: u64, duration_ms: u32) {
    use std::io::{Seek, SeekFrom};
    let header = minimal_mp4(duration_ms);
    let (ftyp, moov) = header.split_at(20);
    let mdat = len - header.len() as u64;
    assert!(
        mdat >= 8 && mdat <= u64::from(u32::MAX),
        "an mdat of {mdat} bytes"
    );
    let mut file = std::fs::File::create(path).expect("create the recording");
    file.write_all(ftyp).unwrap();
    file.write_all(&(mdat as u32).to_be_bytes()).unwrap();
    file.write_all(b"mdat").unwrap();
    file.seek(SeekFrom::Start(ftyp.len() as u64 + mdat))
        .unwrap();
    file.write_all(moov).unwrap();
    assert_eq!(file.metadata().unwrap().len(), len);
}

/// Parses a legacy CSV into (start, error) rows, checking the header.
pub fn parse_csv(text: &str) -> Vec<(String, f64)> {
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("start,error"));
    lines
        .map(|l| {
            let (s, e) = l.split_once(',').expect("two columns");
            (s.to_string(), e.parse().expect("error is a number"))
        })
        .collect()
}

/// The user's phone on a simulated walk, as the demo records it: start, every frame, the
/// camera image and a depth image at each midpoint, stop (sitar-core's evidence included).
pub fn phone_walk_with_evidence(recording: &sitar_sim::Recording) -> sitar_core::Session {
    use sitar_core::{DepthImage, DisplayRotation, LumaImage, Pose, Session, SessionConfig};
    use sitar_sim::{DepthCamera, LumaCamera};
    let config = SessionConfig::from_json(r#"{"convention":"arcore"}"#).expect("config");
    let mut session = Session::new(config);
    let gt = &recording.walk().ground_truth;
    let (camera, luma_camera, display) = (
        DepthCamera::phone(),
        LumaCamera::phone(),
        DisplayRotation::Deg90,
    );
    let pose = |i: usize| Pose::new(gt.positions[i], gt.orientations[i]);
    let last = gt.len() - 1;
    session.start(gt.stamps[0], pose(0)).expect("start");
    for i in 1..last {
        if session
            .frame(gt.stamps[i], pose(i))
            .expect("frame")
            .is_midpoint()
        {
            let (p, q) = (gt.positions[i], gt.orientations[i]);
            let luma = recording
                .room()
                .render_luma_rotated(p, q, &luma_camera, display, i as u64);
            let (w, h) = (luma_camera.width, luma_camera.height);
            let image = LumaImage::new(&luma, w, h, w).expect("luma image");
            session.image(&image, display).expect("image");
            let depth = recording
                .room()
                .render_depth_mm_rotated(p, q, &camera, display);
            let image = DepthImage::new(&depth, camera.width, camera.height, camera.width * 2)
                .expect("depth image");
            // Glass gives no usable sample: recorded, and the walk goes on.
            let _ = session.depth(&image, &camera.intrinsics, display);
        }
    }
    session.stop(gt.stamps[last], pose(last)).expect("stop");
    session
}

/// Puts `tests/fake_adb.sh` on `PATH` as `adb` (the test double for phones), with its phones
/// under `dir/phones-root` and each trial taking `trial_seconds`; returns that root.
///
/// # Safety
/// It sets `PATH`, `FAKE_ADB_ROOT` and `FAKE_TRIAL_SECONDS` for the whole process: call it
/// before any thread that reads the environment starts (one such test per binary).
pub unsafe fn fake_adb_on_path(dir: &Path, trial_seconds: &str) -> PathBuf {
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fake_adb.sh"),
        bin.join("adb"),
    )
    .unwrap();
    let root = dir.join("phones-root");
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    // SAFETY: the caller's contract: no other thread reads the environment yet.
    unsafe {
        std::env::set_var("PATH", path);
        std::env::set_var("FAKE_ADB_ROOT", &root);
        std::env::set_var("FAKE_TRIAL_SECONDS", trial_seconds);
    }
    root
}
