//! What a venue's map costs at a thousand sessions, from kept contributions.
//!
//! `cargo run --release -p sitar-server --example venue_map_figures -- [--sessions 1000]
//! [--subtrajectories 45] [--repeat 15] [--cluster]`
//!
//! An in-process server (embedded store; with `--cluster` Postgres and the S3 bucket of
//! `scripts/cluster-services start`: `SITAR_TEST_DATABASE_URL`, `SITAR_TEST_S3_URL`, `AWS_*`,
//! a fresh database made with `psql`) gets one venue and N finished `upload` sessions, each
//! with the phone's log (anchors seen in its own world frame, a walk along a wall of
//! `--subtrajectories` sub-trajectories, each with a surface point) and two trials. Then, over
//! loopback:
//!
//! * `map.json` after every session's contribution was forgotten (as after the upgrade that
//!   brought the table: every contribution computed from the session's files and kept —
//!   what every request cost before);
//! * `map.json` from the kept contributions, the median of `--repeat` requests;
//! * `map.glb` and the venue report, the same way;
//! * a session joining (its first map request after it finished) and leaving.

use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use sitar_server::{Server, ServerConfig, ServerHandle};

#[path = "../tests/support/http.rs"]
#[allow(dead_code)]
mod http;
use http::{Answer, call};

const FRAME_NS: i64 = 33_333_333;
const T0: i64 = 1_700_000_000_000_000_000;
const CELL_M: f64 = 0.25;

fn t(frame: i64) -> i64 {
    T0 + frame * FRAME_NS
}

/// One user's walk along the wall z = 2 m of the venue frame, in a world frame shifted by
/// `dx` along x; the walk starts `x0` metres along the wall.
struct Phone {
    dx: f64,
    x0: f64,
    subtrajectories: i64,
}

impl Phone {
    fn frames(&self) -> i64 {
        10 * self.subtrajectories
    }

    /// The camera at `frame` in the venue frame.
    fn position(&self, frame: i64) -> [f64; 3] {
        [
            self.x0 + 0.01 * frame as f64,
            1.5,
            0.3 + 0.001 * frame as f64,
        ]
    }

    fn trial(&self, noise: f64) -> String {
        (0..=self.frames())
            .map(|i| {
                let p = self.position(i);
                let wiggle = noise * ((i * i % 7) as f64 - 3.0);
                format!(
                    "{} {} {} {} 0 0 0 1\n",
                    t(i),
                    p[0] + self.dx + wiggle,
                    p[1],
                    p[2]
                )
            })
            .collect()
    }

    fn trajectory_txt(&self) -> String {
        (0..=self.frames())
            .step_by(5)
            .map(|i| {
                let p = self.position(i);
                format!("{} {} {} {} 0 0 0 1\n", t(i), p[0] + self.dx, p[1], p[2])
            })
            .collect()
    }

    fn anchors_csv(&self) -> String {
        let mut csv = String::from("t_ns,anchor,px,py,pz,qx,qy,qz,qw,tracking\n");
        for k in 0..3 {
            csv.push_str(&format!("{},poster-1,{},0,0,0,0,0,1,full\n", t(k), self.dx));
        }
        csv
    }

    fn subtrajectories_csv(&self) -> String {
        let mut csv = String::from(
            "index,start_ns,mid_ns,end_ns,depth,pixel_x,pixel_y,depth_m,distance_m,cam_x,cam_y,cam_z,cam_nx,cam_ny,cam_nz,x,y,z,nx,ny,nz,error_m,class\n",
        );
        for k in 0..self.subtrajectories {
            let p = self.position(10 * k + 5);
            csv.push_str(&format!(
                "{k},{},{},{},valid,128,96,2,2,0,0,2,0,0,-1,{},{},{},0,0,-1,,\n",
                t(10 * k),
                t(10 * k + 5),
                t(10 * k + 10),
                p[0] + self.dx,
                p[1] + 0.2 * ((k % 5) as f64 - 2.0),
                2.0 + 0.001 * ((k % 3) as f64 - 1.0)
            ));
        }
        csv
    }
}

fn ok(a: Answer, what: &str, status: u16) -> Answer {
    assert_eq!(a.status, status, "{what}: {}", a.body);
    a
}

/// Creates a venue session with `phone`'s log and two trials, and asks for its estimate.
fn start_session(server: &ServerHandle, token: &str, venue: &str, phone: &Phone) -> String {
    let body = json!({"playback": "upload", "trials": 2, "venue": venue}).to_string();
    let a = call(
        server,
        token,
        "POST",
        "/v1/sessions",
        Some("application/json"),
        body.as_bytes(),
    );
    let id = ok(a, "POST /v1/sessions", 201).json()["id"]
        .as_str()
        .unwrap()
        .to_owned();
    let base = format!("/v1/sessions/{id}");
    for (name, text) in [
        ("anchors.csv", phone.anchors_csv()),
        ("trajectory.txt", phone.trajectory_txt()),
        ("subtrajectories.csv", phone.subtrajectories_csv()),
    ] {
        let path = format!("{base}/{name}");
        ok(
            call(
                server,
                token,
                "PUT",
                &path,
                Some("text/plain"),
                text.as_bytes(),
            ),
            &path,
            200,
        );
    }
    for noise in [0.0, 0.003] {
        let trial = phone.trial(noise);
        let path = format!("{base}/trials");
        ok(
            call(
                server,
                token,
                "POST",
                &path,
                Some("text/plain"),
                trial.as_bytes(),
            ),
            &path,
            201,
        );
    }
    let path = format!("{base}/estimate");
    ok(call(server, token, "POST", &path, None, &[]), &path, 202);
    id
}

fn wait_done(server: &ServerHandle, token: &str, id: &str) {
    let deadline = Instant::now() + Duration::from_secs(600);
    let path = format!("/v1/sessions/{id}");
    loop {
        let state = call(server, token, "GET", &path, None, &[]).json()["state"].clone();
        if state == "done" {
            return;
        }
        assert!(
            state != "failed" && Instant::now() < deadline,
            "{id}: {state}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn phone(i: usize, subtrajectories: i64) -> Phone {
    Phone {
        dx: (i % 7) as f64 * 0.37 - 1.0,
        x0: (i % 10) as f64 * 0.3,
        subtrajectories,
    }
}

/// One timed request: seconds and the answer.
fn timed(server: &ServerHandle, token: &str, path: &str) -> (f64, Answer) {
    let start = Instant::now();
    let a = call(server, token, "GET", path, None, &[]);
    let s = start.elapsed().as_secs_f64();
    (s, ok(a, path, 200))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn arg(args: &[String], name: &str, default: usize) -> usize {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map_or(default, |v| v.parse().expect(name))
}

/// A fresh database on the cluster's Postgres (made with psql); its URL.
fn fresh_database(url: &str) -> String {
    let name = format!("sitar_venue_bench_{}", std::process::id());
    let status = Command::new("psql")
        .args([url, "-q", "-c", &format!("CREATE DATABASE {name}")])
        .status()
        .expect("psql");
    assert!(status.success(), "psql CREATE DATABASE {name}");
    let (base, _) = url.rsplit_once('/').expect("a database URL");
    format!("{base}/{name}")
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let sessions = arg(&args, "--sessions", 1000);
    let subtrajectories = arg(&args, "--subtrajectories", 45) as i64;
    let repeat = arg(&args, "--repeat", 15);
    let cluster = args.iter().any(|a| a == "--cluster");

    let dir = tempfile::tempdir().unwrap();
    let mut config = ServerConfig::new(dir.path());
    config.limits.sessions_per_hour = u32::MAX;
    if cluster {
        let database = std::env::var("SITAR_TEST_DATABASE_URL")
            .expect("--cluster: eval \"$(scripts/cluster-services start)\" first");
        let store = std::env::var("SITAR_TEST_S3_URL").expect("SITAR_TEST_S3_URL");
        config.database = Some(fresh_database(&database));
        config.store = Some(format!("{store}/venue-bench-{}", std::process::id()));
    }
    let server = Server::spawn(config, "127.0.0.1:0".parse().unwrap()).unwrap();
    let token = std::fs::read_to_string(dir.path().join(sitar_server::ADMIN_TOKEN_FILE))
        .unwrap()
        .trim()
        .to_owned();
    let body = json!({"name": "Bench hall", "anchor": "poster-1", "cell_m": CELL_M}).to_string();
    let a = call(
        &server,
        &token,
        "POST",
        "/v1/venues",
        Some("application/json"),
        body.as_bytes(),
    );
    let venue = ok(a, "POST /v1/venues", 201).json()["id"]
        .as_str()
        .unwrap()
        .to_owned();

    let started = Instant::now();
    let threads = 4;
    let ids: Vec<String> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|k| {
                let (server, token, venue) = (&server, &token, &venue);
                scope.spawn(move || {
                    let mine: Vec<String> = (k..sessions)
                        .step_by(threads)
                        .map(|i| start_session(server, token, venue, &phone(i, subtrajectories)))
                        .collect();
                    for id in &mine {
                        wait_done(server, token, id);
                    }
                    mine
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect()
    });
    eprintln!(
        "{} sessions × {subtrajectories} sub-trajectories finished in {:.1} s ({})",
        ids.len(),
        started.elapsed().as_secs_f64(),
        if cluster {
            "Postgres + S3"
        } else {
            "embedded store"
        }
    );

    let map_path = format!("/v1/venues/{venue}/map.json");
    // Every contribution computed from files: forgotten by uploading each session's
    // anchors.csv again (the same bytes), as a phone resending its log would.
    for (i, id) in ids.iter().enumerate() {
        let text = phone(i, subtrajectories).anchors_csv();
        let path = format!("/v1/sessions/{id}/anchors.csv");
        ok(
            call(
                &server,
                &token,
                "PUT",
                &path,
                Some("text/plain"),
                text.as_bytes(),
            ),
            &path,
            200,
        );
    }
    let (from_files, first) = timed(&server, &token, &map_path);
    let map: Value = first.json();
    let cells = map["cells"].as_array().unwrap().len();
    let listed = map["sessions"].as_array().unwrap().len();
    assert_eq!(listed, sessions);
    let kept: Vec<f64> = (0..repeat)
        .map(|_| {
            let (s, a) = timed(&server, &token, &map_path);
            assert_eq!(
                a.body, first.body,
                "the kept contributions give the same map"
            );
            s
        })
        .collect();
    let glb: Vec<f64> = (0..repeat.div_ceil(3))
        .map(|_| timed(&server, &token, &format!("/v1/venues/{venue}/map.glb")).0)
        .collect();
    let report: Vec<f64> = (0..repeat.div_ceil(3))
        .map(|_| timed(&server, &token, &format!("/v1/venues/{venue}/report")).0)
        .collect();

    // One more session joins: its first map request after it finished, then it leaves.
    let joining = start_session(&server, &token, &venue, &phone(sessions, subtrajectories));
    wait_done(&server, &token, &joining);
    let (joined_s, joined) = timed(&server, &token, &map_path);
    assert_eq!(
        joined.json()["sessions"].as_array().unwrap().len(),
        sessions + 1
    );
    let path = format!("/v1/sessions/{joining}");
    ok(
        call(&server, &token, "DELETE", &path, None, &[]),
        &path,
        200,
    );
    let (left_s, left) = timed(&server, &token, &map_path);
    assert_eq!(
        left.body, first.body,
        "leaving gives the map before it back"
    );

    println!(
        "venue of {sessions} sessions × {subtrajectories} sub-trajectories, {cells} cells, \
         map.json {} KiB ({})",
        first.bytes.len() / 1024,
        if cluster {
            "Postgres + S3"
        } else {
            "embedded store"
        }
    );
    println!("map.json, every contribution computed from files and kept: {from_files:.3} s");
    println!(
        "map.json from kept contributions, median of {repeat}: {:.3} s (min {:.3}, max {:.3})",
        median(kept.clone()),
        kept.iter().copied().fold(f64::INFINITY, f64::min),
        kept.iter().copied().fold(0.0, f64::max)
    );
    println!(
        "map.glb from kept contributions, median of {}: {:.3} s",
        glb.len(),
        median(glb)
    );
    println!(
        "venue report from kept contributions, median of {}: {:.3} s",
        report.len(),
        median(report)
    );
    println!("map.json after a session joined (kept when it finished): {joined_s:.3} s");
    println!("map.json after it left (deleted): {left_s:.3} s");
    server.stop();
}
