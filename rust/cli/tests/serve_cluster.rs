//! `sitar serve --database postgres://… --store s3://…` as an operator runs it: the real
//! binary on loopback against a real Postgres and a real S3-compatible store (SeaweedFS,
//! started by `scripts/cluster-services`). A sim session goes upload → playback → done, and
//! its results are byte-identical to the embedded server's for the same recording. Without
//! `SITAR_TEST_DATABASE_URL` and `SITAR_TEST_S3_URL` the tests print SKIPPED.
// The cluster backends are in a build with the `cluster` feature only.
#![cfg(feature = "cluster")]

mod support;

use std::path::Path;
use std::process::Command;
use std::time::Duration;

use support::cluster::Cluster;
use support::process::{Serving, admin_token, create_token, upload_offset};
use support::run::fails;
use support::sessions::sim_session;

/// Runs a sim session of `trials` trials on `recording`; its status, CSV and JSON results.
fn run_session(
    client: &sitar_client::Client,
    recording: &Path,
    trials: u32,
) -> (String, sitar_client::SessionStatus, String, String) {
    let id = sim_session(client, recording, trials, "trim_mean_30");
    let status = client
        .wait(
            &id,
            Duration::from_millis(50),
            Duration::from_secs(120),
            &mut |_| {},
        )
        .unwrap();
    let csv = client.results_csv(&id).unwrap();
    let json = client.results_json(&id).unwrap();
    (id, status, csv, json)
}

/// Every regular file under `dir`.
fn files_under(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    let mut pending = vec![dir.to_path_buf()];
    while let Some(dir) = pending.pop() {
        for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            let path = entry.path();
            if path.is_dir() {
                pending.push(path);
            } else {
                out.push(path);
            }
        }
    }
    out
}

#[test]
fn a_cluster_instance_plays_a_session_as_the_embedded_one_does() {
    let Some(cluster) = Cluster::fresh("serve_cluster") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let recording = dir.path().join("walk.rec");
    let rec = sitar_sim::Recording::demo(6.0, 30.0, 11).unwrap();
    std::fs::write(&recording, rec.to_bytes()).unwrap();

    // The embedded server: the reference.
    let embedded_data = dir.path().join("embedded");
    let embedded = Serving::sim(&embedded_data, &[]);
    let client = embedded.client(&admin_token(&embedded_data));
    let (_, status, csv, json) = run_session(&client, &recording, 5);
    assert_eq!(status.state, sitar_client::SessionState::Done, "{status:?}");
    drop(embedded);

    // The cluster instance: the first on an empty database writes the admin token.
    let a_data = dir.path().join("instance-a");
    let mut a = cluster.serve(&a_data, &[]);
    a.wait_for("metadata in Postgres", Duration::from_secs(60));
    let admin = admin_token(&a_data);
    // `sitar token create --database` makes a token the running instance accepts.
    let app = create_token(&["--database", &cluster.database], "app", "lab-phone");
    let (id, status, cluster_csv, cluster_json) = run_session(&a.client(&app), &recording, 5);
    assert_eq!(status.state, sitar_client::SessionState::Done, "{status:?}");
    assert_eq!(status.results_trials, 5, "{status:?}");
    assert_eq!(
        cluster_csv, csv,
        "CSV results differ from the embedded server's"
    );
    assert_eq!(
        cluster_json, json,
        "JSON results differ from the embedded server's"
    );
    // Nothing of the session is in the instance's folder, and no database either (the worker
    // store, hosts and leases, is in Postgres too).
    let kept: Vec<_> = files_under(&a_data.join("sessions"));
    assert!(kept.is_empty(), "{kept:?}");
    assert!(!a_data.join("sitar.db").exists());

    // A second instance on the same database and store: no admin token of its own, and it
    // answers for the session the first one played.
    let b_data = dir.path().join("instance-b");
    let b = cluster.serve(&b_data, &[]);
    assert!(!b_data.join("admin.token").exists());
    let from_b = b.client(&admin);
    assert_eq!(from_b.results_csv(&id).unwrap(), csv);
    assert_eq!(
        from_b.status(&id).unwrap().state,
        sitar_client::SessionState::Done
    );
    // A recording begun on A is resumed on B: the first half's part is in the bucket.
    let bytes = std::fs::read(&recording).unwrap();
    let resumed = a.client(&app);
    let id2 = resumed
        .create_session(&sitar_client::NewSession {
            trials: 2,
            setting: "trim_mean_30".into(),
            playback: "sim".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    let half = bytes.len() / 2;
    let total = bytes.len();
    let first = put_range(&a.url, &app, &id2, &bytes[..half], 0, total);
    assert_eq!(first, "200", "the first half is kept for a resume");
    let offset = head_offset(&b.url, &app, &id2);
    assert_eq!(offset, half, "instance B sees what A kept");
    let second = put_range(&b.url, &app, &id2, &bytes[half..], half, total);
    assert_eq!(second, "202");
    let done = b
        .client(&app)
        .wait(
            &id2,
            Duration::from_millis(50),
            Duration::from_secs(120),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(done.state, sitar_client::SessionState::Done, "{done:?}");

    // Deleted through B, it is gone for A too.
    from_b.delete_session(&id).unwrap();
    assert_eq!(
        a.client(&admin).status(&id).unwrap_err().status(),
        Some(404)
    );
}

/// `PUT`s `chunk` as bytes `offset…` of a `total`-byte recording of session `id` (one
/// upload key); the HTTP status.
fn put_range(
    url: &str,
    token: &str,
    id: &str,
    chunk: &[u8],
    offset: usize,
    total: usize,
) -> String {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("chunk");
    std::fs::write(&file, chunk).unwrap();
    let range = format!(
        "Content-Range: bytes {offset}-{}/{total}",
        offset + chunk.len() - 1
    );
    let out = Command::new("curl")
        .args(["-s", "-o", "/dev/null", "-w", "%{http_code}", "-T"])
        .arg(&file)
        .args(["-H", &format!("Authorization: Bearer {token}")])
        .args(["-H", "Idempotency-Key: cluster-resume", "-H", &range])
        .arg(format!("{url}/v1/sessions/{id}/recording"))
        .output()
        .expect("curl");
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

/// The `Upload-Offset` a `HEAD` of session `id`'s recording answers for the upload key.
fn head_offset(url: &str, token: &str, id: &str) -> usize {
    upload_offset(url, token, id, "cluster-resume")
}

#[test]
fn an_instance_killed_during_an_upload_leaves_nothing_partial() {
    let Some(cluster) = Cluster::fresh("cluster_crash") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let recording = dir.path().join("walk.rec");
    // 60 s: about 280 KB, far more than curl sends in one go.
    let rec = sitar_sim::Recording::demo(60.0, 30.0, 5).unwrap();
    std::fs::write(&recording, rec.to_bytes()).unwrap();
    let size = std::fs::metadata(&recording).unwrap().len();
    let data = dir.path().join("instance");
    let mut a = cluster.serve(&data, &[]);
    let admin = admin_token(&data);
    let id = a
        .client(&admin)
        .create_session(&sitar_client::NewSession {
            trials: 2,
            setting: "trim_mean_30".into(),
            playback: "sim".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap();
    // A body sent over about 8 s; the instance is killed (SIGKILL) after 1.5 s of it.
    let mut upload = Command::new("curl")
        .args([
            "-s",
            "-o",
            "/dev/null",
            "--limit-rate",
            &(size / 8).max(1).to_string(),
        ])
        .arg("-T")
        .arg(&recording)
        .args(["-H", &format!("Authorization: Bearer {admin}")])
        .args(["-H", "Idempotency-Key: crash"])
        .arg(format!("{}/v1/sessions/{id}/recording", a.url))
        .spawn()
        .expect("curl");
    std::thread::sleep(Duration::from_millis(1500));
    a.child.kill().unwrap();
    a.child.wait().unwrap();
    let _ = upload.wait();
    // Started again on the same folder: the staged bytes are gone, nothing of the request
    // is in the bucket, and the session still waits for its recording.
    let b = cluster.serve(&data, &[]);
    assert!(
        files_under(&data.join("tmp")).is_empty(),
        "{:?}",
        files_under(&data.join("tmp"))
    );
    let client = b.client(&admin);
    assert_eq!(
        client.status(&id).unwrap().state,
        sitar_client::SessionState::Created
    );
    assert_eq!(upload_offset(&b.url, &admin, &id, "crash"), 0);
    // The client sends it again, whole: the session plays to the end.
    client
        .upload_recording(&id, &recording, &mut |_, _| {})
        .unwrap();
    let done = client
        .wait(
            &id,
            Duration::from_millis(50),
            Duration::from_secs(120),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(done.state, sitar_client::SessionState::Done, "{done:?}");
}

#[test]
fn a_store_that_does_not_answer_is_named_at_start() {
    let dir = tempfile::tempdir().unwrap();
    let serve = [
        "serve",
        "--addr",
        "127.0.0.1:0",
        "--data",
        dir.path().to_str().unwrap(),
    ];
    let err = fails(
        &[
            &serve[..],
            &["--database", "postgres://sitar:hunter2@127.0.0.1:9/nowhere"],
        ]
        .concat(),
    );
    assert!(err.contains("127.0.0.1:9"), "{err}");
    assert!(
        !err.contains("hunter2"),
        "the password is never shown: {err}"
    );
    let err = fails(&[&serve[..], &["--store", "ftp://bucket/x"]].concat());
    assert!(err.contains("s3://BUCKET/PREFIX"), "{err}");
}
