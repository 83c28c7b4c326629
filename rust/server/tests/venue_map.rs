//! `GET /v1/venues/{id}/map.json` over loopback against a real server and its SQLite file:
//! two users' sessions in world frames 1 m apart, each aligned by its anchor observations,
//! give the cells computed here by hand from the sessions' own `results.json` (cell centres
//! `(⌊p/c⌋ + ½)·c`, errors a 30 % trimmed mean as `scipy.stats.trim_mean`); the map follows
//! its sessions (finished, deleted) on the next request, and strangers get a 404.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use sitar_server::{Role, ServerHandle};

mod support;
use support::http::{Answer, call};

const CELL_M: f64 = 0.25;
const FRAME_NS: i64 = 33_333_333;
const T0: i64 = 1_700_000_000_000_000_000;

fn t(frame: i64) -> i64 {
    T0 + frame * FRAME_NS
}

/// The walk's camera position at `frame` in the venue frame.
fn position(frame: i64) -> [f64; 3] {
    [0.01 * frame as f64, 1.5, 0.002 * frame as f64]
}

/// The surface point sub-trajectory `k` saw (venue frame), for even `k`.
fn surface(k: i64) -> [f64; 3] {
    [0.3, 1.5, 2.0 + 0.01 * k as f64]
}

/// One user's files, in a world frame shifted by `dx` along x from the venue frame.
struct Phone {
    dx: f64,
}

impl Phone {
    fn trial(&self, noise: f64) -> String {
        (0..=40)
            .map(|i| {
                let p = position(i);
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
        (0..=40)
            .step_by(5)
            .map(|i| {
                let p = position(i);
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
        for k in 0..4 {
            let depth = if k % 2 == 0 {
                let s = surface(k);
                format!(
                    "valid,128,96,2,2,0,0,2,0,0,-1,{},{},{},0,0,-1",
                    s[0] + self.dx,
                    s[1],
                    s[2]
                )
            } else {
                format!("missing{}", ",".repeat(16))
            };
            csv.push_str(&format!(
                "{k},{},{},{},{depth},,\n",
                t(10 * k),
                t(10 * k + 5),
                t(10 * k + 10)
            ));
        }
        csv
    }
}

fn put(server: &ServerHandle, token: &str, path: &str, body: &str) -> Answer {
    let a = call(
        server,
        token,
        "PUT",
        path,
        Some("text/plain"),
        body.as_bytes(),
    );
    assert_eq!(a.status, 200, "{path}: {}", a.body);
    a
}

fn get(server: &ServerHandle, token: &str, path: &str) -> Answer {
    call(server, token, "GET", path, None, &[])
}

/// A finished session of `token` in `venue` with `phone`'s files; its results.json.
fn finished_session(
    server: &ServerHandle,
    token: &str,
    venue: &str,
    phone: &Phone,
) -> (String, Value) {
    let body = json!({"playback": "upload", "trials": 2, "venue": venue}).to_string();
    let a = call(
        server,
        token,
        "POST",
        "/v1/sessions",
        Some("application/json"),
        body.as_bytes(),
    );
    assert_eq!(a.status, 201, "{}", a.body);
    let id = a.json()["id"].as_str().unwrap().to_owned();
    let base = format!("/v1/sessions/{id}");
    put(
        server,
        token,
        &format!("{base}/anchors.csv"),
        &phone.anchors_csv(),
    );
    put(
        server,
        token,
        &format!("{base}/trajectory.txt"),
        &phone.trajectory_txt(),
    );
    put(
        server,
        token,
        &format!("{base}/subtrajectories.csv"),
        &phone.subtrajectories_csv(),
    );
    for noise in [0.0, 0.003] {
        let trial = phone.trial(noise);
        let a = call(
            server,
            token,
            "POST",
            &format!("{base}/trials"),
            Some("text/plain"),
            trial.as_bytes(),
        );
        assert_eq!(a.status, 201, "{}", a.body);
    }
    assert_eq!(
        call(
            server,
            token,
            "POST",
            &format!("{base}/estimate"),
            None,
            &[]
        )
        .status,
        202
    );
    let deadline = Instant::now() + Duration::from_secs(60);
    while get(server, token, &base).json()["state"] != "done" {
        assert!(
            Instant::now() < deadline,
            "{}",
            get(server, token, &base).body
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let results = get(server, token, &format!("{base}/results.json")).json();
    (id, results)
}

/// The error of the window starting at `start` (the sub-trajectory's start; exact here).
fn error_at(results: &Value, start: i64) -> f64 {
    results["windows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["start"].as_f64() == Some(start as f64))
        .unwrap_or_else(|| panic!("no window at {start}: {}", results["windows"][0]))["error_m"]
        .as_f64()
        .unwrap()
}

/// `scipy.stats.trim_mean(values, 0.3)`: cut ⌊0.3·n⌋ from each end of the sorted values.
fn trim_mean_30(values: &[f64]) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let cut = (0.3 * v.len() as f64).floor() as usize;
    let kept = &v[cut..v.len() - cut];
    kept.iter().sum::<f64>() / kept.len() as f64
}

fn centre(p: [f64; 3]) -> [f64; 3] {
    p.map(|v| ((v / CELL_M).floor() + 0.5) * CELL_M)
}

/// Expected cells: (kind, centre as µm integers) → errors of the sub-trajectories in it.
fn expected(results: &[&Value]) -> BTreeMap<(String, [i64; 3]), Vec<f64>> {
    let key =
        |kind: &str, p: [f64; 3]| (kind.to_owned(), centre(p).map(|v| (v * 1e6).round() as i64));
    let mut cells: BTreeMap<_, Vec<f64>> = BTreeMap::new();
    for r in results {
        for k in 0..4 {
            let e = error_at(r, t(10 * k));
            cells
                .entry(key("path", position(10 * k + 5)))
                .or_default()
                .push(e);
            if k % 2 == 0 {
                cells.entry(key("surface", surface(k))).or_default().push(e);
            }
        }
    }
    cells
}

fn assert_cells(map: &Value, expected: &BTreeMap<(String, [i64; 3]), Vec<f64>>, sessions: u64) {
    let cells = map["cells"].as_array().unwrap();
    assert_eq!(cells.len(), expected.len(), "{map}");
    for cell in cells {
        let c: Vec<f64> = cell["center"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let key = (
            cell["kind"].as_str().unwrap().to_owned(),
            [c[0], c[1], c[2]].map(|v| (v * 1e6).round() as i64),
        );
        let errors = expected
            .get(&key)
            .unwrap_or_else(|| panic!("unexpected cell {cell}"));
        assert_eq!(
            cell["subtrajectories"].as_u64().unwrap() as usize,
            errors.len(),
            "{cell}"
        );
        assert_eq!(cell["sessions"], sessions, "{cell}");
        let want = trim_mean_30(errors);
        let got = cell["error_m"].as_f64().unwrap();
        assert!(
            (got - want).abs() <= 1e-12 * want.abs().max(1e-3),
            "{cell}: {want}"
        );
        let directions: u64 = cell["directions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap())
            .sum();
        assert_eq!(
            directions as usize,
            errors.len(),
            "every camera has a heading: {cell}"
        );
    }
}

#[test]
fn the_venue_map_is_built_from_its_sessions_files_and_follows_them() {
    let dir = tempfile::tempdir().unwrap();
    let (server, admin) = support::spawn_with_admin(dir.path());
    let owner = sitar_server::create_token(dir.path(), Role::App, "owner").unwrap();
    let member = sitar_server::create_token(dir.path(), Role::App, "member").unwrap();
    let stranger = sitar_server::create_token(dir.path(), Role::App, "stranger").unwrap();
    let body = json!({"name": "Hall", "anchor": "poster-1", "cell_m": CELL_M}).to_string();
    let a = call(
        &server,
        &owner,
        "POST",
        "/v1/venues",
        Some("application/json"),
        body.as_bytes(),
    );
    let venue = a.json()["id"].as_str().unwrap().to_owned();
    assert_eq!(
        call(
            &server,
            &owner,
            "PUT",
            &format!("/v1/venues/{venue}/members/member"),
            None,
            &[]
        )
        .status,
        200
    );
    let map_path = format!("/v1/venues/{venue}/map.json");

    let empty = get(&server, &owner, &map_path).json();
    assert_eq!(
        (&empty["id"], &empty["unit"], &empty["cells"]),
        (&json!(venue), &json!("m"), &json!([]))
    );

    let (first, first_results) = finished_session(&server, &owner, &venue, &Phone { dx: 0.0 });
    let map = get(&server, &owner, &map_path).json();
    assert_eq!(
        (&map["anchor"], &map["cell_m"], &map["convention"]),
        (&json!("poster-1"), &json!(CELL_M), &json!("unity"))
    );
    assert_cells(&map, &expected(&[&first_results]), 1);
    assert_eq!(map["sessions"][0]["id"], json!(first));
    assert_eq!(map["sessions"][0]["aligned"], true);
    assert_eq!(map["sessions"][0]["subtrajectories"], 4);

    // A second user, whose world frame is 1 m off: the same cells, seen by two sessions.
    let (second, second_results) = finished_session(&server, &member, &venue, &Phone { dx: 1.0 });
    let map = get(&server, &member, &map_path).json();
    assert_cells(&map, &expected(&[&first_results, &second_results]), 2);
    let worst = map["cells"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["error_m"].as_f64().unwrap())
        .fold(0.0, f64::max);
    assert!(
        worst > 1e-4,
        "the trials differ, so some cell has an error: {map}"
    );
    let both = get(&server, &admin, &format!("{map_path}?min_sessions=2")).json();
    assert_eq!(
        both["cells"].as_array().unwrap().len(),
        map["cells"].as_array().unwrap().len()
    );

    // The report: both sessions with their spread, coverage in words; strangers get 404.
    let page = get(&server, &member, &format!("/v1/venues/{venue}/report"));
    assert_eq!(page.status, 200, "{}", page.body);
    for needed in [
        "<svg id=\"topview\"",
        &first,
        &second,
        "seen only from the",
        "0.0 cm",
        "Hall",
    ] {
        assert!(page.body.contains(needed), "{needed}: {}", page.body);
    }
    assert!(
        page.body.contains("(yours)"),
        "the member's own session is marked"
    );
    let file = get(
        &server,
        &owner,
        &format!("/v1/venues/{venue}/report?download=1"),
    );
    assert_eq!(file.status, 200);
    let head = file.head.to_ascii_lowercase();
    assert!(
        head.contains("content-disposition: attachment; filename=\"venue-"),
        "{head}"
    );
    assert!(
        head.contains("style-src 'sha256-") && !file.body.contains("/assets/"),
        "{head}"
    );
    assert_eq!(
        get(&server, &stranger, &format!("/v1/venues/{venue}/report")).status,
        404
    );

    // A session not yet finished and one without anchors bring no cells, and say so.
    let body = json!({"playback": "upload", "venue": venue}).to_string();
    let a = call(
        &server,
        &owner,
        "POST",
        "/v1/sessions",
        Some("application/json"),
        body.as_bytes(),
    );
    let idle = a.json()["id"].as_str().unwrap().to_owned();
    let map = get(&server, &owner, &map_path).json();
    let listed = map["sessions"].as_array().unwrap();
    assert_eq!(listed.len(), 3);
    let idle_entry = listed.iter().find(|s| s["id"] == json!(idle)).unwrap();
    assert_eq!(idle_entry["aligned"], false, "{idle_entry}");
    assert!(
        idle_entry["reason"].as_str().unwrap().contains("anchors"),
        "{idle_entry}"
    );
    assert_cells(&map, &expected(&[&first_results, &second_results]), 2);

    // The next request after a deletion follows it.
    assert_eq!(
        call(
            &server,
            &member,
            "DELETE",
            &format!("/v1/sessions/{second}"),
            None,
            &[]
        )
        .status,
        200
    );
    let map = get(&server, &owner, &map_path).json();
    assert_cells(&map, &expected(&[&first_results]), 1);
    assert_eq!(
        get(&server, &owner, &format!("{map_path}?min_sessions=2")).json()["cells"],
        json!([])
    );

    // Bad parameters are named; strangers are told the venue does not exist.
    for bad in ["min_sessions=0", "min_sessions=x", "limit=2"] {
        let a = get(&server, &owner, &format!("{map_path}?{bad}"));
        assert_eq!(a.status, 400, "{bad}: {}", a.body);
        assert!(
            a.message().contains(bad.split('=').next().unwrap()),
            "{}",
            a.body
        );
    }
    assert_eq!(get(&server, &stranger, &map_path).status, 404);
    server.stop();
}
