//! The playback hosts' side of the `/v1/worker/…` routes (`sitar worker`): register, heartbeat,
//! lease a trial, fetch its recording, upload the trial or report the phone's failure. Same
//! client as the phones' (timeouts, retries, a pinned certificate); a worker token.

use std::io::Write;
use std::path::Path;

use serde::Deserialize;
use serde_json::json;

use crate::client::{Payload, server_error, transport_error};
use crate::{Client, Error};

/// A registered host: its id and the server's lease timing.
#[derive(Debug, Clone, Deserialize, PartialEq)]
pub struct WorkerHost {
    /// Server-made id (`h` + 16 hex digits).
    pub host: String,
    /// Seconds a lease lasts past the last heartbeat.
    pub lease_s: f64,
    /// How often to heartbeat (a quarter of the lease).
    pub heartbeat_s: f64,
}

/// The server's answer to a heartbeat.
#[derive(Debug, Clone, Deserialize, PartialEq)]
pub struct WorkerHeartbeat {
    /// Leases the host holds that are no longer its: stop those phones, drop their trials.
    pub abort: Vec<String>,
    /// This host's phones taken out of service (2 failures in a row).
    pub out_of_service: Vec<String>,
}

/// A trial leased to one phone.
#[derive(Debug, Clone, Deserialize, PartialEq)]
pub struct WorkerLease {
    /// The lease's id (`l` + 16 hex digits).
    pub lease: String,
    /// The session the trial belongs to.
    pub session: String,
    /// The trial's playback index (a sim trial's seed).
    pub index: u32,
    /// The phone it is leased to.
    pub phone: String,
    /// SHA-256 (hex) of the session's recording: the name to cache it under.
    pub recording_sha256: String,
}

fn parse<T: for<'de> Deserialize<'de>>(text: &str, what: &str) -> Result<T, Error> {
    serde_json::from_str(text)
        .map_err(|e| Error::InvalidResponse(format!("{what}: {e}: {text:.200}")))
}

/// A path segment the server made (host and lease ids): letters and digits only.
fn segment(id: &str) -> Result<&str, Error> {
    if !id.is_empty() && id.len() <= 64 && id.bytes().all(|b| b.is_ascii_alphanumeric()) {
        Ok(id)
    } else {
        Err(Error::InvalidArgument(format!(
            "{id:.64?} is not a server-made id"
        )))
    }
}

impl Client {
    /// `POST /v1/worker/hosts`: registers host `name` playing `playback` (`sim` or `adb`)
    /// with `phones` (a host of the same name registered before keeps its id).
    pub fn worker_register(
        &self,
        name: &str,
        playback: &str,
        phones: &[String],
    ) -> Result<WorkerHost, Error> {
        let body = json!({"name": name, "playback": playback, "phones": phones}).to_string();
        let text = self.request("POST", "/v1/worker/hosts", Payload::Json(body), None)?;
        parse(&text, "POST /v1/worker/hosts")
    }

    /// `POST /v1/worker/hosts/{host}/heartbeat` with the phones present and the leases held.
    pub fn worker_heartbeat(
        &self,
        host: &str,
        phones: &[String],
        leases: &[String],
    ) -> Result<WorkerHeartbeat, Error> {
        let body = json!({"phones": phones, "leases": leases}).to_string();
        let path = format!("/v1/worker/hosts/{}/heartbeat", segment(host)?);
        let text = self.request("POST", &path, Payload::Json(body), None)?;
        parse(&text, "heartbeat")
    }

    /// `POST /v1/worker/hosts/{host}/leases`: the next trial for `phone`, waiting up to
    /// `wait_s` seconds (the server's cap: 20) for one; `None` when nothing came.
    pub fn worker_lease(
        &self,
        host: &str,
        phone: &str,
        wait_s: f64,
    ) -> Result<Option<WorkerLease>, Error> {
        let body = json!({"phone": phone, "wait_s": wait_s}).to_string();
        let path = format!("/v1/worker/hosts/{}/leases", segment(host)?);
        let text = self.request("POST", &path, Payload::Json(body), None)?;
        if text.trim().is_empty() {
            return Ok(None);
        }
        parse(&text, "lease").map(Some)
    }

    /// `GET …/leases/{lease}/recording` into the file `dest` (created or truncated); the
    /// bytes written.
    pub fn worker_recording(&self, host: &str, lease: &str, dest: &Path) -> Result<u64, Error> {
        let url = format!(
            "{}/v1/worker/hosts/{}/leases/{}/recording",
            self.base_url(),
            segment(host)?,
            segment(lease)?
        );
        let (agent, _) = self.agents()?;
        let mut response = agent
            .get(&url)
            .call()
            .map_err(|e| transport_error(&url, e))?;
        let status = response.status().as_u16();
        if status >= 400 {
            let text = response
                .body_mut()
                .with_config()
                .limit(64 << 10)
                .read_to_string()
                .unwrap_or_default();
            return Err(server_error(status, &text));
        }
        let io = |source| Error::Io {
            path: dest.to_path_buf(),
            source,
        };
        let mut file = std::fs::File::create(dest).map_err(io)?;
        let mut reader = response.body_mut().with_config().limit(u64::MAX).reader();
        let copied = std::io::copy(&mut reader, &mut file).map_err(|e| Error::Network {
            url: url.clone(),
            attempts: 1,
            message: e.to_string(),
        })?;
        file.flush().map_err(io)?;
        Ok(copied)
    }

    /// `PUT …/leases/{lease}/trial`: the finished trial (TUM text). A 409 means the lease was
    /// no longer live: the trial is not taken (it is played, or was, elsewhere).
    pub fn worker_upload_trial(&self, host: &str, lease: &str, tum: &str) -> Result<(), Error> {
        let path = format!(
            "/v1/worker/hosts/{}/leases/{}/trial",
            segment(host)?,
            segment(lease)?
        );
        self.request("PUT", &path, Payload::Text(tum), None)
            .map(|_| ())
    }

    /// `POST …/leases/{lease}/failure`: the phone could not play the trial, for `error`.
    pub fn worker_failure(&self, host: &str, lease: &str, error: &str) -> Result<(), Error> {
        let path = format!(
            "/v1/worker/hosts/{}/leases/{}/failure",
            segment(host)?,
            segment(lease)?
        );
        let body = json!({"error": error}).to_string();
        self.request("POST", &path, Payload::Json(body), None)
            .map(|_| ())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_server_made_ids_become_path_segments() {
        assert_eq!(segment("h0123abcd").unwrap(), "h0123abcd");
        for bad in ["", "../x", "h/1", "h 1", "h?x"] {
            assert!(segment(bad).is_err(), "{bad}");
        }
    }
}
