//! Deletes that finish: an instance killed (SIGKILL) in the middle of `DELETE
//! /v1/sessions/{id}` — after the session's rows are gone, before its bytes are (the hidden
//! `--delete-pause-s` holds it there, so the kill lands there every time) — leaves bytes that
//! a live instance's sweep removes within a minute; a repeated DELETE is a 404 on every
//! instance. The cluster case needs `scripts/cluster-services` (else SKIPPED); the embedded
//! case runs always.

mod support;

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use support::process::{Serving, admin_token};
use support::sessions::sim_session;

/// The sweep period the tests give: a crash's leftovers go within three of them.
const SWEEP_S: &str = "1";

/// What the deleting instance logs once the rows are gone (then it pauses).
const ROWS_GONE: &str = "deleted; its bytes go next";

/// `METHOD url/path` with the bearer `token` through curl: the HTTP status (`000` when the
/// connection broke).
fn request(method: &str, url: &str, path: &str, token: &str) -> String {
    let out = Command::new("curl")
        .args(["-s", "-o", "/dev/null", "-w", "%{http_code}", "-X", method])
        .args(["-H", &format!("Authorization: Bearer {token}")])
        .arg(format!("{url}{path}"))
        .output()
        .expect("curl");
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

/// A sim session of 3 trials played to the end on `server`: its id.
fn played_session(server: &Serving, token: &str, dir: &Path) -> String {
    let recording = dir.join("walk.rec");
    let rec = sitar_sim::Recording::demo(4.0, 30.0, 7).unwrap();
    std::fs::write(&recording, rec.to_bytes()).unwrap();
    let client = server.client(token);
    let id = sim_session(&client, &recording, 3, "trim_mean_30");
    let done = client
        .wait(
            &id,
            Duration::from_millis(50),
            Duration::from_secs(120),
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(done.state, sitar_client::SessionState::Done, "{done:?}");
    id
}

/// Sends `DELETE` of session `id` to `server` from a thread of its own (it never answers:
/// the instance is killed while it pauses), waits until the rows are gone, kills the
/// instance and reaps the request.
fn kill_mid_delete(server: &mut Serving, token: &str, id: &str) {
    let (url, path, token) = (
        server.url.clone(),
        format!("/v1/sessions/{id}"),
        token.to_string(),
    );
    let pending = std::thread::spawn(move || request("DELETE", &url, &path, &token));
    server.wait_for(
        &format!("session {id} {ROWS_GONE}"),
        Duration::from_secs(30),
    );
    server.kill();
    let status = pending.join().unwrap();
    assert_eq!(
        status, "000",
        "the delete never answered: its instance died"
    );
}

/// Waits up to `limit` for `gone` to hold; how long it took.
fn within(limit: Duration, mut gone: impl FnMut() -> bool) -> Option<Duration> {
    let start = Instant::now();
    while start.elapsed() < limit {
        if gone() {
            return Some(start.elapsed());
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    None
}

#[test]
fn an_embedded_delete_cut_off_by_a_crash_is_finished_after_the_restart() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let pause = ["--delete-sweep-s", SWEEP_S, "--delete-pause-s", "600"];
    let mut first = Serving::sim(&data, &pause);
    let admin = admin_token(&data);
    let id = played_session(&first, &admin, dir.path());
    let folder = data.join("sessions").join(&id);
    assert!(folder.join("results.csv").is_file());
    kill_mid_delete(&mut first, &admin, &id);
    // Cut off: the session is gone from the database, its folder is still there.
    assert!(
        folder.join("results.csv").is_file(),
        "the kill was mid-delete"
    );

    let second = Serving::sim(&data, &["--delete-sweep-s", SWEEP_S]);
    assert_eq!(
        request("GET", &second.url, &format!("/v1/sessions/{id}"), &admin),
        "404"
    );
    let moved = data.join("tmp").join(format!("deleted-{id}"));
    let took = within(Duration::from_secs(60), || {
        !folder.exists() && !moved.exists()
    })
    .unwrap_or_else(|| panic!("{} is still there after a minute", folder.display()));
    println!("embedded: the interrupted delete's folder went {took:?} after the restart");
    // Deleted means gone: a repeated delete is a 404, as for any unknown id.
    assert_eq!(
        request("DELETE", &second.url, &format!("/v1/sessions/{id}"), &admin),
        "404"
    );
}

#[cfg(feature = "cluster")]
mod cluster {
    use super::*;
    use support::cluster::Cluster;

    /// The keys of the objects under `prefix` of `store` (`s3://BUCKET/PREFIX`), listed with
    /// curl's SigV4 signing from the `AWS_*` variables the services set.
    fn objects(store: &str, prefix: &str) -> Vec<String> {
        let var = |name: &str| std::env::var(name).unwrap_or_else(|_| panic!("{name}"));
        let (bucket, base) = store
            .strip_prefix("s3://")
            .and_then(|s| s.split_once('/'))
            .expect("s3://BUCKET/PREFIX");
        let prefix = format!("{base}/{prefix}");
        let out = Command::new("curl")
            .args(["-s", "-f", "--aws-sigv4"])
            .arg(format!("aws:amz:{}:s3", var("AWS_REGION")))
            .args([
                "--user",
                &format!(
                    "{}:{}",
                    var("AWS_ACCESS_KEY_ID"),
                    var("AWS_SECRET_ACCESS_KEY")
                ),
            ])
            .arg(format!(
                // The signature covers the query: `/` encoded, as SigV4 wants it.
                "{}/{bucket}?list-type=2&prefix={}",
                var("AWS_ENDPOINT_URL").trim_end_matches('/'),
                prefix.replace('/', "%2F")
            ))
            .output()
            .expect("curl");
        assert!(out.status.success(), "listing {prefix}: {out:?}");
        let xml = String::from_utf8_lossy(&out.stdout);
        xml.split("<Key>")
            .skip(1)
            .filter_map(|s| s.split_once("</Key>").map(|(key, _)| key.to_string()))
            .collect()
    }

    /// Rows of `unfinished_deletes` in `database` (through psql).
    fn unfinished(database: &str) -> String {
        let out = Command::new("psql")
            .args([database, "-tAc", "SELECT count(*) FROM unfinished_deletes"])
            .output()
            .expect("psql");
        assert!(out.status.success(), "{out:?}");
        String::from_utf8_lossy(&out.stdout).trim().to_string()
    }

    #[test]
    fn a_live_instance_finishes_the_delete_of_one_killed_mid_delete() {
        let Some(cluster) = Cluster::fresh("cluster_deletes") else {
            return;
        };
        let (database, store) = (&cluster.database, &cluster.store);
        let dir = tempfile::tempdir().unwrap();
        let sweep = ["--delete-sweep-s", SWEEP_S];
        let a_data = dir.path().join("instance-a");
        let mut a = cluster.serve(
            &a_data,
            &[&sweep[..], &["--delete-pause-s", "600"]].concat(),
        );
        let admin = admin_token(&a_data);
        let b = cluster.serve(&dir.path().join("instance-b"), &sweep);
        // A third instance sweeps too: the two take the delete over once between them.
        let mut c = cluster.serve(&dir.path().join("instance-c"), &sweep);
        let id = played_session(&a, &admin, dir.path());
        let folder = format!("sessions/{id}/");
        let before = objects(store, &folder);
        assert!(
            before.iter().any(|k| k.ends_with("/recording"))
                && before.iter().any(|k| k.ends_with("/results.csv"))
                && before.iter().filter(|k| k.contains("/trials/")).count() == 3,
            "{before:?}"
        );

        // Another app token can neither read nor delete it: 404, and nothing goes.
        let other = support::process::create_token(&["--database", database], "app", "other");
        let path = format!("/v1/sessions/{id}");
        assert_eq!(request("DELETE", &b.url, &path, &other), "404");
        assert_eq!(request("GET", &b.url, &path, &other), "404");
        assert_eq!(objects(store, &folder), before);

        kill_mid_delete(&mut a, &admin, &id);
        // Cut off: the session is gone for every instance, its objects are not.
        assert_eq!(request("GET", &b.url, &path, &admin), "404");
        assert_eq!(objects(store, &folder), before, "the kill was mid-delete");
        assert_eq!(unfinished(database), "1");

        // B's or C's sweep takes it over once A's claim (two periods) lapses.
        let took = within(Duration::from_secs(60), || {
            objects(store, &folder).is_empty()
        })
        .unwrap_or_else(|| panic!("left after a minute: {:?}", objects(store, &folder)));
        println!(
            "cluster: a live instance removed the killed delete's objects {took:?} after the kill"
        );
        assert!(within(Duration::from_secs(10), || unfinished(database) == "0").is_some());
        let mut b = b;
        let finished = format!("session {id}: the bytes its interrupted delete left are removed");
        std::thread::sleep(Duration::from_secs(3));
        let (by_b, by_c) = (b.said(&finished), c.said(&finished));
        assert!(by_b != by_c, "one sweeper finished it: B {by_b}, C {by_c}");
        for sweeper in [&mut b, &mut c] {
            assert!(!sweeper.said("left for later"), "{:#?}", sweeper.seen);
        }

        // Deleted means gone: repeated on either instance (A started again), a 404.
        assert_eq!(request("DELETE", &b.url, &path, &admin), "404");
        let a = cluster.serve(&a_data, &sweep);
        assert_eq!(request("DELETE", &a.url, &path, &admin), "404");
        assert!(objects(store, &folder).is_empty());
    }
}
