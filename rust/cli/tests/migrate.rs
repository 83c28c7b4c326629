//! `sitar migrate` as an operator runs it: an embedded installation made by the real
//! `sitar serve` (tokens of every role, a sim session with a share link, a phone's session
//! with evidence in a venue, an `upload` session, a kept half upload, a 40 MiB recording)
//! copied into a real Postgres and a real S3-compatible store (SeaweedFS, started by
//! `scripts/cluster-services`), then served by `sitar serve --database … --store …`: the same
//! tokens work and every answer about every session is byte-identical to the embedded
//! server's. A second run copies nothing; a run killed with SIGKILL mid-copy completes when
//! run again; a running server, a database holding other data and a changed side are refused
//! naming them. Without `SITAR_TEST_DATABASE_URL` and `SITAR_TEST_S3_URL` it prints SKIPPED.
// The cluster backends are in a build with the `cluster` feature only.
#![cfg(feature = "cluster")]

mod support;

use std::path::Path;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use sitar_client::{JobOptions, JobState, NewSession, SessionFrame, UploadJob};

use support::cluster::{fresh_database, services};
use support::process::{Proc, Serving};
use support::run::sitar;

/// Requests to an instance beyond its client.
trait Requests {
    fn get(&self, path: &str, token: &str) -> (u16, Vec<u8>);
    fn call(&self, method: &str, path: &str, token: &str, body: &str) -> (u16, serde_json::Value);
}

impl Requests for Serving {
    /// GET `path` with `token`: status and body bytes.
    fn get(&self, path: &str, token: &str) -> (u16, Vec<u8>) {
        let (status, _, body) = sitar_tests::get_bytes(&format!("{}{path}", self.url), Some(token));
        (status, body)
    }

    /// A JSON request with `token`: status and answer.
    fn call(&self, method: &str, path: &str, token: &str, body: &str) -> (u16, serde_json::Value) {
        let auth = format!("Bearer {token}");
        let (status, _, text) = sitar_tests::raw(
            method,
            &format!("{}{path}", self.url),
            Some("application/json"),
            body.as_bytes(),
            &[("authorization", &auth)],
        );
        (status, serde_json::from_str(&text).unwrap_or_default())
    }
}

/// `psql URL -At -c SQL`: its output, trimmed; panics naming the error.
fn psql(url: &str, sql: &str) -> String {
    let out = Command::new("psql")
        .args([url, "-X", "-q", "-At", "-c", sql])
        .output()
        .expect("psql");
    assert!(
        out.status.success(),
        "{sql}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// `sitar migrate --data DATA --database DB --store STORE`.
fn migrate(data: &Path, database: &str, store: &str) -> Output {
    let data = data.to_str().unwrap();
    sitar(&[
        "migrate",
        "--data",
        data,
        "--database",
        database,
        "--store",
        store,
    ])
}

/// `sitar token create --data DATA --role ROLE --name NAME`: the token.
fn token(data: &Path, role: &str, name: &str) -> String {
    let out = sitar(&[
        "token",
        "create",
        "--data",
        data.to_str().unwrap(),
        "--role",
        role,
        "--name",
        name,
    ]);
    assert!(out.status.success(), "{}", text(&out));
    String::from_utf8(out.stdout).unwrap().trim().to_string()
}

fn new_session(trials: u32, playback: &str) -> NewSession {
    NewSession {
        trials,
        setting: "trim_mean_30".into(),
        playback: playback.into(),
        window_frames: None,
        pose_relation: None,
    }
}

fn wait_done(client: &sitar_client::Client, id: &str) {
    let status = client
        .wait(
            id,
            Duration::from_millis(50),
            Duration::from_secs(120),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(status.state, sitar_client::SessionState::Done, "{status:?}");
}

/// `PUT`s the first `half` of `bytes` as a resumable upload (key `half`) of session `id`.
fn put_half(url: &str, token: &str, id: &str, bytes: &[u8], half: usize) {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("chunk");
    std::fs::write(&file, &bytes[..half]).unwrap();
    let range = format!("Content-Range: bytes 0-{}/{}", half - 1, bytes.len());
    let out = Command::new("curl")
        .args(["-s", "-o", "/dev/null", "-w", "%{http_code}", "-T"])
        .arg(&file)
        .args(["-H", &format!("Authorization: Bearer {token}")])
        .args(["-H", "Idempotency-Key: half", "-H", &range])
        .arg(format!("{url}/v1/sessions/{id}/recording"))
        .output()
        .expect("curl");
    assert_eq!(String::from_utf8_lossy(&out.stdout), "200");
}

/// The `Upload-Offset` a `HEAD` of session `id`'s recording answers for key `half`.
fn kept_offset(url: &str, token: &str, id: &str) -> String {
    let out = Command::new("curl")
        .args(["-s", "-I", "-H", &format!("Authorization: Bearer {token}")])
        .args(["-H", "Idempotency-Key: half"])
        .arg(format!("{url}/v1/sessions/{id}/recording"))
        .output()
        .expect("curl");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .find_map(|l| {
            let (name, value) = l.split_once(':')?;
            name.eq_ignore_ascii_case("upload-offset")
                .then(|| value.trim().to_string())
        })
        .unwrap_or_default()
}

/// The names and roles `sitar token list` prints (not when they were last used).
fn token_names(args: &[&str]) -> Vec<String> {
    let out = sitar(&[&["token", "list"], args].concat());
    assert!(out.status.success(), "{}", text(&out));
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| l.split_whitespace().take(2).collect::<Vec<_>>().join(" "))
        .collect()
}

/// The `copied` column of `table` in a summary.
fn copied(summary: &str, table: &str) -> usize {
    summary
        .lines()
        .find_map(|l| {
            let fields: Vec<&str> = l.split_whitespace().collect();
            (fields.len() == 5 && fields[0] == table).then(|| fields[2].parse().ok())?
        })
        .unwrap_or_else(|| panic!("no row {table} in {summary}"))
}

#[test]
fn an_embedded_installation_moves_into_the_cluster_stores() {
    let Some((database, store)) = services("migrate") else {
        return;
    };
    let (Some(db_a), Some(db_b), Some(db_c)) = (
        fresh_database("migrate_a", &database),
        fresh_database("migrate_b", &database),
        fresh_database("migrate_c", &database),
    ) else {
        return;
    };
    let pid = std::process::id();
    let (store_a, store_b, store_c) = (
        format!("{store}/migrate-a-{pid}"),
        format!("{store}/migrate-b-{pid}"),
        format!("{store}/migrate-c-{pid}"),
    );
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("embedded");

    // The embedded installation, made by the real server.
    let embedded = Serving::sim(&data, &[]);
    let admin = std::fs::read_to_string(data.join("admin.token"))
        .unwrap()
        .trim()
        .to_string();
    let phone_a = token(&data, "app", "phone-a");
    let phone_b = token(&data, "app", "phone-b");
    let host = token(&data, "worker", "host-1");
    let old = token(&data, "app", "old");
    assert!(
        sitar(&["token", "revoke", "--data", data.to_str().unwrap(), "old"])
            .status
            .success()
    );
    let (status, venue) = embedded.call(
        "POST",
        "/v1/venues",
        &admin,
        r#"{"name":"Hall","anchor":"hall","cell_m":0.25}"#,
    );
    assert_eq!(status, 201, "{venue}");
    let venue = venue["id"].as_str().unwrap().to_string();
    let (status, _) = embedded.call(
        "PUT",
        &format!("/v1/venues/{venue}/members/phone-b"),
        &admin,
        "",
    );
    assert!((200..300).contains(&status), "{status}");

    // 1: a sim session played to the end, with a share link.
    let recording = dir.path().join("walk.rec");
    let rec = sitar_sim::Recording::demo(6.0, 30.0, 11).unwrap();
    std::fs::write(&recording, rec.to_bytes()).unwrap();
    let a = embedded.client(&phone_a);
    let sim = a.create_session(&new_session(4, "sim")).unwrap();
    a.upload_recording(&sim, &recording, &mut |_, _| {})
        .unwrap();
    wait_done(&a, &sim);
    let (status, share) = embedded.call("POST", &format!("/v1/sessions/{sim}/share"), &phone_a, "");
    assert_eq!(status, 201, "{share}");
    let share = share["url"]
        .as_str()
        .unwrap()
        .rsplit('/')
        .next()
        .unwrap()
        .to_string();

    // 2: a phone's session with its log and evidence, in the venue.
    let folder = dir.path().join("walk.rec.session");
    sitar_tests::phone_walk_with_evidence(&rec)
        .save(&folder)
        .unwrap();
    let mut options = JobOptions::new(new_session(3, "sim"));
    options.poll_interval = Duration::from_millis(20);
    options.evidence_dir = Some(folder);
    options.frame = SessionFrame {
        convention: Some("arcore".into()),
        venue: Some(venue.clone()),
    };
    let job = UploadJob::start(embedded.client(&phone_b), &recording, options, |_: &str| {
        Ok::<(), std::convert::Infallible>(())
    })
    .unwrap();
    let started = Instant::now();
    while !job.progress().state.is_finished() && started.elapsed() < Duration::from_secs(120) {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(
        job.progress().state,
        JobState::Done,
        "{:?}",
        job.progress().error
    );
    let phone = job.server_id().unwrap();

    // 3: trials from an outside SLAM run.
    let upload = a.create_session(&new_session(3, "upload")).unwrap();
    for wobble in [0.0, 0.01, 0.03] {
        a.upload_trial(&upload, &sitar_tests::tum_walk(300, wobble))
            .unwrap();
    }
    a.start_estimate(&upload).unwrap();
    wait_done(&a, &upload);

    // 4: a recording upload that broke off halfway (its prefix is kept for a resume).
    let b = embedded.client(&phone_b);
    let half = b.create_session(&new_session(2, "sim")).unwrap();
    let bytes = std::fs::read(&recording).unwrap();
    put_half(&embedded.url, &phone_b, &half, &bytes, bytes.len() / 2);

    // 5: a 40 MiB recording (an upload session), last: the copy is killed while it goes.
    let big_file = dir.path().join("big.rec");
    std::fs::write(&big_file, sitar_tests::recording_bytes(40 << 20)).unwrap();
    let admin_client = embedded.client(&admin);
    let big = admin_client
        .create_session(&new_session(2, "upload"))
        .unwrap();
    admin_client
        .upload_recording(&big, &big_file, &mut |_, _| {})
        .unwrap();
    for wobble in [0.0, 0.02] {
        admin_client
            .upload_trial(&big, &sitar_tests::tum_walk(200, wobble))
            .unwrap();
    }
    admin_client.start_estimate(&big).unwrap();
    wait_done(&admin_client, &big);

    // What the embedded server answers: (path, token, status, bytes).
    let mut paths: Vec<(String, String)> = vec![
        ("/v1/sessions".into(), admin.clone()),
        ("/v1/sessions".into(), phone_a.clone()),
        (format!("/v1/venues/{venue}"), phone_b.clone()),
        ("/v1/venues".into(), admin.clone()),
        (format!("/v1/venues/{venue}/map.json"), admin.clone()),
        (format!("/share/{share}/results.json"), admin.clone()),
        ("/v1/sessions".into(), host.clone()),
        ("/v1/sessions".into(), old.clone()),
    ];
    for (id, token) in [
        (&sim, &phone_a),
        (&phone, &phone_b),
        (&upload, &phone_a),
        (&half, &phone_b),
        (&big, &admin),
    ] {
        for route in [
            "",
            "/results.csv",
            "/results.json",
            "/subtrajectories",
            "/subtrajectories/0/image.jpg",
            "/subtrajectories/5/image.jpg",
            "/trajectory.tum",
            "/trials.zip",
            "/scene.json",
            "/report?download=1",
        ] {
            paths.push((format!("/v1/sessions/{id}{route}"), token.clone()));
        }
    }
    let answers: Vec<(u16, Vec<u8>)> = paths.iter().map(|(p, t)| embedded.get(p, t)).collect();
    assert_eq!(answers[6].0, 403, "a worker token reads no sessions");
    assert_eq!(answers[7].0, 401, "a revoked token is refused");
    let ok = answers.iter().filter(|(s, _)| *s == 200).count();
    assert!(ok >= 30, "{ok} answers with content");
    let offset = kept_offset(&embedded.url, &phone_b, &half);
    assert_eq!(offset, (bytes.len() / 2).to_string());
    let tokens = token_names(&["--data", data.to_str().unwrap()]);
    assert_eq!(tokens.len(), 5, "{tokens:?}");

    // A running server is refused: it holds the database open.
    let out = migrate(&data, &db_a, &store_a);
    assert!(!out.status.success());
    assert!(text(&out).contains("a server"), "{}", text(&out));
    assert_eq!(
        psql(&db_a, "SELECT to_regclass('sessions') IS NULL"),
        "t",
        "nothing written"
    );
    drop(embedded);

    // A database that holds other data (another installation's admin token under id 1).
    let out = sitar(&[
        "token",
        "create",
        "--database",
        &db_c,
        "--role",
        "admin",
        "--name",
        "admin",
    ]);
    assert!(out.status.success(), "{}", text(&out));
    let out = migrate(&data, &db_c, &store_c);
    assert!(!out.status.success());
    let said = text(&out);
    assert!(
        said.contains("other data") && said.contains("tokens row id=1"),
        "{said}"
    );
    assert!(!said.contains(&admin), "no token is ever printed: {said}");
    assert_eq!(psql(&db_c, "SELECT COUNT(*) FROM sessions"), "0");

    // A: copied, verified; a second run copies nothing.
    let started = Instant::now();
    let out = migrate(&data, &db_a, &store_a);
    let took = started.elapsed();
    assert!(out.status.success(), "{}", text(&out));
    let said = text(&out);
    assert!(said.contains("verified"), "{said}");
    println!("first copy in {took:?}:\n{said}");
    let started = Instant::now();
    let out = migrate(&data, &db_a, &store_a);
    println!("second run (nothing to copy) in {:?}", started.elapsed());
    assert!(out.status.success(), "{}", text(&out));
    assert!(text(&out).contains("nothing copied"), "{}", text(&out));
    assert_eq!(psql(&db_a, "SELECT COUNT(*) FROM sessions"), "5");
    assert_eq!(psql(&db_a, "SELECT COUNT(*) FROM tokens"), "4");

    // B: killed (SIGKILL) while the 40 MiB recording goes up, then run again.
    let data_arg = data.to_str().unwrap();
    let mut run = Proc::sitar(&[
        "migrate",
        "--data",
        data_arg,
        "--database",
        &db_b,
        "--store",
        &store_b,
    ]);
    run.wait_for(&format!("session {big} ("), Duration::from_secs(120));
    // The large session's first file goes quickly, its recording (40 MiB, about 1 s here)
    // takes a while: killed soon after the line, the run is in the middle of it.
    std::thread::sleep(Duration::from_millis(30));
    run.child.kill().unwrap();
    let status = run.child.wait().unwrap();
    assert!(!status.success(), "killed mid-copy");
    assert_eq!(
        psql(
            &db_b,
            &format!("SELECT COUNT(*) FROM sessions WHERE id = '{big}'")
        ),
        "0",
        "the killed run had not copied the large session's rows"
    );
    let out = migrate(&data, &db_b, &store_b);
    assert!(out.status.success(), "{}", text(&out));
    let said = text(&out);
    assert!(said.contains("verified"), "{said}");
    // Only what the killed run had not finished: the large session's rows.
    assert_eq!(copied(&said, "tokens"), 0, "{said}");
    assert_eq!(copied(&said, "sessions"), 1, "{said}");
    let out = migrate(&data, &db_b, &store_b);
    assert!(text(&out).contains("nothing copied"), "{}", text(&out));

    // A row changed in the database since: refused, naming the session and the column.
    psql(
        &db_b,
        &format!("UPDATE sessions SET stop_reason = 'tampered' WHERE id = '{upload}'"),
    );
    let out = migrate(&data, &db_b, &store_b);
    assert!(!out.status.success());
    let said = text(&out);
    assert!(
        said.contains(&upload) && said.contains("stop_reason"),
        "{said}"
    );
    psql(
        &db_b,
        &format!("UPDATE sessions SET stop_reason = NULL WHERE id = '{upload}'"),
    );
    // A file changed here since: exits non-zero naming it.
    let results = data.join("sessions").join(&upload).join("results.csv");
    let kept = std::fs::read(&results).unwrap();
    std::fs::write(&results, b"start,error\n").unwrap();
    let out = migrate(&data, &db_b, &store_b);
    assert!(!out.status.success());
    let said = text(&out);
    assert!(
        said.contains(&format!("sessions/{upload}/results.csv")) && said.contains("SHA-256"),
        "{said}"
    );
    std::fs::write(&results, kept).unwrap();
    assert!(migrate(&data, &db_b, &store_b).status.success());

    // The cluster serves A: the same tokens, byte-identical answers.
    let instance = dir.path().join("instance");
    let cluster = Serving::sim(&instance, &["--database", &db_a, "--store", &store_a]);
    assert!(
        !instance.join("admin.token").exists(),
        "the admin token is the migrated one"
    );
    for ((path, token), (status, body)) in paths.iter().zip(&answers) {
        let (got_status, got) = cluster.get(path, token);
        assert_eq!(got_status, *status, "{path}");
        assert!(
            got == *body,
            "{path}: the cluster's answer differs from the embedded server's"
        );
    }
    assert_eq!(kept_offset(&cluster.url, &phone_b, &half), offset);
    // The worker token does what it did: register a playback host, and nothing else.
    let host_body = r#"{"name":"lab-host","playback":"sim","phones":["sim:0"]}"#;
    let (status, answer) = cluster.call("POST", "/v1/worker/hosts", &host, host_body);
    assert_eq!(status, 201, "{answer}");
    let (status, _) = cluster.call("POST", "/v1/worker/hosts", &phone_a, host_body);
    assert_eq!(status, 403);
    assert_eq!(token_names(&["--database", &db_a]), tokens);
    // Ids the embedded store handed out are never handed out again (a revoked token's too).
    let out = sitar(&[
        "token",
        "create",
        "--database",
        &db_a,
        "--role",
        "app",
        "--name",
        "new",
    ]);
    assert!(out.status.success(), "{}", text(&out));
    assert_eq!(psql(&db_a, "SELECT id FROM tokens WHERE name = 'new'"), "6");
}
