//! The cluster under fire: two `sitar serve` instances on one Postgres and one bucket, three
//! `sitar worker --playback sim` hosts and 30 sessions from 3 tokens — while one host is
//! killed (SIGKILL) in the middle of a trial, another is stopped (SIGSTOP) past its lease and
//! let go on, Postgres restarts, and one instance is killed (SIGKILL) during an upload that
//! the client then finishes against the other. Every session ends `done`, every trial is
//! stored exactly once, and every result is byte-identical to the embedded server's for the
//! same recording and trials. Its own test binary: restarting Postgres must not disturb
//! other tests. Without `SITAR_TEST_DATABASE_URL`, `SITAR_TEST_S3_URL` and
//! `SITAR_TEST_PG_DATA` (`scripts/cluster-services start`) it prints SKIPPED.
// The cluster backends are in a build with the `cluster` feature only.
#![cfg(feature = "cluster")]

mod support;

use std::collections::HashMap;
use std::io::Write;
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use sitar_client::{Client, NewSession};
use support::cluster::{fresh_database, postgres_data, restart_postgres, services};
use support::process::{Proc, Serving, create_token, sim_host, upload_offset};
use support::sessions::{embedded_results, sim_session, trials_in_zip};

const TEST: &str = "cluster_chaos";

/// A host's lease without heartbeats, in seconds.
const LEASE_S: u64 = 2;

/// An instance silent this long has its sessions adopted, in seconds.
const INSTANCE_TIMEOUT_S: u64 = 3;

/// What the test needs of the services: a fresh database, a bucket prefix of its own and
/// Postgres' data folder.
struct Services {
    database: String,
    store: String,
    pg_data: PathBuf,
}

/// The services, or `None` after printing SKIPPED.
fn cluster() -> Option<Services> {
    let (url, store) = services(TEST)?;
    let pg_data = postgres_data(TEST)?;
    let database = fresh_database(TEST, &url)?;
    Some(Services {
        database,
        store: format!("{store}/{TEST}-{}", std::process::id()),
        pg_data,
    })
}

/// `sitar token create --database`: the token.
fn token(database: &str, role: &str, name: &str) -> String {
    create_token(&["--database", database], role, name)
}

/// An instance with remote playback on a free port.
fn serve(data: &Path, services: &Services) -> Serving {
    let (lease, timeout) = (LEASE_S.to_string(), INSTANCE_TIMEOUT_S.to_string());
    Serving::start(
        data,
        &[
            "--playback",
            "sim",
            "--playback-workers",
            "0",
            "--lease-s",
            &lease,
            "--instance-timeout-s",
            &timeout,
            "--jobs-per-token",
            "4",
            "--database",
            &services.database,
            "--store",
            &services.store,
        ],
    )
}

/// A sim host of 2 phones playing at `speed`× real time, connected to `url`.
fn worker(url: &str, token: &str, name: &str, speed: &str, dir: &Path) -> Proc {
    sim_host(url, token, name, "2", speed, dir)
}

fn new_session(client: &Client, trials: u32) -> String {
    client
        .create_session(&NewSession {
            trials,
            setting: "trim_mean_30".into(),
            playback: "sim".into(),
            window_frames: None,
            pose_relation: None,
        })
        .unwrap()
}

/// `curl` with the token and upload key: `-w %{http_code}` output.
fn curl(token: &str, args: &[&str]) -> Command {
    let mut c = Command::new("curl");
    c.args(["-s", "-H", &format!("Authorization: Bearer {token}")])
        .args(["-H", "Idempotency-Key: chaos-upload"])
        .args(args);
    c
}

/// `PUT`s bytes `offset…` of `file` to its end as one request at `url`: the HTTP status.
fn put_rest(url: &str, token: &str, id: &str, file: &Path, offset: usize) -> String {
    let bytes = std::fs::read(file).unwrap();
    let rest = file.with_extension(format!("from-{offset}"));
    std::fs::write(&rest, &bytes[offset..]).unwrap();
    let range = format!(
        "Content-Range: bytes {offset}-{}/{}",
        bytes.len() - 1,
        bytes.len()
    );
    let out = curl(
        token,
        &["-o", "/dev/null", "-w", "%{http_code}", "-H", &range],
    )
    .arg("-T")
    .arg(&rest)
    .arg(format!("{url}/v1/sessions/{id}/recording"))
    .output()
    .expect("curl");
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

/// Starts a `PUT` of bytes `offset…` of `file` to its end at `url` and sends only the first
/// `sent` bytes of its body: the open connection, which the server waits on for the rest.
fn put_cut_off(
    url: &str,
    token: &str,
    id: &str,
    file: &Path,
    offset: usize,
    sent: usize,
) -> TcpStream {
    let bytes = std::fs::read(file).unwrap();
    let address = url.strip_prefix("http://").unwrap();
    let mut stream = TcpStream::connect(address).unwrap();
    let head = format!(
        "PUT /v1/sessions/{id}/recording HTTP/1.1\r\nHost: {address}\r\n\
         Authorization: Bearer {token}\r\nIdempotency-Key: chaos-upload\r\n\
         Content-Type: application/octet-stream\r\nContent-Length: {}\r\n\
         Content-Range: bytes {offset}-{}/{}\r\n\r\n",
        bytes.len() - offset,
        bytes.len() - 1,
        bytes.len()
    );
    stream.write_all(head.as_bytes()).unwrap();
    stream.write_all(&bytes[offset..offset + sent]).unwrap();
    stream.flush().unwrap();
    stream
}

/// What `psql` prints for `sql` (for a failure's message).
fn psql(database: &str, sql: &str) -> String {
    let out = Command::new("psql")
        .args([database, "-c", sql])
        .output()
        .expect("psql");
    format!(
        "\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// Trials stored per session, counted in the database itself.
fn stored_trials(database: &str) -> HashMap<String, u32> {
    let out = Command::new("psql")
        .args([database, "-qAt", "-F", " ", "-c"])
        .arg("SELECT session_id, count(*) FROM trials GROUP BY session_id")
        .output()
        .expect("psql");
    assert!(out.status.success(), "{out:?}");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let (id, n) = l.split_once(' ')?;
            Some((id.to_string(), n.parse().ok()?))
        })
        .collect()
}

#[test]
fn two_instances_three_hosts_and_thirty_sessions_come_through_kills_stops_and_a_database_restart() {
    let Some(services) = cluster() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (a_data, b_data, hosts) = (
        dir.path().join("instance-a"),
        dir.path().join("instance-b"),
        dir.path().join("hosts"),
    );
    // A starts first on the empty database (it writes the admin token), then B.
    let mut a = serve(&a_data, &services);
    let mut b = serve(&b_data, &services);
    let (a_url, b_url) = (a.url.clone(), b.url.clone());
    let apps: Vec<String> = (0..3)
        .map(|k| token(&services.database, "app", &format!("lab-app-{k}")))
        .collect();
    let work = token(&services.database, "worker", "lab-hosts");

    // 4 s walks at 4× real time: 1 s trials, half a lease.
    let walk = sitar_tests::sim_recording(dir.path(), "walk.sitar", 4.0, 17);
    let mut h1 = worker(&a_url, &work, "host-1", "4", &hosts);
    let mut h2 = worker(&b_url, &work, "host-2", "4", &hosts);
    let mut h3 = worker(&b_url, &work, "host-3", "4", &hosts);

    // 30 sessions of 3 tokens (3 or 4 trials), sent to both instances, uploaded at once.
    let sessions: Vec<(usize, String, u32)> = std::thread::scope(|scope| {
        let uploads: Vec<_> = (0..3)
            .map(|k| {
                let (apps, walk) = (&apps, &walk);
                let urls = [a_url.clone(), b_url.clone()];
                scope.spawn(move || {
                    (0..10)
                        .map(|n| {
                            let client = Client::new(&urls[n % 2])
                                .unwrap()
                                .with_server_token(&apps[k])
                                .unwrap();
                            let trials = 3 + (n as u32 % 2);
                            let id = sim_session(&client, walk, trials, "trim_mean_30");
                            (k, id, trials)
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        uploads
            .into_iter()
            .flat_map(|u| u.join().unwrap())
            .collect()
    });

    // A host killed in the middle of a trial: its lease expires, the trial is played again.
    h1.wait_for("playing trial", Duration::from_secs(60));
    h1.signal("KILL");
    // A host stopped past its lease, then let go on: its late trial is refused.
    h2.wait_for("playing trial", Duration::from_secs(60));
    h2.signal("STOP");
    std::thread::sleep(Duration::from_secs(LEASE_S + 3));
    h2.signal("CONT");
    // Postgres restarts under both instances and the hosts.
    restart_postgres(&services.pg_data);

    // Instance A killed during an upload: its first half went whole to A in one request,
    // the second is cut off by the kill; the client finishes it against B from B's offset.
    let big = dir.path().join("long-walk.sitar");
    std::fs::write(
        &big,
        sitar_sim::Recording::demo(12.0, 30.0, 23)
            .unwrap()
            .to_bytes(),
    )
    .unwrap();
    let size = std::fs::metadata(&big).unwrap().len() as usize;
    let big_client = Client::new(&a_url)
        .unwrap()
        .with_server_token(&apps[0])
        .unwrap();
    let big_id = new_session(&big_client, 2);
    let half = size / 2;
    let first = {
        let bytes = std::fs::read(&big).unwrap();
        let first = dir.path().join("first-half");
        std::fs::write(&first, &bytes[..half]).unwrap();
        let range = format!("Content-Range: bytes 0-{}/{size}", half - 1);
        curl(
            &apps[0],
            &["-o", "/dev/null", "-w", "%{http_code}", "-H", &range],
        )
        .arg("-T")
        .arg(&first)
        .arg(format!("{a_url}/v1/sessions/{big_id}/recording"))
        .output()
        .unwrap()
    };
    assert_eq!(String::from_utf8_lossy(&first.stdout), "200", "{first:?}");
    let cut = put_cut_off(&a_url, &apps[0], &big_id, &big, half, 4096);
    std::thread::sleep(Duration::from_millis(1500));
    a.kill();
    a.drain();
    drop(cut);
    let resumed_at = upload_offset(&b_url, &apps[0], &big_id, "chaos-upload");
    // The first request's bytes are stored whole; the cut-off one's died with A.
    assert_eq!(resumed_at, half, "B resumes after A's first request");
    let status = put_rest(&b_url, &apps[0], &big_id, &big, resumed_at);
    assert_eq!(status, "202", "the recording is whole");

    // Everything ends done, through B: each trial once, results as the embedded server's.
    let mut references: HashMap<(PathBuf, u32), (String, String)> = HashMap::new();
    let all = sessions
        .iter()
        .cloned()
        .chain(std::iter::once((0, big_id.clone(), 2)));
    for (owner, id, trials) in all {
        let client = Client::new(&b_url)
            .unwrap()
            .with_server_token(&apps[owner])
            .unwrap();
        let waited = client.wait(
            &id,
            Duration::from_millis(100),
            Duration::from_secs(120),
            &mut |_| {},
        );
        let finished = waited
            .as_ref()
            .is_ok_and(|s| s.state.as_str() == "done" && s.trials_done == trials);
        if !finished {
            let told = [&mut a.process, &mut b.process, &mut h1, &mut h2, &mut h3]
                .into_iter()
                .map(|p| {
                    p.drain();
                    p.seen
                        .iter()
                        .filter(|l| l.contains(&id))
                        .cloned()
                        .collect::<Vec<_>>()
                })
                .collect::<Vec<_>>();
            panic!(
                "{id} did not end done with {trials} trials: {waited:?}\nsessions: {}\n\
                 its leases: {}\nits trials: {}\nits failures: {}\ninstances: {}\n\
                 A, B, host 1, 2, 3 said of it: {told:#?}",
                psql(
                    &services.database,
                    "SELECT id, state, trials_total, played_by, stop_request FROM sessions \
                     WHERE state <> 'done' ORDER BY seq"
                ),
                psql(
                    &services.database,
                    &format!(
                        "SELECT play_index, state, attempts, host_id, phone, taken \
                         FROM trial_leases WHERE session_id = '{id}' ORDER BY play_index"
                    )
                ),
                psql(
                    &services.database,
                    &format!(
                        "SELECT idx, play_index, source FROM trials \
                         WHERE session_id = '{id}' ORDER BY idx"
                    )
                ),
                psql(
                    &services.database,
                    &format!("SELECT * FROM trial_failures WHERE session_id = '{id}'")
                ),
                psql(&services.database, "SELECT * FROM instances"),
            );
        }
        assert_eq!(
            trials_in_zip(&b_url, &apps[owner], &id),
            trials as usize,
            "{id}"
        );
        let recording = if id == big_id { &big } else { &walk };
        let expected = references
            .entry((recording.clone(), trials))
            .or_insert_with(|| embedded_results(recording, trials, "trim_mean_30"));
        assert_eq!(client.results_json(&id).unwrap(), expected.0, "{id}");
        assert_eq!(client.results_csv(&id).unwrap(), expected.1, "{id}");
    }
    // What the stopped host did with its trial once it went on, and B took A's sessions.
    assert!(
        h2.said("refused") || h2.said("stopped"),
        "the stopped host neither dropped nor had its trial refused: {:#?}",
        h2.seen
    );
    assert!(b.said("adopted from"), "B adopted none of A's sessions");
    let stored = stored_trials(&services.database);
    assert_eq!(stored.len(), 31, "{stored:?}");
    for (_, id, trials) in &sessions {
        assert_eq!(stored.get(id), Some(trials), "{id}");
    }
    assert_eq!(stored.get(&big_id), Some(&2));
}
