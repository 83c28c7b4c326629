//! Access control over loopback against the real server: every route without a token, with
//! a wrong one, with another app's token (404) and with an app token on admin routes (403);
//! the admin token file; what the database holds; revocation; the page cookie; legacy
//! `?token=`; share links; `--insecure-no-auth`; the request log's token names.

use std::sync::Mutex;

use sitar_client::{NewSession, SessionState};
use sitar_tests::*;

/// Every route with a method it answers, `{id}` standing for a session id.
const ROUTES: &[(&str, &str)] = &[
    ("GET", "/"),
    ("GET", "/favicon.ico"),
    ("POST", "/v1/sessions"),
    ("GET", "/v1/sessions"),
    ("GET", "/v1/sessions/{id}"),
    ("DELETE", "/v1/sessions/{id}"),
    ("PUT", "/v1/sessions/{id}/recording"),
    ("HEAD", "/v1/sessions/{id}/recording"),
    ("POST", "/v1/sessions/{id}/trials"),
    ("POST", "/v1/sessions/{id}/estimate"),
    ("GET", "/v1/sessions/{id}/results.csv"),
    ("GET", "/v1/sessions/{id}/results.json"),
    ("GET", "/v1/sessions/{id}/report"),
    ("PUT", "/v1/sessions/{id}/evidence.csv"),
    ("PUT", "/v1/sessions/{id}/subtrajectories.csv"),
    ("GET", "/v1/sessions/{id}/subtrajectories"),
    ("PUT", "/v1/sessions/{id}/subtrajectories/0/image.jpg"),
    ("GET", "/v1/sessions/{id}/subtrajectories/0/image.jpg"),
    ("POST", "/v1/sessions/{id}/share"),
    ("DELETE", "/v1/sessions/{id}/share"),
    ("GET", "/v1/devices"),
    ("POST", "/recording"),
    ("POST", "/timestamps"),
    ("GET", "/results.csv"),
];

/// (status, headers as lower-case `name: value` lines, body) of a request with `auth` as the
/// whole `Authorization` header (none when `None`) and extra headers.
fn call(
    method: &str,
    url: &str,
    auth: Option<&str>,
    headers: &[(&str, &str)],
) -> (u16, String, String) {
    let agent = bare_agent();
    let mut builder = ureq::http::Request::builder().method(method).uri(url);
    if let Some(auth) = auth {
        builder = builder.header("authorization", auth);
    }
    for (k, v) in headers {
        builder = builder.header(*k, *v);
    }
    let request = builder.body(()).unwrap();
    let mut response = agent.run(request).expect("request goes through");
    let head = response
        .headers()
        .iter()
        .map(|(k, v)| format!("{}: {}", k.as_str(), v.to_str().unwrap_or("?")))
        .collect::<Vec<_>>()
        .join("\n");
    let body = response.body_mut().read_to_string().unwrap_or_default();
    (response.status().as_u16(), head, body)
}

fn bearer(token: &str) -> String {
    format!("Bearer {token}")
}

fn upload_session() -> NewSession {
    NewSession {
        trials: 2,
        setting: "median".into(),
        playback: "upload".into(),
        window_frames: None,
        pose_relation: None,
    }
}

#[test]
fn every_route_but_the_health_check_needs_a_known_token() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 20.0, 1));
    let base = server.url();
    let id = client(&server).create_session(&upload_session()).unwrap();
    let (status, _, _) = call("GET", &format!("{base}/healthz"), None, &[]);
    assert_eq!(status, 200);
    let wrong = bearer("sitar_0000000000000000000000000000000000000000");
    for (method, route) in ROUTES {
        let url = format!("{base}{}", route.replace("{id}", &id));
        for auth in [
            None,
            Some(wrong.as_str()),
            Some("Basic dXNlcjpwYXNz"),
            Some("Bearer <x>"),
        ] {
            let (status, head, body) = call(method, &url, auth, &[]);
            assert_eq!(status, 401, "{method} {route} with {auth:?}: {body}");
            assert!(
                head.contains("www-authenticate: Bearer"),
                "{method} {route}: {head}"
            );
            if *method != "HEAD" {
                let code = error_code(status, "application/json", &body, 401);
                assert_eq!(code, "unauthorized", "{method} {route}");
            }
        }
        // The admin token gets past authentication on every route.
        let (status, _, body) = call(method, &url, Some(&bearer(ADMIN_TOKEN)), &[]);
        assert!(
            ![401, 403].contains(&status),
            "{method} {route}: {status} {body}"
        );
    }
    // A cookie does not authenticate writes.
    let cookie = format!("sitar_token={ADMIN_TOKEN}");
    let (status, _, _) = call(
        "DELETE",
        &format!("{base}/v1/sessions/{id}"),
        None,
        &[("cookie", &cookie)],
    );
    assert_eq!(status, 401);
    // (The loop above deleted the session; reading the list works by cookie.)
    let (status, _, _) = call(
        "GET",
        &format!("{base}/v1/sessions"),
        None,
        &[("cookie", &cookie)],
    );
    assert_eq!(status, 200);
}

#[test]
fn app_tokens_see_only_their_own_sessions_and_no_admin_routes() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 20.0, 1));
    let base = server.url();
    let mine = client_with(&server, APP_TOKEN)
        .create_session(&upload_session())
        .unwrap();
    let theirs = client_with(&server, APP2_TOKEN)
        .create_session(&upload_session())
        .unwrap();

    for (method, route) in ROUTES.iter().filter(|(_, r)| r.contains("{id}")) {
        let url = format!("{base}{}", route.replace("{id}", &theirs));
        let (status, _, body) = call(method, &url, Some(&bearer(APP_TOKEN)), &[]);
        assert_eq!(status, 404, "{method} {route}: {body}");
        // The same answer as for a session that does not exist: nothing is revealed.
        if *method == "GET" && route.ends_with("{id}") {
            assert_eq!(body.replace(&theirs, "X"), {
                let (_, _, none) = call(
                    method,
                    &format!("{base}/v1/sessions/s0000000000000000"),
                    Some(&bearer(APP_TOKEN)),
                    &[],
                );
                none.replace("s0000000000000000", "X")
            });
        }
    }
    for route in ["/", "/v1/devices"] {
        let (status, _, body) = call(
            "GET",
            &format!("{base}{route}"),
            Some(&bearer(APP_TOKEN)),
            &[],
        );
        assert_eq!(status, 403, "{route}: {body}");
        assert_eq!(
            error_code(status, "application/json", &body, 403),
            "forbidden"
        );
    }
    // Lists: an app its own, the admin both.
    let ids = |token: &str| -> Vec<String> {
        let (_, _, body) = call(
            "GET",
            &format!("{base}/v1/sessions"),
            Some(&bearer(token)),
            &[],
        );
        let v: serde_json::Value = serde_json::from_str(&body).unwrap();
        v["sessions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["id"].as_str().unwrap().to_owned())
            .collect()
    };
    assert_eq!(ids(APP_TOKEN), std::slice::from_ref(&mine));
    assert_eq!(ids(APP2_TOKEN), std::slice::from_ref(&theirs));
    assert_eq!(ids(ADMIN_TOKEN), [theirs.clone(), mine.clone()]);
    // The same idempotency key from two apps makes two sessions.
    let key = [
        ("idempotency-key", "same-key"),
        ("content-type", "application/json"),
    ];
    let create = |token: &str| {
        let (_, _, body) = raw(
            "POST",
            &format!("{base}/v1/sessions"),
            Some("application/json"),
            b"{}",
            &[("authorization", &bearer(token)), key[0]],
        );
        serde_json::from_str::<serde_json::Value>(&body).unwrap()["id"]
            .as_str()
            .unwrap()
            .to_owned()
    };
    let a = create(APP_TOKEN);
    assert_eq!(create(APP_TOKEN), a);
    assert_ne!(create(APP2_TOKEN), a);
    // An app deletes its own; the admin deletes anyone's.
    let (status, _, _) = call(
        "DELETE",
        &format!("{base}/v1/sessions/{mine}"),
        Some(&bearer(APP_TOKEN)),
        &[],
    );
    assert_eq!(status, 200);
    let (status, _, _) = call(
        "DELETE",
        &format!("{base}/v1/sessions/{theirs}"),
        Some(&bearer(ADMIN_TOKEN)),
        &[],
    );
    assert_eq!(status, 200);
}

#[test]
fn a_new_data_directory_gets_a_private_admin_token_and_the_database_no_raw_token() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let server = start(sim_config(&data, 20.0, 1));
    let file = data.join(sitar_server::ADMIN_TOKEN_FILE);
    let admin = std::fs::read_to_string(&file).unwrap().trim().to_owned();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        assert_eq!(
            std::fs::metadata(&file).unwrap().permissions().mode() & 0o777,
            0o600
        );
    }
    assert!(admin.len() >= 38, "{admin}");
    let (status, _, _) = call(
        "GET",
        &format!("{}/v1/sessions", server.url()),
        Some(&bearer(&admin)),
        &[],
    );
    assert_eq!(status, 200);
    let app = sitar_server::create_token(&data, sitar_server::Role::App, "lab-phone").unwrap();
    let id = client_with(&server, &app)
        .create_session(&upload_session())
        .unwrap();
    assert!(!id.is_empty());
    server.stop();
    // A restart keeps the file as it was.
    let server = start(sim_config(&data, 20.0, 1));
    assert_eq!(std::fs::read_to_string(&file).unwrap().trim(), admin);
    server.stop();
    // No token, whole or in part, in any file the database keeps.
    for entry in std::fs::read_dir(&data).unwrap() {
        let path = entry.unwrap().path();
        if path
            .file_name()
            .unwrap()
            .to_string_lossy()
            .starts_with("sitar.db")
        {
            let bytes = String::from_utf8_lossy(&std::fs::read(&path).unwrap()).into_owned();
            for token in [&admin, &app, ADMIN_TOKEN, APP_TOKEN] {
                let secret = &token[token.len() - 20..];
                assert!(!bytes.contains(secret), "{} holds a token", path.display());
            }
        }
    }
}

#[test]
fn a_revoked_token_fails_on_its_next_request() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let server = start(sim_config(&data, 20.0, 1));
    let token = sitar_server::create_token(&data, sitar_server::Role::App, "soon-gone").unwrap();
    let app = client_with(&server, &token);
    let id = app.create_session(&upload_session()).unwrap();
    assert!(app.status(&id).is_ok());
    let listed = sitar_server::list_tokens(&data).unwrap();
    let gone = listed.iter().find(|t| t.name == "soon-gone").unwrap();
    assert!(gone.last_used_ms.is_some());
    assert!(sitar_server::revoke_token(&data, "soon-gone").unwrap());
    let err = app.status(&id).unwrap_err();
    assert_eq!(err.status(), Some(401), "{err}");
}

#[test]
fn a_page_visit_with_a_token_becomes_a_strict_cookie_and_a_clean_address() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 20.0, 1));
    let base = server.url();
    let (status, head, _) = call(
        "GET",
        &format!("{base}/?token={ADMIN_TOKEN}&x=1"),
        None,
        &[],
    );
    assert_eq!(status, 303, "{head}");
    assert!(head.contains("location: /?x=1"), "{head}");
    let cookie_line = head.lines().find(|l| l.starts_with("set-cookie:")).unwrap();
    assert!(
        cookie_line.contains(&format!("sitar_token={ADMIN_TOKEN}")),
        "{cookie_line}"
    );
    assert!(cookie_line.contains("HttpOnly"), "{cookie_line}");
    assert!(cookie_line.contains("SameSite=Strict"), "{cookie_line}");
    let cookie = format!("other=1; sitar_token={ADMIN_TOKEN}");
    let (status, head, page) = call("GET", &format!("{base}/?x=1"), None, &[("cookie", &cookie)]);
    assert_eq!(status, 200, "{page}");
    assert!(head.contains("content-type: text/html"), "{head}");
    // A wrong token in the address is a 401, not a cookie.
    let (status, head, _) = call("GET", &format!("{base}/?token=sitar_wrong"), None, &[]);
    assert_eq!(status, 401);
    assert!(!head.contains("set-cookie"), "{head}");
    // JSON routes take no `?token=`.
    let (status, _, _) = call(
        "GET",
        &format!("{base}/v1/devices?token={ADMIN_TOKEN}"),
        None,
        &[],
    );
    assert_eq!(status, 401);
}

#[test]
fn legacy_routes_take_the_token_in_the_address() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 20.0, 1));
    let base = server.url();
    let (status, _, body) = call("GET", &format!("{base}/results.csv"), None, &[]);
    assert_eq!(status, 401, "{body}");
    let (status, _, body) = call(
        "GET",
        &format!("{base}/results.csv?token={APP_TOKEN}"),
        None,
        &[],
    );
    assert_eq!(
        status, 404,
        "no finished session yet, but authenticated: {body}"
    );
    let (ct, body) = multipart("timestamps", "t.txt", b"0 1\n");
    let post = |url: &str| {
        bare_agent()
            .post(url)
            .header("content-type", &ct)
            .send(&body[..])
            .unwrap()
            .status()
            .as_u16()
    };
    assert_eq!(post(&format!("{base}/timestamps")), 401);
    // Authenticated: "no recording uploaded yet" (of this token).
    assert_eq!(post(&format!("{base}/timestamps?token={APP_TOKEN}")), 409);
}

#[test]
fn a_share_link_opens_one_report_until_revoked() {
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 20.0, 1));
    let base = server.url();
    let app = client_with(&server, APP_TOKEN);
    let id = app
        .create_session(&NewSession {
            playback: "sim".into(),
            ..upload_session()
        })
        .unwrap();
    let rec = sim_recording(dir.path(), "walk.rec", 3.0, 7);
    app.upload_recording(&id, &rec, &mut |_, _| {}).unwrap();
    assert_eq!(wait_done(&app, &id).state, SessionState::Done);
    // Another app cannot share it; its owner can.
    let share = format!("{base}/v1/sessions/{id}/share");
    let (status, _, _) = call("POST", &share, Some(&bearer(APP2_TOKEN)), &[]);
    assert_eq!(status, 404);
    let (status, _, body) = call("POST", &share, Some(&bearer(APP_TOKEN)), &[]);
    assert_eq!(status, 201, "{body}");
    let url = serde_json::from_str::<serde_json::Value>(&body).unwrap()["url"]
        .as_str()
        .unwrap()
        .to_owned();
    assert!(url.starts_with(&format!("{base}/share/sitar_")), "{url}");
    let (status, head, page) = call("GET", &url, None, &[]);
    assert_eq!(status, 200, "{page}");
    assert!(head.contains("content-type: text/html"), "{head}");
    assert!(page.contains(&id), "the report of the session");
    // The link opens nothing else.
    let (status, _, _) = call("GET", &format!("{base}/v1/sessions/{id}/report"), None, &[]);
    assert_eq!(status, 401);
    let (status, _, _) = call("GET", &format!("{url}x"), None, &[]);
    assert_eq!(status, 404);
    let (status, _, body) = call("DELETE", &share, Some(&bearer(APP_TOKEN)), &[]);
    assert_eq!(status, 200, "{body}");
    assert!(body.contains("\"revoked\":1"), "{body}");
    let (status, _, _) = call("GET", &url, None, &[]);
    assert_eq!(status, 404);
}

#[test]
fn without_authentication_only_loopback_is_served() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = sim_config(&dir.path().join("data"), 20.0, 1);
    config.insecure_no_auth = true;
    let err = sitar_server::Server::spawn(config.clone(), "0.0.0.0:0".parse().unwrap())
        .err()
        .expect("refused on every interface");
    assert!(err.to_string().contains("loopback"), "{err}");
    let server = sitar_server::Server::spawn(config, "127.0.0.1:0".parse().unwrap()).unwrap();
    let (status, _, body) = call("GET", &format!("{}/v1/sessions", server.url()), None, &[]);
    assert_eq!(status, 200, "{body}");
    assert!(
        !dir.path()
            .join("data")
            .join(sitar_server::ADMIN_TOKEN_FILE)
            .exists()
    );
}

/// Collects the server's log lines of this test binary.
struct Collect(Mutex<Vec<String>>);

impl log::Log for Collect {
    fn enabled(&self, _: &log::Metadata<'_>) -> bool {
        true
    }
    fn log(&self, record: &log::Record<'_>) {
        self.0.lock().unwrap().push(record.args().to_string());
    }
    fn flush(&self) {}
}

static LOG: Collect = Collect(Mutex::new(Vec::new()));

#[test]
fn request_log_lines_name_the_token_never_show_it() {
    let _ = log::set_logger(&LOG);
    log::set_max_level(log::LevelFilter::Debug);
    let dir = tempfile::tempdir().unwrap();
    let server = start(sim_config(&dir.path().join("data"), 20.0, 1));
    let base = server.url();
    let (status, _, _) = call(
        "GET",
        &format!("{base}/v1/devices"),
        Some(&bearer(APP_TOKEN)),
        &[],
    );
    assert_eq!(status, 403);
    let (status, _, _) = call("GET", &format!("{base}/?token={ADMIN_TOKEN}"), None, &[]);
    assert_eq!(status, 303);
    server.stop();
    let lines = LOG.0.lock().unwrap().clone();
    assert!(
        lines
            .iter()
            .any(|l| l.contains("GET /v1/devices [test-app] → 403")),
        "{lines:#?}"
    );
    for token in [ADMIN_TOKEN, APP_TOKEN] {
        assert!(!lines.iter().any(|l| l.contains(token)), "{lines:#?}");
    }
}
