//! The TLS listener's connection cap, over loopback against the real server: two idle
//! `openssl s_client` connections hold the slots, `curl` gets the JSON 503 over TLS, and the
//! slots come back.

use std::time::{Duration, Instant};

use sitar_tests::*;

fn installed(tool: &str) -> bool {
    std::process::Command::new(tool)
        .arg("version")
        .output()
        .is_ok()
        || std::process::Command::new(tool)
            .arg("--version")
            .output()
            .is_ok()
}

#[test]
fn the_tls_listener_has_the_same_cap_and_answers_503_over_tls() {
    use std::process::{Command, Stdio};
    if !installed("openssl") || !installed("curl") {
        eprintln!("SKIPPED the_tls_listener_has_the_same_cap: openssl or curl missing");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let mut config = sim_config(&data, 10.0, 1);
    config.max_connections = 2;
    config.header_read_timeout = Duration::from_secs(30);
    config.tls = Some(sitar_server::TlsConfig {
        names: vec!["127.0.0.1".into()],
        ..sitar_server::TlsConfig::default()
    });
    let server = start(config);
    let cert = data.join("tls").join("cert.pem");
    // Two handshaken, idle TLS connections (stdin kept open) hold both slots.
    let holder = || {
        Command::new("openssl")
            .args(["s_client", "-quiet", "-connect"])
            .arg(server.addr().to_string())
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap()
    };
    let mut holders: Vec<_> = (0..2).map(|_| holder()).collect();
    let curl = || {
        let out = Command::new("curl")
            .args(["-sS", "--max-time", "10", "-w", " %{http_code}", "--cacert"])
            .arg(&cert)
            .arg(format!("{}/healthz", server.url()))
            .output()
            .unwrap();
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let deadline = Instant::now() + Duration::from_secs(10);
    let refused = loop {
        // A curl that raced a holder to a slot got it, and the holder its 503 (then exited):
        // start that holder again before asking.
        for running in &mut holders {
            if running.try_wait().unwrap().is_some() {
                *running = holder();
            }
        }
        std::thread::sleep(Duration::from_millis(200));
        let answer = curl();
        if answer.ends_with(" 503") {
            break answer;
        }
        assert!(Instant::now() < deadline, "never refused: {answer}");
        std::thread::sleep(Duration::from_millis(100));
    };
    assert!(refused.contains("\"code\":\"busy\""), "{refused}");
    for holder in &mut holders {
        let _ = holder.kill();
        let _ = holder.wait();
    }
    let deadline = Instant::now() + Duration::from_secs(10);
    while !curl().ends_with(" 200") {
        assert!(Instant::now() < deadline, "the slots never came back");
        std::thread::sleep(Duration::from_millis(100));
    }
}
