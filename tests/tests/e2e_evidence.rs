//! Evidence over loopback against the real server: a simulated phone walk (real rendered
//! pixels and depth) is recorded by sitar-core, its session folder is sent by the
//! `UploadJob`, and the server serves thumbnails byte-equal and properties equal to what
//! the phone computed, with the class of the latest results; another app's token gets 404;
//! bad tables are a 422 naming the line; bad images are refused.

use std::path::Path;
use std::time::{Duration, Instant};

use sitar_client::{JobOptions, JobState, NewSession, UploadJob};
use sitar_core::{DepthImage, DisplayRotation, LumaImage, Pose, Session, SessionConfig};
use sitar_sim::{DepthCamera, LumaCamera, Recording};
use sitar_tests::*;

/// The phone side: start, every frame, image and depth at midpoints, stop (as the demo).
fn record_walk(recording: &Recording) -> Session {
    let mut session = Session::new(SessionConfig::from_json(r#"{"convention":"arcore"}"#).unwrap());
    let gt = &recording.walk().ground_truth;
    let camera = DepthCamera::phone();
    let luma_camera = LumaCamera::phone();
    let display = DisplayRotation::Deg90;
    let pose = |i: usize| Pose::new(gt.positions[i], gt.orientations[i]);
    let last = gt.len() - 1;
    session.start(gt.stamps[0], pose(0)).unwrap();
    for i in 1..last {
        if session.frame(gt.stamps[i], pose(i)).unwrap().is_midpoint() {
            let (p, q) = (gt.positions[i], gt.orientations[i]);
            let luma = recording
                .room()
                .render_luma_rotated(p, q, &luma_camera, display, i as u64);
            let (w, h) = (luma_camera.width, luma_camera.height);
            session
                .image(&LumaImage::new(&luma, w, h, w).unwrap(), display)
                .unwrap();
            let depth = recording
                .room()
                .render_depth_mm_rotated(p, q, &camera, display);
            let image =
                DepthImage::new(&depth, camera.width, camera.height, camera.width * 2).unwrap();
            // Glass gives no usable sample: recorded, and the walk goes on.
            let _ = session.depth(&image, &camera.intrinsics, display);
        }
    }
    session.stop(gt.stamps[last], pose(last)).unwrap();
    session
}

fn put(url: &str, token: &str, ct: &str, body: &[u8]) -> (u16, String) {
    let (status, _, body) = raw(
        "PUT",
        url,
        Some(ct),
        body,
        &[("authorization", &format!("Bearer {token}"))],
    );
    (status, body)
}

/// A `PUT` that declares `length` bytes and sends none: the status of the early answer.
fn declared_only_put(url: &str, length: usize) -> u16 {
    use std::io::{Read, Write};
    let rest = url.strip_prefix("http://").expect("http URL");
    let (host, path) = rest.split_at(rest.find('/').expect("a path"));
    let mut stream = std::net::TcpStream::connect(host).unwrap();
    stream
        .set_read_timeout(Some(std::time::Duration::from_secs(10)))
        .unwrap();
    write!(
        stream,
        "PUT {path} HTTP/1.1\r\nHost: {host}\r\nAuthorization: Bearer {APP_TOKEN}\r\n\
         Content-Type: image/jpeg\r\nContent-Length: {length}\r\n\r\n"
    )
    .unwrap();
    let mut head = [0u8; 12];
    stream.read_exact(&mut head).unwrap();
    let line = String::from_utf8_lossy(&head);
    line[9..12]
        .parse()
        .unwrap_or_else(|_| panic!("status line {line:?}"))
}

fn run_job(client: sitar_client::Client, recording: &Path, folder: &Path) -> (String, bool) {
    let mut options = JobOptions::new(NewSession {
        trials: 3,
        setting: "median".into(),
        playback: "sim".into(),
        window_frames: None,
        pose_relation: None,
    });
    options.poll_interval = Duration::from_millis(20);
    options.evidence_dir = Some(folder.to_path_buf());
    let job = UploadJob::start(client, recording, options, |_: &str| {
        Ok::<(), std::convert::Infallible>(())
    })
    .unwrap();
    let started = Instant::now();
    while !job.progress().state.is_finished() && started.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(20));
    }
    let progress = job.progress();
    assert_eq!(progress.state, JobState::Done, "{:?}", progress.error);
    (job.server_id().unwrap(), progress.evidence_sent)
}

#[test]
fn evidence_is_uploaded_by_the_job_and_served_as_the_phone_computed_it() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 40.0, 2));
    let recording = Recording::demo(6.0, 30.0, 5).unwrap();
    let rec_path = dir.path().join("walk.rec");
    std::fs::write(&rec_path, recording.to_bytes()).unwrap();
    let mut phone = record_walk(&recording);
    let folder = dir.path().join("phone");
    phone.save(&folder).unwrap();
    let thumbnails = std::fs::read_dir(folder.join("thumbnails"))
        .unwrap()
        .count();
    assert!(thumbnails >= 10, "{thumbnails} thumbnails");

    let app = client_with(&server, APP_TOKEN);
    let (id, sent) = run_job(app.clone(), &rec_path, &folder);
    assert!(sent, "the job reports the evidence sent");

    // The phone loads the same final results the server joins with.
    phone.load_results(&app.results_json(&id).unwrap()).unwrap();
    let served: serde_json::Value =
        serde_json::from_str(&app.subtrajectories_json(&id).unwrap()).unwrap();
    let subs = served["subtrajectories"].as_array().unwrap();
    let evidence = phone.evidence();
    assert_eq!(subs.len(), evidence.len());
    let mut classes = 0;
    for (k, (sub, e)) in subs.iter().zip(&evidence).enumerate() {
        let span = &phone.subtrajectories()[k];
        assert_eq!(sub["index"], k);
        assert_eq!(sub["start_ns"], span.start_ns);
        assert_eq!(sub["end_ns"].as_i64(), span.end_ns);
        let image = e.image.expect("every midpoint had an image");
        let got = &sub["image"];
        assert_eq!(got["mean_brightness"].as_f64(), Some(image.mean_brightness));
        assert_eq!(got["contrast_std"].as_f64(), Some(image.contrast_std));
        assert_eq!(got["laplacian_var"].as_f64(), Some(image.laplacian_var));
        assert_eq!(got["corners_per_10k"].as_f64(), Some(image.corners_per_10k));
        assert_eq!(got["saturated_share"].as_f64(), Some(image.saturated_share));
        assert_eq!(
            sub["motion"]["linear_speed_m_s"].as_f64(),
            Some(e.motion.linear_speed_m_s)
        );
        assert_eq!(
            sub["motion"]["angular_speed_deg_s"].as_f64(),
            Some(e.motion.angular_speed_deg_s)
        );
        assert_eq!(sub["depth"]["valid"], e.depth.valid);
        assert_eq!(
            sub["depth"]["distance_m"].as_f64(),
            Some(e.depth.distance_m)
        );
        let causes: Vec<&str> = e.causes.names().collect();
        assert_eq!(sub["causes"], serde_json::json!(causes));
        // Error and class: the phone's own lookup of the same results.
        assert_eq!(sub["error"].as_f64(), phone.subtrajectory_error(k as u32));
        if sub["error"].is_f64() {
            classes += 1;
            assert_eq!(sub["class"], phone.subtrajectory_class(k as u32).name());
        }
        // The thumbnail, byte-equal.
        let url = sub["image_url"].as_str().unwrap();
        assert_eq!(
            url,
            format!("/v1/sessions/{id}/subtrajectories/{k}/image.jpg")
        );
        let jpeg = app.subtrajectory_image(&id, k as u32).unwrap();
        assert_eq!(jpeg, phone.thumbnail(k as u32).unwrap(), "thumbnail {k}");
    }
    assert!(
        classes * 2 > subs.len(),
        "{classes} of {} classified",
        subs.len()
    );

    // Another app's token: the same 404 as an unknown session, on every evidence route.
    let other = client_with(&server, APP2_TOKEN);
    assert_eq!(
        other.subtrajectories_json(&id).unwrap_err().status(),
        Some(404)
    );
    assert_eq!(
        other.subtrajectory_image(&id, 0).unwrap_err().status(),
        Some(404)
    );
    assert_eq!(
        other.upload_evidence(&id, &folder).unwrap_err().status(),
        Some(404)
    );
    let base = format!("{}/v1/sessions/{id}", server.url());
    let jpeg = phone.thumbnail(0).unwrap().to_vec();
    let (status, _) = put(
        &format!("{base}/subtrajectories/0/image.jpg"),
        APP2_TOKEN,
        "image/jpeg",
        &jpeg,
    );
    assert_eq!(status, 404);

    // A bad table: 422 naming the line and column; what was stored stays.
    let csv = std::fs::read_to_string(folder.join("evidence.csv")).unwrap();
    let mut lines: Vec<String> = csv.lines().map(str::to_owned).collect();
    lines[3] = lines[3].replacen(",1,", ",1,bright", 1);
    let (status, body) = put(
        &format!("{base}/evidence.csv"),
        APP_TOKEN,
        "text/csv",
        lines.join("\n").as_bytes(),
    );
    assert_eq!(status, 422, "{body}");
    assert!(
        body.contains("line 4") && body.contains("mean_brightness"),
        "{body}"
    );
    let (status, body) = put(
        &format!("{base}/subtrajectories.csv"),
        APP_TOKEN,
        "text/csv",
        b"index,start_ns,end_ns\n0,10,20\n1,twenty,30\n",
    );
    assert_eq!(status, 422, "{body}");
    assert!(
        body.contains("line 3") && body.contains("start_ns"),
        "{body}"
    );
    let again: serde_json::Value =
        serde_json::from_str(&app.subtrajectories_json(&id).unwrap()).unwrap();
    assert_eq!(again, served);

    // Bad images: not a JPEG (422), too large (413), an index beyond the table (404).
    let image_url = |k: &str| format!("{base}/subtrajectories/{k}/image.jpg");
    let (status, body) = put(
        &image_url("0"),
        APP_TOKEN,
        "image/jpeg",
        b"GIF89a not a jpeg",
    );
    assert_eq!(status, 422, "{body}");
    // Too large by its declared length: refused before a byte of the body is read (the
    // body is never sent, so the answer cannot race a client still writing).
    assert_eq!(declared_only_put(&image_url("0"), 600 << 10), 413);
    let beyond = subs.len().to_string();
    assert_eq!(
        put(&image_url(&beyond), APP_TOKEN, "image/jpeg", &jpeg).0,
        404
    );
    assert_eq!(
        put(&image_url("../0"), APP_TOKEN, "image/jpeg", &jpeg).0,
        404
    );
    assert_eq!(put(&image_url("-1"), APP_TOKEN, "image/jpeg", &jpeg).0, 404);
    // The stored thumbnail is still the phone's.
    assert_eq!(app.subtrajectory_image(&id, 0).unwrap(), jpeg);
    server.stop();
}

#[test]
fn a_session_folder_without_evidence_still_gets_its_results() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 40.0, 2));
    let rec = sim_recording(dir.path(), "walk.rec", 3.0, 9);
    let empty = dir.path().join("no-evidence");
    std::fs::create_dir_all(&empty).unwrap();
    let app = client_with(&server, APP_TOKEN);
    let (id, sent) = run_job(app.clone(), &rec, &empty);
    assert!(!sent);
    let served: serde_json::Value =
        serde_json::from_str(&app.subtrajectories_json(&id).unwrap()).unwrap();
    assert_eq!(served["subtrajectories"], serde_json::json!([]));
    assert_eq!(
        app.subtrajectory_image(&id, 0).unwrap_err().status(),
        Some(404)
    );
    server.stop();
}
