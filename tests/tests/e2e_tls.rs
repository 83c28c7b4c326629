//! HTTPS over loopback against the real server: the self-signed certificate's fingerprint is
//! the one openssl computes, a client pinned to it works, one pinned to another fails with
//! the clear mismatch error, plain HTTP to the TLS port fails cleanly, curl verifies it.

use std::process::Command;

use sitar_server::TlsConfig;
use sitar_tests::*;

fn tls_server(data: &std::path::Path) -> sitar_server::ServerHandle {
    let mut config = sim_config(data, 20.0, 1);
    config.tls = Some(TlsConfig {
        names: vec!["127.0.0.1".into(), "localhost".into()],
        ..TlsConfig::default()
    });
    start(config)
}

fn installed(tool: &str) -> bool {
    Command::new(tool).arg("version").output().is_ok()
        || Command::new(tool).arg("--version").output().is_ok()
}

#[test]
fn a_pinned_client_talks_https_and_a_wrong_pin_is_refused_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let server = tls_server(&data);
    assert!(
        server.url().starts_with("https://127.0.0.1:"),
        "{}",
        server.url()
    );
    let fingerprint = server.tls_fingerprint().unwrap().to_owned();
    assert_eq!(fingerprint.len(), 95, "{fingerprint}");

    let pinned = sitar_client::Client::new(&server.url())
        .unwrap()
        .with_server_token(APP_TOKEN)
        .unwrap()
        .with_server_cert_sha256(&fingerprint)
        .unwrap();
    pinned.health().unwrap();
    let id = upload_session(&pinned, 2);
    assert_eq!(pinned.status(&id).unwrap().id, id);

    // Another fingerprint: refused before anything is sent, naming both, not retried.
    let other = "00:".repeat(31) + "01";
    let wrong = sitar_client::Client::new(&server.url())
        .unwrap()
        .with_server_token(APP_TOKEN)
        .unwrap()
        .with_server_cert_sha256(&other)
        .unwrap();
    let err = wrong.health().unwrap_err();
    assert!(
        matches!(err, sitar_client::Error::CertificateMismatch { .. }),
        "{err:?}"
    );
    let message = err.to_string();
    assert!(
        message.contains(&fingerprint) && message.contains(&other),
        "{message}"
    );
    // Without a pin, the self-signed certificate is not trusted either.
    let unpinned = sitar_client::Client::new(&server.url())
        .unwrap()
        .with_retries(0, std::time::Duration::from_millis(1));
    assert!(matches!(
        unpinned.health().unwrap_err(),
        sitar_client::Error::Network { .. }
    ));
    // A pin needs an https:// URL: no plain-HTTP fallback to configure.
    let plain = sitar_client::Client::new(&server.url().replace("https://", "http://")).unwrap();
    let err = plain.with_server_cert_sha256(&fingerprint).unwrap_err();
    assert!(err.to_string().contains("https://"), "{err}");

    // Plain HTTP to the TLS port: a clear 400, then the connection closes.
    let (status, _, body) = raw(
        "GET",
        &format!("http://{}/healthz", server.addr()),
        None,
        b"",
        &[],
    );
    assert_eq!(status, 400, "{body}");
    assert!(body.contains("this port speaks HTTPS"), "{body}");
}

#[test]
fn openssl_and_curl_agree_with_the_printed_fingerprint() {
    if !installed("openssl") || !installed("curl") {
        eprintln!(
            "SKIPPED openssl_and_curl_agree_with_the_printed_fingerprint: openssl or curl missing"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    let server = tls_server(&data);
    let cert = data.join("tls").join("cert.pem");
    let out = Command::new("openssl")
        .args(["x509", "-noout", "-fingerprint", "-sha256", "-in"])
        .arg(&cert)
        .output()
        .unwrap();
    let printed = String::from_utf8(out.stdout).unwrap();
    let from_openssl = printed.trim().rsplit('=').next().unwrap();
    assert_eq!(from_openssl, server.tls_fingerprint().unwrap(), "{printed}");
    // The server's certificate is the file's, verified by curl for 127.0.0.1.
    let base = server.url();
    let curl = |args: &[&str]| {
        let out = Command::new("curl")
            .args(["-sS", "--max-time", "10", "--cacert"])
            .arg(&cert)
            .args(args)
            .output()
            .unwrap();
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let (ok, body, err) = curl(&[&format!("{base}/healthz")]);
    assert!(ok && body.contains("ok"), "{body} {err}");
    let (ok, body, err) = curl(&[
        "-H",
        &format!("Authorization: Bearer {ADMIN_TOKEN}"),
        &format!("{base}/v1/sessions"),
    ]);
    assert!(ok && body.contains("sessions"), "{body} {err}");
    // Over TLS the page cookie is Secure.
    let (ok, head, err) = curl(&[
        "-D",
        "-",
        "-o",
        "/dev/null",
        &format!("{base}/?token={ADMIN_TOKEN}"),
    ]);
    assert!(ok, "{err}");
    let cookie = head
        .lines()
        .find(|l| l.to_ascii_lowercase().starts_with("set-cookie"))
        .unwrap();
    assert!(cookie.contains("; Secure"), "{cookie}");
    // Plain HTTP to the TLS port with curl: the 400 that says so.
    let (_, body, _) = curl(&[&format!("http://{}/healthz", server.addr())]);
    assert!(body.contains("this port speaks HTTPS"), "{body}");
    // The overview shows the fingerprint.
    let (ok, page, err) = curl(&[
        "-H",
        &format!("Authorization: Bearer {ADMIN_TOKEN}"),
        &format!("{base}/"),
    ]);
    assert!(
        ok && page.contains(server.tls_fingerprint().unwrap()),
        "{err}"
    );
}
