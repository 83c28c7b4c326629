//! Venues over loopback against a real server and its SQLite file: who sees what (owner,
//! members, admins; 404 for everyone else), sessions joining with one convention, their
//! alignment from the phone's `anchors.csv`, and the phone's log checked whole on arrival.

use std::path::Path;

use serde_json::{Value, json};
use sitar_server::{Role, ServerHandle};

mod support;
use support::http::{Answer, call};

struct World {
    dir: tempfile::TempDir,
    server: ServerHandle,
    admin: String,
    owner: String,
    member: String,
    stranger: String,
}

fn start() -> World {
    let dir = tempfile::tempdir().unwrap();
    let (server, admin) = support::spawn_with_admin(dir.path());
    let token = |name| sitar_server::create_token(dir.path(), Role::App, name).unwrap();
    World {
        owner: token("owner"),
        member: token("member"),
        stranger: token("stranger"),
        admin,
        server,
        dir,
    }
}

impl World {
    fn call(&self, token: &str, method: &str, path: &str, body: Option<Value>) -> Answer {
        let bytes = body.map(|b| b.to_string().into_bytes()).unwrap_or_default();
        call(
            &self.server,
            token,
            method,
            path,
            Some("application/json"),
            &bytes,
        )
    }

    fn put(&self, token: &str, path: &str, text: &str) -> Answer {
        call(
            &self.server,
            token,
            "PUT",
            path,
            Some("text/plain"),
            text.as_bytes(),
        )
    }

    fn venue(&self, token: &str) -> String {
        let a = self.call(
            token,
            "POST",
            "/v1/venues",
            Some(json!({"name": "Lobby", "anchor": "poster-1"})),
        );
        assert_eq!(a.status, 201, "{}", a.body);
        a.json()["id"].as_str().unwrap().to_owned()
    }

    fn session(&self, token: &str, body: Value) -> Answer {
        self.call(token, "POST", "/v1/sessions", Some(body))
    }

    fn session_id(&self, token: &str, body: Value) -> String {
        let a = self.session(token, body);
        assert_eq!(a.status, 201, "{}", a.body);
        a.json()["id"].as_str().unwrap().to_owned()
    }
}

fn is_venue_id(id: &str) -> bool {
    id.len() == 17
        && id.starts_with('v')
        && id[1..]
            .bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b))
}

#[test]
fn a_venue_is_seen_by_its_owner_its_members_and_admins_only() {
    let w = start();
    let id = w.venue(&w.owner);
    assert!(is_venue_id(&id), "{id}");
    let got = w
        .call(&w.owner, "GET", &format!("/v1/venues/{id}"), None)
        .json();
    assert_eq!(
        (&got["name"], &got["anchor"], &got["cell_m"], &got["role"]),
        (
            &json!("Lobby"),
            &json!("poster-1"),
            &json!(0.25),
            &json!("owner")
        )
    );
    assert_eq!(got["members"], json!([]));

    // Strangers (and members-to-be) are told it does not exist, on every venue route.
    let routes = [
        ("GET", format!("/v1/venues/{id}")),
        ("DELETE", format!("/v1/venues/{id}")),
        ("PUT", format!("/v1/venues/{id}/members/stranger")),
        ("DELETE", format!("/v1/venues/{id}/members/member")),
    ];
    for token in [&w.stranger, &w.member] {
        for (method, path) in &routes {
            let a = w.call(token, method, path, None);
            assert_eq!(a.status, 404, "{method} {path}: {}", a.body);
            assert!(a.message().contains(&id), "{}", a.body);
        }
        let listed = w.call(token, "GET", "/v1/venues", None).json();
        assert_eq!(listed["venues"], json!([]));
    }
    // The same 404 as an id that does not exist, and a malformed one.
    for path in ["/v1/venues/v0000000000000000", "/v1/venues/..%2f"] {
        assert_eq!(w.call(&w.owner, "GET", path, None).status, 404);
    }

    // Membership: by token name, owner only; an unknown name is a 404.
    let member_path = format!("/v1/venues/{id}/members/member");
    let a = w.call(&w.owner, "PUT", &member_path, None);
    assert_eq!(
        (a.status, &a.json()["member"]),
        (200, &json!("member")),
        "{}",
        a.body
    );
    let a = w.call(
        &w.owner,
        "PUT",
        &format!("/v1/venues/{id}/members/nobody"),
        None,
    );
    assert_eq!(a.status, 404, "{}", a.body);
    assert!(a.message().contains("nobody"), "{}", a.body);
    let seen = w.call(&w.member, "GET", &format!("/v1/venues/{id}"), None);
    assert_eq!(seen.status, 200, "{}", seen.body);
    assert_eq!(seen.json()["role"], "member");
    assert!(
        seen.json().get("members").is_none(),
        "only the owner sees members"
    );
    let listed = w.call(&w.member, "GET", "/v1/venues", None).json();
    assert_eq!(listed["venues"][0]["id"], json!(id));
    // A member may not change the venue: 403, not 404 (it sees the venue).
    for (method, path) in [
        ("DELETE", format!("/v1/venues/{id}")),
        ("PUT", format!("/v1/venues/{id}/members/stranger")),
        ("DELETE", member_path.clone()),
    ] {
        let a = w.call(&w.member, method, &path, None);
        assert_eq!(a.status, 403, "{method} {path}: {}", a.body);
    }
    assert_eq!(
        w.call(&w.owner, "GET", &format!("/v1/venues/{id}"), None)
            .json()["members"],
        json!(["member"])
    );

    // Admins see every venue.
    let other = w.venue(&w.stranger);
    let all = w.call(&w.admin, "GET", "/v1/venues", None).json();
    let ids: Vec<&str> = all["venues"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v["id"].as_str().unwrap())
        .collect();
    assert_eq!(ids, [other.as_str(), id.as_str()], "newest first");
    assert_eq!(
        w.call(&w.admin, "GET", "/v1/venues?limit=1", None).json()["venues"]
            .as_array()
            .unwrap()
            .len(),
        1
    );
    assert_eq!(
        w.call(&w.admin, "GET", "/v1/venues?limit=0", None).status,
        400
    );
    assert_eq!(
        w.call(&w.admin, "GET", &format!("/v1/venues/{other}"), None)
            .json()["role"],
        "admin"
    );

    // Ending the membership hides the venue again.
    let a = w.call(&w.owner, "DELETE", &member_path, None);
    assert_eq!(
        (a.status, &a.json()["removed"]),
        (200, &json!(true)),
        "{}",
        a.body
    );
    assert_eq!(
        w.call(&w.member, "GET", &format!("/v1/venues/{id}"), None)
            .status,
        404
    );
    w.server.stop();
}

#[test]
fn a_bad_venue_request_names_its_key() {
    let w = start();
    for (body, status, key) in [
        (
            json!({"name": "L", "anchor": "a", "cell_m": 0.01}),
            422,
            "cell_m",
        ),
        (
            json!({"name": "L", "anchor": "a", "cell_m": 2.5}),
            422,
            "cell_m",
        ),
        (json!({"name": "L", "anchor": "a,b"}), 422, "anchor"),
        (
            json!({"name": "L", "anchor": "x".repeat(65)}),
            422,
            "anchor",
        ),
        (json!({"name": "", "anchor": "a"}), 422, "name"),
        (json!({"name": "L"}), 400, "anchor"),
        (
            json!({"name": "L", "anchor": "a", "cells": 1}),
            400,
            "cells",
        ),
    ] {
        let a = w.call(&w.owner, "POST", "/v1/venues", Some(body.clone()));
        assert_eq!(a.status, status, "{body}: {}", a.body);
        assert!(a.message().starts_with(key), "{body}: {}", a.body);
    }
    let a = w.call(
        &w.owner,
        "POST",
        "/v1/venues",
        Some(json!({"name": "L", "anchor": "a", "cell_m": 2})),
    );
    assert_eq!(a.status, 201, "{}", a.body);
    let id = a.json()["id"].as_str().unwrap().to_owned();
    assert_eq!(
        w.call(&w.owner, "GET", &format!("/v1/venues/{id}"), None)
            .json()["cell_m"],
        2.0
    );
    assert_eq!(
        w.call(&w.stranger, "GET", "/v1/venues", None).json()["venues"],
        json!([])
    );
    w.server.stop();
}

#[test]
fn sessions_join_a_venue_they_can_see_with_one_convention() {
    let w = start();
    let venue = w.venue(&w.owner);
    w.call(
        &w.owner,
        "PUT",
        &format!("/v1/venues/{venue}/members/member"),
        None,
    );

    // A venue the caller cannot see, or a convention no phone has: 422 naming the key.
    for (token, body, key) in [
        (
            &w.stranger,
            json!({"playback": "upload", "venue": venue}),
            "venue",
        ),
        (
            &w.owner,
            json!({"playback": "upload", "venue": "v0000000000000000"}),
            "venue",
        ),
        (
            &w.owner,
            json!({"playback": "upload", "venue": "../etc"}),
            "venue",
        ),
        (
            &w.owner,
            json!({"playback": "upload", "convention": "opengl"}),
            "convention",
        ),
    ] {
        let a = w.session(token, body.clone());
        assert_eq!(a.status, 422, "{body}: {}", a.body);
        assert!(a.message().starts_with(key), "{body}: {}", a.body);
    }
    let first = w.session_id(
        &w.owner,
        json!({"playback": "upload", "venue": venue, "convention": "arcore"}),
    );
    // Another convention: 409 naming both.
    let a = w.session(&w.member, json!({"playback": "upload", "venue": venue}));
    assert_eq!(a.status, 409, "{}", a.body);
    let message = a.message();
    assert!(
        message.contains("arcore") && message.contains("unity"),
        "{message}"
    );
    let theirs = w.session_id(
        &w.member,
        json!({"playback": "upload", "venue": venue, "convention": "arcore"}),
    );

    let status = w
        .call(&w.member, "GET", &format!("/v1/sessions/{theirs}"), None)
        .json();
    assert_eq!(
        (&status["venue"], &status["alignment"]),
        (&json!(venue), &Value::Null)
    );
    let alone = w.session_id(&w.owner, json!({"playback": "upload"}));
    let status = w
        .call(&w.owner, "GET", &format!("/v1/sessions/{alone}"), None)
        .json();
    assert_eq!(
        (&status["venue"], &status["alignment"]),
        (&Value::Null, &Value::Null)
    );

    // Nobody reads another member's sessions through the venue.
    let seen = |token: &str| {
        w.call(token, "GET", &format!("/v1/venues/{venue}"), None)
            .json()
    };
    assert_eq!(seen(&w.member)["sessions"], json!([theirs]));
    assert_eq!(seen(&w.owner)["sessions"], json!([first]));
    assert_eq!(seen(&w.admin)["sessions"], json!([first, theirs]));
    assert_eq!(
        (
            &seen(&w.member)["session_count"],
            &seen(&w.member)["convention"]
        ),
        (&json!(2), &json!("arcore"))
    );
    assert_eq!(
        w.call(&w.owner, "GET", &format!("/v1/sessions/{theirs}"), None)
            .status,
        404
    );

    // A deleted session leaves the venue; a deleted venue keeps its sessions.
    assert_eq!(
        w.call(&w.member, "DELETE", &format!("/v1/sessions/{theirs}"), None)
            .status,
        200
    );
    assert_eq!(seen(&w.owner)["session_count"], 1);
    let a = w.call(&w.owner, "DELETE", &format!("/v1/venues/{venue}"), None);
    assert_eq!(
        (a.status, &a.json()["deleted"]),
        (200, &json!(true)),
        "{}",
        a.body
    );
    let kept = w.call(&w.owner, "GET", &format!("/v1/sessions/{first}"), None);
    assert_eq!(kept.status, 200, "{}", kept.body);
    assert_eq!(kept.json()["venue"], Value::Null);
    assert_eq!(
        w.call(&w.owner, "GET", &format!("/v1/venues/{venue}"), None)
            .status,
        404
    );
    w.server.stop();
}

/// `anchors.csv` rows: the image seen about (1, 1.5, −2) (x ± 5 mm) with heading 30°, `full` times,
/// then `limited` observations far off.
fn anchors_csv(full: usize, limited: usize) -> String {
    let h = 30f64.to_radians() / 2.0;
    let mut csv = String::from("t_ns,anchor,px,py,pz,qx,qy,qz,qw,tracking\n");
    for k in 0..full {
        let wobble = if k % 2 == 0 { 0.005 } else { -0.005 };
        csv.push_str(&format!(
            "{},poster-1,{},1.5,-2,0,{},0,{},full\n",
            1000 + k,
            1.0 + wobble,
            h.sin(),
            h.cos()
        ));
    }
    for k in 0..limited {
        csv.push_str(&format!("{},poster-1,9,9,9,0,0,0,1,limited\n", 5000 + k));
    }
    csv
}

#[test]
fn the_phones_log_is_checked_whole_and_gives_the_alignment() {
    let w = start();
    let venue = w.venue(&w.owner);
    let id = w.session_id(
        &w.owner,
        json!({"playback": "upload", "trials": 2, "venue": venue}),
    );
    let base = format!("/v1/sessions/{id}");
    let status = || w.call(&w.owner, "GET", &base, None).json();

    // anchors.csv: a bad cell is a 422 naming line and column, and nothing is stored.
    let bad = anchors_csv(3, 0).replace("1.5,-2,0", "1.5,-2,zero");
    let a = w.put(&w.owner, &format!("{base}/anchors.csv"), &bad);
    assert_eq!(a.status, 422, "{}", a.body);
    assert!(
        a.message().contains("line 2") && a.message().contains("qx"),
        "{}",
        a.body
    );
    assert_eq!(status()["alignment"], Value::Null);
    // Only limited observations: not aligned, and why.
    let a = w.put(&w.owner, &format!("{base}/anchors.csv"), &anchors_csv(0, 2));
    assert_eq!(
        (a.status, &a.json()["observations"]),
        (200, &json!(2)),
        "{}",
        a.body
    );
    let why = status()["alignment"]["error"].as_str().unwrap().to_owned();
    assert!(why.contains("full"), "{why}");
    // Replaced whole: 4 full (±5 mm about x = 1) and 2 limited; the spread is exactly 5 mm.
    let a = w.put(&w.owner, &format!("{base}/anchors.csv"), &anchors_csv(4, 2));
    assert_eq!(a.json()["observations"], 6);
    let alignment = status()["alignment"].clone();
    assert_eq!(
        (&alignment["anchor"], &alignment["observations"]),
        (&json!("poster-1"), &json!(4))
    );
    let spread = alignment["position_spread_m"].as_f64().unwrap();
    assert!((spread - 0.005).abs() < 1e-9, "{alignment}");
    assert!(
        alignment["heading_spread_deg"].as_f64().unwrap() < 1e-9,
        "{alignment}"
    );

    // trajectory.txt: TUM, integer ns, rising; served back as sent.
    let tum = "100 0 0 0 0 0 0 1\n200 0.1 0 0 0 0 0 1\n300 0.2 0 0 0 0 0 1\n";
    for (bad, line, column) in [
        (tum.replace("200 0.1", "200.5 0.1"), "line 2", "timestamp"),
        (tum.replace("300 0.2", "150 0.2"), "line 3", "timestamp"),
        (
            tum.replace("0.2 0 0 0 0 0 1", "0.2 0 0 0 0 0"),
            "line 3",
            "row",
        ),
    ] {
        let a = w.put(&w.owner, &format!("{base}/trajectory.txt"), &bad);
        assert_eq!(a.status, 422, "{}", a.body);
        assert!(
            a.message().contains(line) && a.message().contains(column),
            "{}",
            a.body
        );
    }
    assert_ne!(
        w.call(&w.owner, "GET", &format!("{base}/trajectory.tum"), None)
            .status,
        200
    );
    let a = w.put(&w.owner, &format!("{base}/trajectory.txt"), tum);
    assert_eq!(
        (a.status, &a.json()["poses"]),
        (200, &json!(3)),
        "{}",
        a.body
    );
    let served = w.call(&w.owner, "GET", &format!("{base}/trajectory.tum"), None);
    assert_eq!((served.status, served.body.as_str()), (200, tum));

    // subtrajectories.csv in sitar-core's header: read whole.
    let header = "index,start_ns,mid_ns,end_ns,depth,pixel_x,pixel_y,depth_m,distance_m,cam_x,cam_y,cam_z,cam_nx,cam_ny,cam_nz,x,y,z,nx,ny,nz,error_m,class";
    let valid = "valid,128,96,1.5,1.52,0.1,0.2,-1.5,0,0,1,0.3,1.4,-2.1,0,0,1";
    let table = format!(
        "{header}\n0,100,150,200,{valid},,\n1,200,250,300,missing{},,\n",
        ",".repeat(16)
    );
    let bad = table.replace("-2.1,0,0,1", "-2.1,0,0,3");
    let a = w.put(&w.owner, &format!("{base}/subtrajectories.csv"), &bad);
    assert_eq!(a.status, 422, "{}", a.body);
    assert!(a.message().contains("line 2, column `nx`"), "{}", a.body);
    let listed = w
        .call(&w.owner, "GET", &format!("{base}/subtrajectories"), None)
        .json();
    assert_eq!(listed["subtrajectories"], json!([]), "nothing stored");
    let a = w.put(&w.owner, &format!("{base}/subtrajectories.csv"), &table);
    assert_eq!(a.status, 200, "{}", a.body);
    assert_eq!(
        (&a.json()["subtrajectories"], &a.json()["depth_samples"]),
        (&json!(2), &json!(1))
    );

    // Owner only: another token is told the session does not exist.
    assert_eq!(
        w.put(
            &w.stranger,
            &format!("{base}/anchors.csv"),
            &anchors_csv(1, 0)
        )
        .status,
        404
    );
    // Bounded: a declared body over the limit is refused before it is read.
    let a = call(
        &w.server,
        &w.owner,
        "PUT",
        &format!("{base}/trajectory.txt"),
        Some("text/plain"),
        &[],
    );
    assert_eq!(a.status, 422, "an empty log has no poses: {}", a.body);
    let big = oversized(&w.server, &w.owner, &format!("{base}/anchors.csv"), 9 << 20);
    assert_eq!(big, 413);

    // Still accepted once the session is finished.
    for k in 0..2 {
        let trial: String = (0..40)
            .map(|i| {
                format!(
                    "{} {} 0 {} 0 0 0 1\n",
                    1_000_000 + i * 33_000_000,
                    0.01 * i as f64 + 0.001 * k as f64,
                    0.002 * i as f64
                )
            })
            .collect();
        let a = call(
            &w.server,
            &w.owner,
            "POST",
            &format!("{base}/trials"),
            Some("text/plain"),
            trial.as_bytes(),
        );
        assert_eq!(a.status, 201, "{}", a.body);
    }
    assert_eq!(
        w.call(&w.owner, "POST", &format!("{base}/estimate"), None)
            .status,
        202
    );
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while status()["state"] != "done" {
        assert!(std::time::Instant::now() < deadline, "{}", status());
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    assert_eq!(
        w.put(&w.owner, &format!("{base}/anchors.csv"), &anchors_csv(5, 0))
            .status,
        200
    );
    assert_eq!(status()["alignment"]["observations"], 5);

    // Deleting the session removes its log with it.
    let folder = w.dir.path().join("sessions").join(&id);
    assert!(folder.join("phone_log").is_dir());
    assert_eq!(w.call(&w.owner, "DELETE", &base, None).status, 200);
    assert!(!Path::new(&folder).exists());
    w.server.stop();
}

/// The status of a `PUT` that declares `bytes` and sends none of them.
fn oversized(server: &ServerHandle, token: &str, path: &str, bytes: u64) -> u16 {
    use std::io::{Read, Write};
    let mut stream = std::net::TcpStream::connect(server.addr()).unwrap();
    let head = format!(
        "PUT {path} HTTP/1.1\r\nHost: localhost\r\nAuthorization: Bearer {token}\r\n\
         Content-Type: text/csv\r\nContent-Length: {bytes}\r\nConnection: close\r\n\r\n"
    );
    stream.write_all(head.as_bytes()).unwrap();
    let mut raw = Vec::new();
    let _ = stream.read_to_end(&mut raw);
    String::from_utf8_lossy(&raw)
        .split(' ')
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0)
}
