//! Per-token limits survive a restart: sessions created in the hour and bytes uploaded in
//! the day are counted in the server's database, so a server stopped and started again on the
//! same data directory still answers 429 (with `Retry-After`) to the token that used them up,
//! and not to another token.

use sitar_server::Limits;
use sitar_tests::*;

/// (status, Retry-After, body) of a request with `token`.
fn send(base: &str, path: &str, token: &str, content_type: &str, body: &str) -> (u16, u64, String) {
    let mut response = bare_agent()
        .post(&format!("{base}{path}"))
        .header("authorization", &format!("Bearer {token}"))
        .header("content-type", content_type)
        .send(body)
        .unwrap();
    let retry = response
        .headers()
        .get("retry-after")
        .and_then(|v| v.to_str().ok()?.parse().ok())
        .unwrap_or(0);
    let body = response.body_mut().read_to_string().unwrap();
    (response.status().as_u16(), retry, body)
}

fn create(base: &str, token: &str) -> (u16, u64, String) {
    let json = r#"{"playback":"upload","trials":2}"#;
    send(base, "/v1/sessions", token, "application/json", json)
}

/// A TUM trajectory of `n` poses (about 45 bytes each).
fn trajectory(n: usize) -> String {
    (0..n)
        .map(|i| {
            format!(
                "{:.6} {:.6} 0 1.5 0 0 0 1\n",
                i as f64 / 30.0,
                i as f64 * 0.01
            )
        })
        .collect()
}

fn server(data: &std::path::Path) -> sitar_server::ServerHandle {
    let mut config = sim_config(data, 20.0, 1);
    config.limits = Limits {
        sessions_per_hour: 2,
        upload_bytes_per_day: 1_000,
        concurrent_uploads: 4,
    };
    start(config)
}

#[test]
fn a_restart_keeps_the_sessions_per_hour_and_the_bytes_per_day() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let first_run = server(&data);
    let base = first_run.url();
    let (status, _, body) = create(&base, APP_TOKEN);
    assert_eq!(status, 201, "{body}");
    let id = serde_json::from_str::<serde_json::Value>(&body).unwrap()["id"]
        .as_str()
        .unwrap()
        .to_owned();
    assert_eq!(create(&base, APP_TOKEN).0, 201);
    assert_eq!(create(&base, APP_TOKEN).0, 429);
    // One upload over the day's 1000 bytes: it started under the limit, so it is taken.
    let text = trajectory(40);
    assert!(text.len() > 1_000, "{}", text.len());
    let trials = format!("/v1/sessions/{id}/trials");
    let (status, _, body) = send(&base, &trials, APP_TOKEN, "text/plain", &text);
    assert_eq!(status, 201, "{body}");
    let (status, _, body) = send(&base, &trials, APP_TOKEN, "text/plain", &text);
    assert_eq!(status, 429, "{body}");
    first_run.stop();

    // The same data directory, a new process state: both limits still apply.
    let second_run = server(&data);
    let base = second_run.url();
    let (status, retry, body) = create(&base, APP_TOKEN);
    assert_eq!(status, 429, "sessions per hour after a restart: {body}");
    assert!(body.contains("too_many_requests"), "{body}");
    assert!((3_500..=3_600).contains(&retry), "Retry-After {retry}");
    let (status, retry, body) = send(&base, &trials, APP_TOKEN, "text/plain", &text);
    assert_eq!(status, 429, "bytes per day after a restart: {body}");
    assert!(body.contains(&format!("{} bytes", text.len())), "{body}");
    assert!((1..=86_400).contains(&retry), "Retry-After {retry}");
    // Another token's counters are its own.
    let (status, _, body) = create(&base, APP2_TOKEN);
    assert_eq!(status, 201, "{body}");
    second_run.stop();
}
