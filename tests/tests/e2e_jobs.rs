//! Jobs as a bounded, fair queue over loopback: the server's playback kinds and trial cap,
//! FIFO order per token with round-robin between tokens and the position in the status,
//! cancel and delete of queued and playing sessions, the queue after a restart (a bad row
//! never stops the server), and no crossed wires (legacy results, idempotency keys).

use std::path::Path;
use std::time::{Duration, Instant};

use serde_json::Value;
use sitar_tests::*;

fn bearer(token: &str) -> String {
    format!("Bearer {token}")
}

/// `POST {base}{path}` with a JSON body as `token`: (status, body).
fn post_json(
    base: &str,
    path: &str,
    token: &str,
    body: &str,
    headers: &[(&str, &str)],
) -> (u16, String) {
    let auth = bearer(token);
    let mut all = vec![("authorization", auth.as_str())];
    all.extend_from_slice(headers);
    let (status, _, text) = raw(
        "POST",
        &format!("{base}{path}"),
        Some("application/json"),
        body.as_bytes(),
        &all,
    );
    (status, text)
}

/// A new session as `token`; its id.
fn create(base: &str, token: &str, body: &str) -> String {
    let (status, text) = post_json(base, "/v1/sessions", token, body, &[]);
    assert_eq!(status, 201, "{text}");
    let doc: Value = serde_json::from_str(&text).unwrap();
    doc["id"].as_str().unwrap().to_owned()
}

fn upload(base: &str, token: &str, id: &str, recording: &Path) {
    let bytes = std::fs::read(recording).unwrap();
    let auth = bearer(token);
    let (status, _, text) = raw(
        "PUT",
        &format!("{base}/v1/sessions/{id}/recording"),
        Some("application/octet-stream"),
        &bytes,
        &[("authorization", &auth)],
    );
    assert!(
        status == 200 || status == 201 || status == 202,
        "{status} {text}"
    );
}

/// `METHOD {base}/v1/sessions/{id}` with no body as `token`: (status, body).
fn on_session(method: &str, base: &str, token: &str, id: &str) -> (u16, String) {
    let auth = bearer(token);
    let (code, _, text) = raw(
        method,
        &format!("{base}/v1/sessions/{id}"),
        None,
        b"",
        &[("authorization", &auth)],
    );
    (code, text)
}

/// `DELETE {base}/v1/sessions/{id}` as `token`, which must answer 200.
fn delete(base: &str, token: &str, id: &str) {
    let (code, text) = on_session("DELETE", base, token, id);
    assert_eq!(code, 200, "{text}");
}

/// `GET /v1/sessions/{id}` as `token`: (status, document).
fn status(base: &str, token: &str, id: &str) -> (u16, Value) {
    let (code, text) = on_session("GET", base, token, id);
    (code, serde_json::from_str(&text).unwrap_or(Value::Null))
}

/// Polls (every 20 ms, up to `limit`) until `done` holds for the session's status.
fn wait_for(
    base: &str,
    token: &str,
    id: &str,
    limit: Duration,
    done: impl Fn(&Value) -> bool,
) -> Value {
    let started = Instant::now();
    loop {
        let (code, doc) = status(base, token, id);
        assert_eq!(code, 200, "{doc}");
        if done(&doc) {
            return doc;
        }
        assert!(started.elapsed() < limit, "waited {limit:?}: {doc}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn finished(doc: &Value) -> bool {
    doc["state"] == "done" || doc["state"] == "failed"
}

#[test]
fn kinds_and_trials_beyond_what_the_server_offers_are_422s_that_name_the_bound() {
    let dir = tempfile::tempdir().unwrap();
    // An adb server: sim sessions only with --allow-sim.
    let server = start(sitar_server::ServerConfig::new(dir.path().join("adb")));
    let base = server.url();
    refused(&base, r#"{"playback":"sim","trials":1000}"#, &[]);
    refused(
        &base,
        r#"{"playback":"sim","trials":3}"#,
        &["adb and upload", "--allow-sim"],
    );
    refused(
        &base,
        r#"{"playback":"upload","trials":101}"#,
        &["cap of 100", "--max-trials"],
    );
    create(&base, APP_TOKEN, r#"{"playback":"upload","trials":100}"#);
    create(&base, APP_TOKEN, r#"{"playback":"adb","trials":100}"#);
    server.stop();

    let mut config = sitar_server::ServerConfig::new(dir.path().join("allowed"));
    config.allow_sim = true;
    config.max_trials = 7;
    let server = start(config);
    let base = server.url();
    create(&base, APP_TOKEN, r#"{"playback":"sim","trials":7}"#);
    refused(&base, r#"{"playback":"sim","trials":8}"#, &["cap of 7"]);
}

/// `POST /v1/sessions` with `body` is a 422 whose text names each of `named`.
fn refused(base: &str, body: &str, named: &[&str]) {
    let (code, text) = post_json(base, "/v1/sessions", APP_TOKEN, body, &[]);
    assert_eq!(code, 422, "{body}: {text}");
    for name in named {
        assert!(text.contains(name), "{body}: {name} not in {text}");
    }
}

#[test]
fn queued_sessions_wait_their_turn_show_their_place_and_cancel_or_delete() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    // 3 s at 3×: one trial a second; one worker, one session per token at a time.
    let mut config = sim_config(&data, 3.0, 1);
    config.playback_workers = 1;
    config.jobs_per_token = 1;
    let server = start(config);
    let base = server.url();
    let rec = sim_recording(dir.path(), "walk.rec", 3.0, 5);

    let a1 = create(&base, APP_TOKEN, r#"{"playback":"sim","trials":40}"#);
    upload(&base, APP_TOKEN, &a1, &rec);
    wait_for(&base, APP_TOKEN, &a1, Duration::from_secs(10), |d| {
        d["state"] == "playing"
    });
    let a2 = create(&base, APP_TOKEN, r#"{"playback":"sim","trials":3}"#);
    let a3 = create(&base, APP_TOKEN, r#"{"playback":"sim","trials":3}"#);
    let b1 = create(&base, APP2_TOKEN, r#"{"playback":"sim","trials":2}"#);
    for (token, id) in [(APP_TOKEN, &a2), (APP_TOKEN, &a3), (APP2_TOKEN, &b1)] {
        upload(&base, token, id, &rec);
    }
    // Round-robin: the other token's session comes before this token's second one.
    let place = |token, id: &str| status(&base, token, id).1["queue_position"].clone();
    assert_eq!(place(APP_TOKEN, &a1), Value::Null);
    assert_eq!(place(APP_TOKEN, &a2), 1);
    assert_eq!(place(APP2_TOKEN, &b1), 2);
    assert_eq!(place(APP_TOKEN, &a3), 3);
    assert_eq!(status(&base, APP_TOKEN, &a3).1["state"], "uploaded");

    // Another token can neither cancel nor delete it: the same 404 as an unknown id.
    let (code, _) = post_json(
        &base,
        &format!("/v1/sessions/{a3}/cancel"),
        APP2_TOKEN,
        "",
        &[],
    );
    assert_eq!(code, 404);
    // Cancelling a queued session with no trials fails it with the reason.
    let (code, text) = post_json(
        &base,
        &format!("/v1/sessions/{a3}/cancel"),
        APP_TOKEN,
        "",
        &[],
    );
    assert_eq!(code, 202, "{text}");
    let doc = status(&base, APP_TOKEN, &a3).1;
    assert_eq!(doc["state"], "failed", "{doc}");
    assert!(
        doc["error"]
            .as_str()
            .unwrap()
            .contains("cancelled by the client after 0 trial(s)"),
        "{doc}"
    );
    let (code, text) = post_json(
        &base,
        &format!("/v1/sessions/{a3}/cancel"),
        APP_TOKEN,
        "",
        &[],
    );
    assert_eq!(code, 409, "{text}");
    // Deleting a queued session takes it out of the queue.
    delete(&base, APP_TOKEN, &a2);
    assert_eq!(status(&base, APP_TOKEN, &a2).0, 404);
    assert_eq!(place(APP2_TOKEN, &b1), 1);

    // Cancelling a playing session keeps what it played: an estimate over its trials.
    wait_for(&base, APP_TOKEN, &a1, Duration::from_secs(20), |d| {
        d["trials_done"].as_u64() >= Some(2)
    });
    let (code, text) = post_json(
        &base,
        &format!("/v1/sessions/{a1}/cancel"),
        APP_TOKEN,
        "",
        &[],
    );
    assert_eq!(code, 202, "{text}");
    let doc = wait_for(&base, APP_TOKEN, &a1, Duration::from_secs(20), finished);
    assert_eq!(doc["state"], "done", "{doc}");
    let played = doc["trials_done"].as_u64().unwrap();
    assert!((2..40).contains(&played), "{doc}");
    assert_eq!(doc["results_trials"].as_u64(), Some(played), "{doc}");
    assert!(
        doc["stop_reason"]
            .as_str()
            .unwrap()
            .contains("cancelled by the client"),
        "{doc}"
    );

    // The other token's session plays next, to the end.
    let doc = wait_for(&base, APP2_TOKEN, &b1, Duration::from_secs(30), finished);
    assert_eq!(
        (doc["state"].as_str(), doc["trials_done"].as_u64()),
        (Some("done"), Some(2)),
        "{doc}"
    );

    // Deleting a playing session stops it, then deletes it whole.
    let a4 = create(&base, APP_TOKEN, r#"{"playback":"sim","trials":40}"#);
    upload(&base, APP_TOKEN, &a4, &rec);
    wait_for(&base, APP_TOKEN, &a4, Duration::from_secs(20), |d| {
        d["trials_done"].as_u64() >= Some(1)
    });
    let started = Instant::now();
    delete(&base, APP_TOKEN, &a4);
    assert!(
        started.elapsed() < Duration::from_secs(5),
        "{:?}",
        started.elapsed()
    );
    assert_eq!(status(&base, APP_TOKEN, &a4).0, 404);
    assert!(!data.join("sessions").join(&a4).exists());

    // The worker is free again: the next session plays.
    let a5 = create(&base, APP_TOKEN, r#"{"playback":"sim","trials":2}"#);
    upload(&base, APP_TOKEN, &a5, &rec);
    let doc = wait_for(&base, APP_TOKEN, &a5, Duration::from_secs(30), finished);
    assert_eq!(doc["state"], "done", "{doc}");
}

#[test]
fn after_a_restart_the_queue_resumes_in_order_and_a_bad_row_fails_alone() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let config = || {
        let mut config = sim_config(&data, 3.0, 1);
        config.playback_workers = 1;
        config.jobs_per_token = 1;
        config
    };
    let rec = sim_recording(dir.path(), "walk.rec", 3.0, 9);
    let server = start(config());
    let base = server.url();
    let first = create(&base, APP_TOKEN, r#"{"playback":"sim","trials":3}"#);
    upload(&base, APP_TOKEN, &first, &rec);
    wait_for(&base, APP_TOKEN, &first, Duration::from_secs(10), |d| {
        d["state"] == "playing"
    });
    let queued: Vec<String> = (0..4)
        .map(|_| {
            let id = create(&base, APP_TOKEN, r#"{"playback":"sim","trials":2}"#);
            upload(&base, APP_TOKEN, &id, &rec);
            id
        })
        .collect();
    server.stop();

    // Rows no server writes: a negative trial count, an unknown playback, an unknown state.
    let db = rusqlite::Connection::open(data.join("sitar.db")).unwrap();
    let set = |sql: &str, id: &str| db.execute(sql, [id]).unwrap();
    set(
        "UPDATE sessions SET trials_total = -5 WHERE id = ?1",
        &queued[1],
    );
    set(
        "UPDATE sessions SET playback = 'vhs' WHERE id = ?1",
        &queued[2],
    );
    let odd = create_offline(&db);
    drop(db);

    let server = start(config());
    let base = server.url();
    // The first session resumes playing; the readable queued ones wait in their order.
    assert_eq!(status(&base, APP_TOKEN, &queued[0]).1["queue_position"], 1);
    assert_eq!(status(&base, APP_TOKEN, &queued[3]).1["queue_position"], 2);
    // Listing names the unreadable rows and skips them; the overview page answers.
    let (code, _, text) = raw("GET", &format!("{base}/v1/sessions"), None, b"", &[]);
    assert_eq!(code, 200, "{text}");
    let doc: Value = serde_json::from_str(&text).unwrap();
    let unreadable: Vec<&str> = doc["unreadable"]
        .as_array()
        .unwrap()
        .iter()
        .map(|u| u["id"].as_str().unwrap())
        .collect();
    for id in [&queued[1], &queued[2], &odd] {
        assert!(unreadable.contains(&id.as_str()), "{id}: {doc}");
    }
    let (code, _, _) = raw("GET", &format!("{base}/"), None, b"", &[]);
    assert_eq!(code, 200);
    for id in [&first, &queued[0], &queued[3]] {
        let doc = wait_for(&base, APP_TOKEN, id, Duration::from_secs(40), finished);
        assert_eq!(doc["state"], "done", "{doc}");
    }
    // The unreadable in-flight rows were failed with the reason, not played.
    server.stop();
    let db = rusqlite::Connection::open(data.join("sitar.db")).unwrap();
    for id in [&queued[1], &queued[2]] {
        let (state, error): (String, String) = db
            .query_row(
                "SELECT state, error FROM sessions WHERE id = ?1",
                [id],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .unwrap();
        assert_eq!(state, "failed", "{id}");
        assert!(error.contains("cannot read"), "{error}");
    }
}

/// A session row in a state no server writes, straight into the database; its id.
fn create_offline(db: &rusqlite::Connection) -> String {
    let id = "s00000000000000ee".to_owned();
    db.execute(
        "INSERT INTO sessions (id, created_ms, trials_total, setting, playback, state, adaptive_k) \
         VALUES (?1, 1, 2, 'median', 'sim', 'paused', 3)",
        [&id],
    )
    .unwrap();
    id
}

#[test]
fn legacy_results_and_idempotency_keys_stay_with_their_token() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = sim_config(&dir.path().join("data"), 30.0, 1);
    config.default_trials = 2;
    let server = start(config);
    let base = server.url();
    let rec = sim_recording(dir.path(), "walk.rec", 3.0, 5);

    // Token one plays a session through the legacy routes.
    let (ct, body) = multipart("recording", "recording.mp4", &std::fs::read(&rec).unwrap());
    let auth1 = bearer(APP_TOKEN);
    let (code, _, text) = raw(
        "POST",
        &format!("{base}/recording"),
        Some(&ct),
        &body,
        &[("authorization", &auth1)],
    );
    assert_eq!(code, 200, "{text}");
    let legacy: Value = serde_json::from_str(&text).unwrap();
    let legacy = legacy["id"].as_str().unwrap().to_owned();
    // Then a v1 session of each token finishes later.
    for token in [APP_TOKEN, APP2_TOKEN] {
        let id = create(
            &base,
            token,
            r#"{"playback":"sim","trials":3,"setting":"median"}"#,
        );
        upload(&base, token, &id, &rec);
        wait_for(&base, token, &id, Duration::from_secs(30), finished);
    }
    let results = |token: &str, path: &str| {
        let auth = bearer(token);
        let (code, _, text) = raw(
            "GET",
            &format!("{base}{path}"),
            None,
            b"",
            &[("authorization", &auth)],
        );
        (code, text)
    };
    // Token one gets its legacy session's results, not the newer v1 one's.
    let (code, text) = results(APP_TOKEN, "/results.csv");
    assert_eq!(code, 200, "{text}");
    assert_eq!(
        text,
        results(APP_TOKEN, &format!("/v1/sessions/{legacy}/results.csv")).1
    );
    // Token two made no legacy session: nothing, never token one's.
    assert_eq!(results(APP2_TOKEN, "/results.csv").0, 404);

    // Idempotency keys belong to their token; the same key with another body is a 409.
    let key = [("idempotency-key", "replayed-key-1")];
    let body = r#"{"playback":"upload","trials":3}"#;
    let (code, first) = post_json(&base, "/v1/sessions", APP_TOKEN, body, &key);
    assert_eq!(code, 201, "{first}");
    let (code, again) = post_json(&base, "/v1/sessions", APP_TOKEN, body, &key);
    assert_eq!((code, &again), (201, &first));
    let (code, text) = post_json(
        &base,
        "/v1/sessions",
        APP_TOKEN,
        r#"{"playback":"upload","trials":4}"#,
        &key,
    );
    assert_eq!(code, 409, "{text}");
    assert!(text.contains("Idempotency-Key"), "{text}");
    let (code, other) = post_json(&base, "/v1/sessions", APP2_TOKEN, body, &key);
    assert_eq!(code, 201, "{other}");
    assert_ne!(other, first);
}

#[test]
fn sessions_resumed_into_the_queue_end_at_once_on_estimate_or_cancel() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let config = |workers| {
        let mut config = sim_config(&data, 3.0, 1);
        config.playback_workers = workers;
        config.jobs_per_token = workers;
        config
    };
    let rec = sim_recording(dir.path(), "walk.rec", 3.0, 4);
    // Three play at once, each to 2 trials or more.
    let server = start(config(3));
    let base = server.url();
    let ids: Vec<String> = (0..3)
        .map(|_| {
            let id = create(&base, APP_TOKEN, r#"{"playback":"sim","trials":40}"#);
            upload(&base, APP_TOKEN, &id, &rec);
            id
        })
        .collect();
    for id in &ids {
        wait_for(&base, APP_TOKEN, id, Duration::from_secs(30), |d| {
            d["trials_done"].as_u64() >= Some(2)
        });
    }
    server.stop();

    // One worker after the restart: the first plays, the others wait, still `playing`.
    let server = start(config(1));
    let base = server.url();
    for (id, place) in [(&ids[1], 1), (&ids[2], 2)] {
        let doc = status(&base, APP_TOKEN, id).1;
        assert_eq!(
            (doc["state"].as_str(), doc["queue_position"].as_u64()),
            (Some("playing"), Some(place)),
            "{doc}"
        );
    }
    let (code, text) = post_json(
        &base,
        &format!("/v1/sessions/{}/estimate", ids[1]),
        APP_TOKEN,
        "",
        &[],
    );
    assert_eq!(code, 202, "{text}");
    let (code, text) = post_json(
        &base,
        &format!("/v1/sessions/{}/cancel", ids[2]),
        APP_TOKEN,
        "",
        &[],
    );
    assert_eq!(code, 202, "{text}");
    for (id, reason) in [
        (&ids[1], "estimate requested after"),
        (&ids[2], "cancelled by the client after"),
    ] {
        let doc = wait_for(&base, APP_TOKEN, id, Duration::from_secs(20), finished);
        assert_eq!(doc["state"], "done", "{doc}");
        assert!(
            doc["stop_reason"].as_str().unwrap().starts_with(reason),
            "{doc}"
        );
        assert_eq!(doc["results_trials"], doc["trials_done"], "{doc}");
        assert!(doc["trials_done"].as_u64() >= Some(2), "{doc}");
    }
    delete(&base, APP_TOKEN, &ids[0]);
}
