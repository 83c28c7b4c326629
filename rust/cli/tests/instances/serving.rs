//! A `sitar serve --playback sim` for the instance tests, and requests through curl.

use std::path::Path;
use std::process::Command;

use crate::support::process::Serving;

/// Starts `sitar serve --playback sim` on a free port with `extra` arguments.
pub fn start(data: &Path, extra: &[&str]) -> Serving {
    let mut args = vec!["--playback", "sim"];
    args.extend_from_slice(extra);
    Serving::start(data, &args)
}

/// `METHOD url/path` with the bearer `token` through curl: (HTTP status, body).
pub fn request(method: &str, url: &str, path: &str, token: &str) -> (String, String) {
    let out = Command::new("curl")
        .args(["-s", "-X", method, "-w", "\n%{http_code}"])
        .args(["-H", &format!("Authorization: Bearer {token}")])
        .arg(format!("{url}{path}"))
        .output()
        .expect("curl");
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let (body, status) = text.rsplit_once('\n').unwrap_or(("", &text));
    (status.trim().to_string(), body.to_string())
}
