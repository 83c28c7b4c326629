use std::fs::File;
use std::hash::{BuildHasher, Hasher};
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use ureq::Agent;

use crate::{Error, NewSession, SessionFrame, SessionOptions, SessionStatus};

/// Header carrying the client-made key that makes `POST` requests safe to retry.
pub const IDEMPOTENCY_HEADER: &str = "Idempotency-Key";

/// Header in which the server tells how many bytes of an interrupted recording upload it kept.
pub const UPLOAD_OFFSET_HEADER: &str = "Upload-Offset";

/// Blocking client of the SiTAR backend.
///
/// Every call has a timeout; connection errors, timeouts and 5xx answers are
/// retried with exponential backoff. `POST`s carry an idempotency key that is
/// the same on every retry, so a retried create or trial upload never
/// duplicates anything on the server.
#[derive(Debug, Clone)]
pub struct Client {
    base: String,
    agent: Agent,
    upload_agent: Agent,
    timeout: Duration,
    retries: u32,
    backoff: Duration,
    /// `Authorization: Bearer …` on every request, when set.
    server_token: Option<String>,
    /// The pinned certificate's SHA-256 (`server_cert_sha256`), when set.
    cert_pin: Option<crate::pin::Fingerprint>,
    /// With a pin: the agents that trust exactly the pinned certificate, made on the first
    /// call (shared by the clones of this client).
    pinned: Arc<Mutex<Option<(Agent, Agent)>>>,
}

pub(crate) enum Payload<'a> {
    Empty,
    Json(String),
    Text(&'a str),
    /// A small body held in memory, with its content type.
    Bytes(&'a [u8], &'static str),
    /// A file sent from byte `offset` on (a resumed upload when `offset > 0`).
    File {
        path: &'a Path,
        offset: u64,
        progress: &'a mut dyn FnMut(u64, u64),
        cancel: &'a AtomicBool,
    },
}

impl Client {
    /// A client of the server at `base_url` (e.g. `http://127.0.0.1:8000`), with a
    /// 30 s timeout per call (uploads: per read/write), 3 retries and 200 ms initial backoff.
    pub fn new(base_url: &str) -> Result<Client, Error> {
        let base = base_url.trim_end_matches('/').to_string();
        let rest = base
            .strip_prefix("http://")
            .or_else(|| base.strip_prefix("https://"))
            .ok_or_else(|| Error::InvalidUrl(base_url.to_string()))?;
        if rest.is_empty() || rest.contains(char::is_whitespace) {
            return Err(Error::InvalidUrl(base_url.to_string()));
        }
        let timeout = Duration::from_secs(30);
        Ok(Client {
            agent: make_agent(timeout, false, None, None),
            upload_agent: make_agent(timeout, true, None, None),
            base,
            timeout,
            retries: 3,
            backoff: Duration::from_millis(200),
            server_token: None,
            cert_pin: None,
            pinned: Arc::new(Mutex::new(None)),
        })
    }

    /// The same client with another timeout. Plain calls must finish within it;
    /// uploads may take longer but no single read or write may stall longer.
    pub fn with_timeout(mut self, timeout: Duration) -> Client {
        self.timeout = timeout;
        self.rebuild_agents();
        self
    }

    /// The same client sending `Authorization: Bearer TOKEN` with every request (a token from
    /// `sitar token create`; the server answers 401 without one). A token that could not be
    /// a header value is refused here, naming it.
    pub fn with_server_token(mut self, token: &str) -> Result<Client, Error> {
        let token = token.trim();
        if token.is_empty()
            || !token
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
        {
            return Err(Error::InvalidArgument(
                "server_token: expected the letters, digits, '_' and '-' of a sitar token".into(),
            ));
        }
        self.server_token = Some(token.to_owned());
        self.rebuild_agents();
        Ok(self)
    }

    /// The same client accepting only the TLS certificate whose SHA-256 fingerprint is
    /// `fingerprint` (`AB:CD:…` as `sitar serve --tls` and `openssl x509 -fingerprint -sha256`
    /// print it): for a self-signed certificate. The URL must be `https://`. A server showing
    /// another certificate fails every call with [`Error::CertificateMismatch`]; without a
    /// pin, an `https://` server needs a certificate the platform trusts (its verifier and
    /// system roots; on Android Mozilla's roots, bundled).
    pub fn with_server_cert_sha256(mut self, fingerprint: &str) -> Result<Client, Error> {
        if !self.base.starts_with("https://") {
            return Err(Error::InvalidArgument(format!(
                "server_cert_sha256 needs an https:// server URL, not {}",
                self.base
            )));
        }
        self.cert_pin = Some(crate::pin::parse_fingerprint(fingerprint)?);
        self.pinned = Arc::new(Mutex::new(None));
        Ok(self)
    }

    fn rebuild_agents(&mut self) {
        let token = self.server_token.as_deref();
        self.agent = make_agent(self.timeout, false, token, None);
        self.upload_agent = make_agent(self.timeout, true, token, None);
        self.pinned = Arc::new(Mutex::new(None));
    }

    /// (plain, upload) agents: with a pin, those trusting only the pinned certificate,
    /// fetched on first use.
    pub(crate) fn agents(&self) -> Result<(Agent, Agent), Error> {
        let Some(pin) = &self.cert_pin else {
            return Ok((self.agent.clone(), self.upload_agent.clone()));
        };
        let mut pinned = self.pinned.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(agents) = pinned.as_ref() {
            return Ok(agents.clone());
        }
        let cert = crate::pin::fetch_pinned(&self.base, pin, self.timeout)?;
        let token = self.server_token.as_deref();
        let agents = (
            make_agent(self.timeout, false, token, Some(&cert)),
            make_agent(self.timeout, true, token, Some(&cert)),
        );
        *pinned = Some(agents.clone());
        Ok(agents)
    }

    /// The same client with `retries` extra attempts and an initial `backoff`
    /// that doubles after every failed attempt.
    pub fn with_retries(mut self, retries: u32, backoff: Duration) -> Client {
        self.retries = retries;
        self.backoff = backoff;
        self
    }

    /// The server's base URL, without a trailing slash.
    pub fn base_url(&self) -> &str {
        &self.base
    }

    /// `GET /healthz`: Ok when the server answers.
    pub fn health(&self) -> Result<(), Error> {
        self.request("GET", "/healthz", Payload::Empty, None)
            .map(|_| ())
    }

    /// `POST /v1/sessions`: creates a session and returns its server-made id.
    pub fn create_session(&self, req: &NewSession) -> Result<String, Error> {
        self.create_session_with(req, &SessionOptions::default())
    }

    /// Like [`Client::create_session`], with the optional settings (adaptive stopping,
    /// window length, pose relation); the server answers 400 naming a bad one.
    pub fn create_session_with(
        &self,
        req: &NewSession,
        options: &SessionOptions,
    ) -> Result<String, Error> {
        self.create_session_in(req, options, &SessionFrame::default())
    }

    /// Like [`Client::create_session_with`], in `frame`: the phone's convention and the venue
    /// the session joins (sent only when set; the server answers 422 naming a venue the
    /// caller cannot see, 409 naming both conventions when the venue's sessions use another).
    pub fn create_session_in(
        &self,
        req: &NewSession,
        options: &SessionOptions,
        frame: &SessionFrame,
    ) -> Result<String, Error> {
        let mut body =
            serde_json::to_value(req).map_err(|e| Error::InvalidArgument(e.to_string()))?;
        if let Some(convention) = &frame.convention {
            body["convention"] = convention.as_str().into();
        }
        if let Some(venue) = &frame.venue {
            body["venue"] = venue.as_str().into();
        }
        if let Some(min) = options.adaptive_min_trials {
            body["adaptive_min_trials"] = min.into();
        }
        if let Some(k) = options.adaptive_k {
            body["adaptive_k"] = k.into();
        }
        if let Some(name) = &options.calibration {
            body["calibration"] = name.as_str().into();
        }
        let key = idempotency_key();
        let text = self.request(
            "POST",
            "/v1/sessions",
            Payload::Json(body.to_string()),
            Some(&key),
        )?;
        let value: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| Error::InvalidResponse(format!("create session: {e}: {text}")))?;
        value["id"]
            .as_str()
            .map(str::to_string)
            .ok_or_else(|| Error::InvalidResponse(format!("create session: no \"id\" in {text}")))
    }

    /// `PUT /v1/sessions/{id}/recording`: streams the file at `path` from disk
    /// (never whole in memory). `progress(sent, total)` is called as bytes go out.
    ///
    /// An upload cut off by a dropped connection resumes, on a retry or in a later call for
    /// the same file: the client asks the server how many bytes it kept (`HEAD`,
    /// `Upload-Offset`) and sends only the rest, with `Content-Range`. Its requests carry an
    /// `Idempotency-Key` made from the file's path, length and modification time, to which
    /// the server ties the kept bytes, so a resume never continues another file's bytes.
    /// When nothing was kept it sends the whole file (the `PUT` replaces, so that is safe).
    pub fn upload_recording(
        &self,
        id: &str,
        path: &Path,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<(), Error> {
        self.upload_recording_cancellable(id, path, progress, &AtomicBool::new(false))
    }

    /// [`Client::upload_recording`] that stops as soon as `cancel` is set, also in the
    /// middle of the transfer: the connection is dropped (the server keeps no partial
    /// file) and the call returns [`Error::Cancelled`] without retrying.
    pub fn upload_recording_cancellable(
        &self,
        id: &str,
        path: &Path,
        progress: &mut dyn FnMut(u64, u64),
        cancel: &AtomicBool,
    ) -> Result<(), Error> {
        let url = format!(
            "{}/v1/sessions/{}/recording",
            self.base,
            check_session_id(id)?
        );
        let meta = recording_file(path)?;
        let total = meta.len();
        // The server ties the bytes it keeps to this key, so a resume never continues another
        // file's bytes, and the same file uploaded again (after an app restart) resumes.
        let key = file_key(path, &meta);
        if cancel.load(Ordering::Acquire) {
            return Err(Error::Cancelled);
        }
        let mut delay = self.backoff;
        let mut attempt = 0;
        // Resume from what the server kept; anything unusable means from the start.
        let kept = |client: &Client| {
            client
                .kept_offset(&url, &key)
                .filter(|&n| n < total)
                .unwrap_or(0)
        };
        let mut offset = kept(self);
        loop {
            attempt += 1;
            if cancel.load(Ordering::Acquire) {
                return Err(Error::Cancelled);
            }
            let mut payload = Payload::File {
                path,
                offset,
                progress: &mut *progress,
                cancel,
            };
            let outcome = self.attempt("PUT", &url, &mut payload, Some(&key));
            // A 409 to a resume means the kept offset moved (or an earlier attempt is still
            // being received): ask again.
            let stale_offset =
                offset > 0 && matches!(outcome, Err(Error::Server { status: 409, .. }));
            if !(retryable(&outcome) || stale_offset) || attempt > self.retries {
                return outcome.map(|_| ()).map_err(|e| with_attempts(e, attempt));
            }
            std::thread::sleep(delay);
            delay = delay.saturating_mul(2);
            offset = kept(self);
        }
    }

    /// `HEAD` on a recording URL: the bytes of the interrupted upload with `key` that the
    /// server kept. `None` when the server does not say (an older server, or unreachable).
    fn kept_offset(&self, url: &str, key: &str) -> Option<u64> {
        let response = self
            .agents()
            .ok()?
            .0
            .head(url)
            .header(IDEMPOTENCY_HEADER, key)
            .call()
            .ok()?;
        if response.status().as_u16() != 200 {
            return None;
        }
        response
            .headers()
            .get(UPLOAD_OFFSET_HEADER)?
            .to_str()
            .ok()?
            .parse()
            .ok()
    }

    /// `POST /v1/sessions/{id}/trials`: one trial's TUM text (e.g. from an outside SLAM run).
    pub fn upload_trial(&self, id: &str, tum_text: &str) -> Result<(), Error> {
        let url = format!("/v1/sessions/{}/trials", check_session_id(id)?);
        let key = idempotency_key();
        self.request("POST", &url, Payload::Text(tum_text), Some(&key))
            .map(|_| ())
    }

    /// Sends a phone session folder's evidence (`subtrajectories.csv`, `evidence.csv`,
    /// `thumbnails/<k>.jpg`, sitar-core's formats) to session `id`: `PUT`s that each replace
    /// one small file, so a retry sends them again. Returns how many thumbnails were sent;
    /// `Ok(None)` when `dir` has no `evidence.csv` (nothing is sent).
    pub fn upload_evidence(&self, id: &str, dir: &Path) -> Result<Option<usize>, Error> {
        self.upload_evidence_files(id, dir, true)
    }

    /// [`Client::upload_evidence`]; `with_spans` false leaves out `subtrajectories.csv` (the
    /// upload job sends it with the phone's log, before the recording).
    pub(crate) fn upload_evidence_files(
        &self,
        id: &str,
        dir: &Path,
        with_spans: bool,
    ) -> Result<Option<usize>, Error> {
        let id = check_session_id(id)?;
        let read = |path: std::path::PathBuf| {
            std::fs::read(&path).map_err(|source| Error::Io { path, source })
        };
        let evidence = dir.join("evidence.csv");
        if !evidence.is_file() {
            return Ok(None);
        }
        let spans = dir.join("subtrajectories.csv");
        if with_spans && spans.is_file() {
            let body = read(spans)?;
            let url = format!("/v1/sessions/{id}/subtrajectories.csv");
            self.request("PUT", &url, Payload::Bytes(&body, "text/csv"), None)?;
        }
        let body = read(evidence)?;
        let url = format!("/v1/sessions/{id}/evidence.csv");
        self.request("PUT", &url, Payload::Bytes(&body, "text/csv"), None)?;
        // Only `<k>.jpg` with a numeric k: the names the phone writes.
        let mut thumbnails: Vec<u32> = std::fs::read_dir(dir.join("thumbnails"))
            .into_iter()
            .flatten()
            .flatten()
            .filter_map(|e| e.file_name().to_str()?.strip_suffix(".jpg")?.parse().ok())
            .collect();
        thumbnails.sort_unstable();
        for k in &thumbnails {
            let body = read(dir.join("thumbnails").join(format!("{k}.jpg")))?;
            let url = format!("/v1/sessions/{id}/subtrajectories/{k}/image.jpg");
            self.request("PUT", &url, Payload::Bytes(&body, "image/jpeg"), None)?;
        }
        Ok(Some(thumbnails.len()))
    }

    /// `GET /v1/sessions/{id}/subtrajectories`: the evidence joined with the latest results
    /// (JSON text).
    pub fn subtrajectories_json(&self, id: &str) -> Result<String, Error> {
        let url = format!("/v1/sessions/{}/subtrajectories", check_session_id(id)?);
        self.request("GET", &url, Payload::Empty, None)
    }

    /// `GET /v1/sessions/{id}/subtrajectories/{k}/image.jpg`: the thumbnail's bytes (at
    /// most 1 MiB are read).
    pub fn subtrajectory_image(&self, id: &str, k: u32) -> Result<Vec<u8>, Error> {
        let url = format!(
            "{}/v1/sessions/{}/subtrajectories/{k}/image.jpg",
            self.base,
            check_session_id(id)?
        );
        let (plain, _) = self.agents()?;
        let mut response = plain
            .get(&url)
            .call()
            .map_err(|e| transport_error(&url, e))?;
        let status = response.status().as_u16();
        let body = response
            .body_mut()
            .with_config()
            .limit(1 << 20)
            .read_to_vec()
            .map_err(|e| transport_error(&url, e))?;
        if status >= 400 {
            return Err(server_error(status, &String::from_utf8_lossy(&body)));
        }
        Ok(body)
    }

    /// `POST /v1/sessions/{id}/estimate`: asks for the estimate of the trials so far.
    pub fn start_estimate(&self, id: &str) -> Result<(), Error> {
        let url = format!("/v1/sessions/{}/estimate", check_session_id(id)?);
        let key = idempotency_key();
        self.request("POST", &url, Payload::Empty, Some(&key))
            .map(|_| ())
    }

    /// `DELETE /v1/sessions/{id}`: removes a session that no job works on (done, failed, or
    /// waiting for uploads) with its files. A session in flight is a 409 [`Error::Server`].
    pub fn delete_session(&self, id: &str) -> Result<(), Error> {
        let url = format!("/v1/sessions/{}", check_session_id(id)?);
        self.request("DELETE", &url, Payload::Empty, None)
            .map(|_| ())
    }

    /// `GET /v1/sessions/{id}`.
    pub fn status(&self, id: &str) -> Result<SessionStatus, Error> {
        let url = format!("/v1/sessions/{}", check_session_id(id)?);
        let text = self.request("GET", &url, Payload::Empty, None)?;
        serde_json::from_str(&text)
            .map_err(|e| Error::InvalidResponse(format!("status: {e}: {text}")))
    }

    /// Polls [`Client::status`] every `interval` until the session is done or
    /// failed, calling `on_status` with every answer. Gives up after `limit`.
    pub fn wait(
        &self,
        id: &str,
        interval: Duration,
        limit: Duration,
        on_status: &mut dyn FnMut(&SessionStatus),
    ) -> Result<SessionStatus, Error> {
        let started = Instant::now();
        loop {
            let status = self.status(id)?;
            on_status(&status);
            if status.state.is_finished() {
                return Ok(status);
            }
            if started.elapsed() >= limit {
                return Err(Error::Timeout {
                    url: format!("{}/v1/sessions/{id}", self.base),
                    attempts: 1,
                });
            }
            std::thread::sleep(interval);
        }
    }

    /// `GET /v1/sessions/{id}/results.csv` (legacy `start,error` form).
    pub fn results_csv(&self, id: &str) -> Result<String, Error> {
        let url = format!("/v1/sessions/{}/results.csv", check_session_id(id)?);
        self.request("GET", &url, Payload::Empty, None)
    }

    /// `GET /v1/sessions/{id}/results.json`.
    pub fn results_json(&self, id: &str) -> Result<String, Error> {
        let url = format!("/v1/sessions/{}/results.json", check_session_id(id)?);
        self.request("GET", &url, Payload::Empty, None)
    }

    /// `GET /v1/sessions/{id}/report`: the HTML report page.
    pub fn report_html(&self, id: &str) -> Result<String, Error> {
        let url = format!("/v1/sessions/{}/report", check_session_id(id)?);
        self.request("GET", &url, Payload::Empty, None)
    }

    /// `GET /v1/devices`: the playback devices as JSON text.
    pub fn devices_json(&self) -> Result<String, Error> {
        self.request("GET", "/v1/devices", Payload::Empty, None)
    }

    pub(crate) fn request(
        &self,
        method: &str,
        path: &str,
        mut payload: Payload<'_>,
        idempotency: Option<&str>,
    ) -> Result<String, Error> {
        let url = format!("{}{}", self.base, path);
        let mut delay = self.backoff;
        let mut attempt = 0;
        loop {
            attempt += 1;
            let outcome = self.attempt(method, &url, &mut payload, idempotency);
            if !retryable(&outcome) || attempt > self.retries {
                return outcome.map_err(|e| with_attempts(e, attempt));
            }
            std::thread::sleep(delay);
            delay = delay.saturating_mul(2);
        }
    }

    fn attempt(
        &self,
        method: &str,
        url: &str,
        payload: &mut Payload<'_>,
        idempotency: Option<&str>,
    ) -> Result<String, Error> {
        let (plain, upload) = self.agents()?;
        let agent = if matches!(payload, Payload::File { .. }) {
            &upload
        } else {
            &plain
        };
        let with_key = |b: ureq::RequestBuilder<ureq::typestate::WithBody>| match idempotency {
            Some(key) => b.header(IDEMPOTENCY_HEADER, key),
            None => b,
        };
        let result = match (method, payload) {
            ("GET", _) => agent.get(url).call(),
            ("DELETE", _) => agent.delete(url).call(),
            (m, Payload::Empty) => with_key(body_builder(agent, m, url)).send_empty(),
            (m, Payload::Json(text)) => with_key(body_builder(agent, m, url))
                .header("content-type", "application/json")
                .send(text.as_str()),
            (m, Payload::Text(text)) => with_key(body_builder(agent, m, url))
                .header("content-type", "text/plain; charset=utf-8")
                .send(*text),
            (m, Payload::Bytes(bytes, content_type)) => with_key(body_builder(agent, m, url))
                .header("content-type", *content_type)
                .send(*bytes),
            (
                m,
                Payload::File {
                    path,
                    offset,
                    progress,
                    cancel,
                },
            ) => {
                let path: &Path = path;
                let io = |source| Error::Io {
                    path: path.to_path_buf(),
                    source,
                };
                let mut file = File::open(path).map_err(io)?;
                let total = file.metadata().map_err(io)?.len();
                let offset = (*offset).min(total);
                file.seek(SeekFrom::Start(offset)).map_err(io)?;
                progress(offset, total);
                let mut reader = ProgressReader {
                    inner: file,
                    sent: offset,
                    reported: offset,
                    total,
                    progress: &mut **progress,
                    cancel,
                };
                let request = with_key(body_builder(agent, m, url))
                    .header("content-type", "application/octet-stream")
                    .header("content-length", (total - offset).to_string());
                let request = if offset > 0 {
                    let last = total - 1;
                    request.header("content-range", format!("bytes {offset}-{last}/{total}"))
                } else {
                    request
                };
                let sent = request.send(ureq::SendBody::from_reader(&mut reader));
                if cancel.load(Ordering::Acquire) {
                    return Err(Error::Cancelled);
                }
                sent
            }
        };
        let mut response = result.map_err(|e| transport_error(url, e))?;
        let status = response.status().as_u16();
        let text = response
            .body_mut()
            .with_config()
            .limit(1 << 30)
            .read_to_string()
            .map_err(|e| transport_error(url, e))?;
        if status >= 400 {
            return Err(server_error(status, &text));
        }
        Ok(text)
    }
}

/// Connection errors, timeouts and 5xx answers are worth another attempt.
/// The metadata of a recording that can be read: a regular file that opens. Anything else
/// (missing, a directory, unreadable) is a local [`Error::Io`], never retried as a network error.
pub(crate) fn recording_file(path: &Path) -> Result<std::fs::Metadata, Error> {
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file",
        )));
    }
    File::open(path).map_err(io)?;
    Ok(meta)
}

fn retryable<T>(outcome: &Result<T, Error>) -> bool {
    match outcome {
        Ok(_) => false,
        Err(Error::Server { status, .. }) => *status >= 500,
        Err(Error::Network { .. } | Error::Timeout { .. }) => true,
        Err(_) => false,
    }
}

/// The error of the last attempt, saying how many were made.
fn with_attempts(e: Error, attempts: u32) -> Error {
    match e {
        Error::Network { url, message, .. } => Error::Network {
            url,
            attempts,
            message,
        },
        Error::Timeout { url, .. } => Error::Timeout { url, attempts },
        other => other,
    }
}

/// Puts `Authorization: Bearer TOKEN` on every request of an agent.
struct BearerAuth(ureq::http::HeaderValue);

impl ureq::middleware::Middleware for BearerAuth {
    fn handle(
        &self,
        mut request: ureq::http::Request<ureq::SendBody<'_>>,
        next: ureq::middleware::MiddlewareNext<'_>,
    ) -> Result<ureq::http::Response<ureq::Body>, ureq::Error> {
        request
            .headers_mut()
            .insert(ureq::http::header::AUTHORIZATION, self.0.clone());
        next.handle(request)
    }
}

/// What an unpinned `https://` URL is checked against: the platform's verifier (the system's
/// roots and policy; on Linux the system bundle, or `SSL_CERT_FILE` / `SSL_CERT_DIR` when
/// set), or on Android before `Sitar.init(context)` the bundled Mozilla roots
/// ([`crate::platform_tls`]).
fn platform_roots() -> ureq::tls::RootCerts {
    match crate::platform_tls::current_roots() {
        crate::platform_tls::Roots::PlatformVerifier => ureq::tls::RootCerts::PlatformVerifier,
        crate::platform_tls::Roots::Bundled => ureq::tls::RootCerts::WebPki,
    }
}

fn make_agent(
    timeout: Duration,
    streaming: bool,
    token: Option<&str>,
    only_root: Option<&rustls::pki_types::CertificateDer<'static>>,
) -> Agent {
    let mut builder = Agent::config_builder()
        .http_status_as_error(false)
        .timeout_connect(Some(timeout.min(Duration::from_secs(10))));
    if let Some(value) =
        token.and_then(|t| ureq::http::HeaderValue::from_str(&format!("Bearer {t}")).ok())
    {
        let mut value = value;
        value.set_sensitive(true);
        builder = builder.middleware(BearerAuth(value));
    }
    let roots = match only_root {
        Some(cert) => {
            ureq::tls::RootCerts::new_with_certs(&[
                ureq::tls::Certificate::from_der(cert.as_ref()).to_owned()
            ])
        }
        None => platform_roots(),
    };
    builder = builder.tls_config(ureq::tls::TlsConfig::builder().root_certs(roots).build());
    let builder = if streaming {
        // Bigger writes: fewer syscalls and server wake-ups per GiB uploaded.
        builder
            .output_buffer_size(1 << 20)
            .timeout_per_read(Some(timeout))
            .timeout_per_write(Some(timeout))
    } else {
        builder.timeout_global(Some(timeout))
    };
    builder.build().into()
}

fn body_builder(
    agent: &Agent,
    method: &str,
    url: &str,
) -> ureq::RequestBuilder<ureq::typestate::WithBody> {
    if method == "PUT" {
        agent.put(url)
    } else {
        agent.post(url)
    }
}

pub(crate) fn transport_error(url: &str, e: ureq::Error) -> Error {
    match e {
        ureq::Error::Timeout(_) => Error::Timeout {
            url: url.to_string(),
            attempts: 1,
        },
        ureq::Error::Io(io) if io.kind() == std::io::ErrorKind::TimedOut => Error::Timeout {
            url: url.to_string(),
            attempts: 1,
        },
        ureq::Error::BadUri(u) => Error::InvalidUrl(u),
        other => Error::Network {
            url: url.to_string(),
            attempts: 1,
            message: other.to_string(),
        },
    }
}

pub(crate) fn server_error(status: u16, body: &str) -> Error {
    let parsed: Option<serde_json::Value> = serde_json::from_str(body).ok();
    let field = |name: &str| {
        parsed
            .as_ref()
            .and_then(|v| v["error"][name].as_str())
            .map(str::to_string)
    };
    Error::Server {
        status,
        code: field("code").unwrap_or_else(|| "http".to_string()),
        message: field("message").unwrap_or_else(|| body.chars().take(200).collect()),
    }
}

/// Checks that `id` has the shape of a server-made session id (`[A-Za-z0-9_-]`, 1 to 64
/// bytes); anything else could change a URL's path. Every call that takes an id checks it.
pub fn check_session_id(id: &str) -> Result<&str, Error> {
    if !id.is_empty()
        && id.len() <= 64
        && id
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_')
    {
        Ok(id)
    } else {
        Err(Error::InvalidArgument(format!(
            "session id {id:?} is not a server-made id"
        )))
    }
}

/// The key of a recording upload: the file's path, length and modification time, so the
/// same file gets the same key in every process (FNV-1a: stable across runs and Rust
/// versions) and a rewritten file gets another. Random when the file system keeps no time.
fn file_key(path: &Path, meta: &std::fs::Metadata) -> String {
    let Ok(modified) = meta.modified() else {
        return idempotency_key();
    };
    let mtime_ns = modified
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for &byte in canonical.as_os_str().as_encoded_bytes() {
        hash = (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
    }
    format!("recording-{hash:016x}-{}-{mtime_ns}", meta.len())
}

/// 128 random-enough bits: a per-process random hasher seed, the clock and a counter.
pub(crate) fn idempotency_key() -> String {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let now = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    let mut words = [0u64; 2];
    for (i, word) in words.iter_mut().enumerate() {
        let mut h = std::collections::hash_map::RandomState::new().build_hasher();
        h.write_u128(now);
        h.write_u64(n);
        h.write_usize(i);
        h.write_u32(std::process::id());
        *word = h.finish();
    }
    format!("{:016x}{:016x}", words[0], words[1])
}

struct ProgressReader<'a> {
    inner: File,
    sent: u64,
    reported: u64,
    total: u64,
    progress: &'a mut dyn FnMut(u64, u64),
    cancel: &'a AtomicBool,
}

impl Read for ProgressReader<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        // Checked on every read (one atomic load per buffer), so a cancel stops a slow
        // upload within one buffer rather than at the end of the file.
        if self.cancel.load(Ordering::Acquire) {
            return Err(std::io::Error::other("upload cancelled"));
        }
        let n = self.inner.read(buf)?;
        self.sent += n as u64;
        // Report every MiB and at the end: cheap even for multi-GiB files.
        if n > 0 && (self.sent - self.reported >= 1 << 20 || self.sent == self.total) {
            self.reported = self.sent;
            (self.progress)(self.sent, self.total);
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SessionState;
    use crate::test_server::{Reply, serve};
    use std::io::Write;
    use std::net::TcpListener;
    use std::sync::{Arc, Mutex};

    fn fast(base: &str) -> Client {
        Client::new(base)
            .unwrap()
            .with_retries(3, Duration::from_millis(10))
    }

    fn new_session() -> NewSession {
        NewSession {
            trials: 4,
            setting: "median".into(),
            playback: "upload".into(),
            window_frames: None,
            pose_relation: None,
        }
    }

    #[test]
    fn create_session_posts_json_with_an_idempotency_key() {
        let (base, seen) = serve(vec![Reply::Answer(201, r#"{"id":"s-abc"}"#)]);
        let id = fast(&base).create_session(&new_session()).unwrap();
        assert_eq!(id, "s-abc");
        let seen = seen.lock().unwrap();
        assert_eq!(seen[0].method, "POST");
        assert_eq!(seen[0].path, "/v1/sessions");
        assert_eq!(seen[0].header("content-type"), Some("application/json"));
        assert_eq!(seen[0].header(IDEMPOTENCY_HEADER).map(str::len), Some(32));
        let body: serde_json::Value = serde_json::from_slice(&seen[0].body).unwrap();
        assert_eq!(
            body,
            serde_json::json!({"trials":4,"setting":"median","playback":"upload"})
        );
    }

    #[test]
    fn session_options_travel_as_their_json_keys_and_absent_ones_stay_absent() {
        let (base, seen) = serve(vec![
            Reply::Answer(201, r#"{"id":"s-abc"}"#),
            Reply::Answer(201, r#"{"id":"s-def"}"#),
        ]);
        let client = fast(&base);
        let options = SessionOptions {
            adaptive_min_trials: Some(5),
            ..SessionOptions::default()
        };
        let windowed = NewSession {
            window_frames: Some(20),
            pose_relation: Some("angle_deg".into()),
            ..new_session()
        };
        client.create_session_with(&windowed, &options).unwrap();
        client
            .create_session_with(&new_session(), &SessionOptions::default())
            .unwrap();
        let seen = seen.lock().unwrap();
        let body = |i: usize| serde_json::from_slice::<serde_json::Value>(&seen[i].body).unwrap();
        assert_eq!(
            body(0),
            serde_json::json!({"trials":4,"setting":"median","playback":"upload",
                "adaptive_min_trials":5,"window_frames":20,"pose_relation":"angle_deg"})
        );
        assert_eq!(
            body(1),
            serde_json::json!({"trials":4,"setting":"median","playback":"upload"})
        );
    }

    #[test]
    fn a_5xx_is_retried_with_the_same_idempotency_key() {
        let (base, seen) = serve(vec![
            Reply::Answer(503, r#"{"error":{"code":"busy","message":"try later"}}"#),
            Reply::Answer(500, "oops"),
            Reply::Answer(201, r#"{"id":"s1"}"#),
        ]);
        let id = fast(&base).create_session(&new_session()).unwrap();
        assert_eq!(id, "s1");
        let seen = seen.lock().unwrap();
        assert_eq!(seen.len(), 3);
        let key = seen[0].header(IDEMPOTENCY_HEADER).unwrap();
        assert!(
            seen.iter()
                .all(|s| s.header(IDEMPOTENCY_HEADER) == Some(key))
        );
    }

    #[test]
    fn a_4xx_is_not_retried_and_carries_the_json_error() {
        let (base, seen) = serve(vec![
            Reply::Answer(
                404,
                r#"{"error":{"code":"not_found","message":"no session s9"}}"#,
            ),
            Reply::Answer(200, "{}"),
        ]);
        let err = fast(&base).status("s9").unwrap_err();
        match err {
            Error::Server {
                status,
                code,
                message,
            } => {
                assert_eq!(
                    (status, code.as_str(), message.as_str()),
                    (404, "not_found", "no session s9")
                );
            }
            other => panic!("unexpected {other:?}"),
        }
        assert_eq!(seen.lock().unwrap().len(), 1);
    }

    #[test]
    fn persistent_5xx_gives_up_after_the_retries() {
        let (base, seen) = serve((0..4).map(|_| Reply::Answer(502, "bad gateway")).collect());
        let err = fast(&base).health().unwrap_err();
        assert_eq!(err.status(), Some(502));
        assert_eq!(seen.lock().unwrap().len(), 4);
    }

    #[test]
    fn connection_refused_is_a_network_error_after_every_attempt() {
        let port = TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let err = fast(&format!("http://127.0.0.1:{port}"))
            .health()
            .unwrap_err();
        assert!(matches!(err, Error::Network { attempts: 4, .. }), "{err:?}");
    }

    #[test]
    fn a_silent_server_times_out() {
        let (base, _seen) = serve(vec![Reply::Hang, Reply::Hang]);
        let client = Client::new(&base)
            .unwrap()
            .with_timeout(Duration::from_millis(300))
            .with_retries(1, Duration::from_millis(10));
        let started = Instant::now();
        let err = client.health().unwrap_err();
        assert!(matches!(err, Error::Timeout { attempts: 2, .. }), "{err:?}");
        // Two attempts of 0.3 s, far below the 30 s default (a loose bound: CI machines are loaded).
        assert!(
            started.elapsed() < Duration::from_secs(5),
            "{:?}",
            started.elapsed()
        );
    }

    #[test]
    fn upload_streams_the_file_with_its_length_and_reports_progress() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rec.mp4");
        let data: Vec<u8> = (0..3_000_000u32).map(|i| (i * 7 % 251) as u8).collect();
        std::fs::write(&path, &data).unwrap();
        // A server without resumable uploads: 405 to the HEAD, then the whole file.
        let (base, seen) = serve(vec![Reply::Answer(405, "{}"), Reply::Answer(202, "{}")]);
        let mut calls = Vec::new();
        fast(&base)
            .upload_recording("s1", &path, &mut |sent, total| calls.push((sent, total)))
            .unwrap();
        let seen = seen.lock().unwrap();
        assert_eq!(seen[0].method, "HEAD");
        assert_eq!(seen[1].method, "PUT");
        assert_eq!(seen[1].path, "/v1/sessions/s1/recording");
        assert_eq!(seen[1].header("content-length"), Some("3000000"));
        assert_eq!(seen[1].header("content-range"), None);
        assert!(seen[1].body == data);
        // Both carry the file's key.
        let key = seen[1].header("idempotency-key").unwrap();
        assert!(
            key.starts_with("recording-") && key.contains("-3000000-"),
            "{key}"
        );
        assert_eq!(seen[0].header("idempotency-key"), Some(key));
        assert_eq!(calls.first(), Some(&(0, 3_000_000)));
        assert_eq!(calls.last(), Some(&(3_000_000, 3_000_000)));
        assert!(calls.windows(2).all(|w| w[0].0 <= w[1].0));
    }

    #[test]
    fn an_upload_the_server_kept_part_of_sends_only_the_rest() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rec.mp4");
        let data: Vec<u8> = (0..3_000_000u32).map(|i| (i * 7 % 251) as u8).collect();
        std::fs::write(&path, &data).unwrap();
        let (base, seen) = serve(vec![Reply::Offset(1_000_000), Reply::Answer(202, "{}")]);
        let mut calls = Vec::new();
        fast(&base)
            .upload_recording("s1", &path, &mut |sent, total| calls.push((sent, total)))
            .unwrap();
        let seen = seen.lock().unwrap();
        assert_eq!(seen[1].method, "PUT");
        assert_eq!(
            seen[1].header("content-range"),
            Some("bytes 1000000-2999999/3000000")
        );
        assert_eq!(seen[1].header("content-length"), Some("2000000"));
        assert!(seen[1].body == data[1_000_000..]);
        assert_eq!(calls.first(), Some(&(1_000_000, 3_000_000)));
        assert_eq!(calls.last(), Some(&(3_000_000, 3_000_000)));
        // Another file (here: the same path rewritten, so a new time) gets another key.
        let key = seen[1].header("idempotency-key").unwrap().to_string();
        drop(seen);
        std::fs::File::options()
            .write(true)
            .open(&path)
            .unwrap()
            .set_modified(UNIX_EPOCH + Duration::from_secs(1_700_000_000))
            .unwrap();
        let meta = std::fs::metadata(&path).unwrap();
        assert_ne!(file_key(&path, &meta), key);
        assert_eq!(file_key(&path, &meta), file_key(&path, &meta));
    }

    #[test]
    fn a_cancelled_upload_stops_mid_transfer_and_is_not_retried() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rec.mp4");
        let total = 64u64 << 20;
        std::fs::File::create(&path)
            .unwrap()
            .set_len(total)
            .unwrap();
        // A server that reads whatever arrives on each connection and counts it.
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let base = format!("http://{}", listener.local_addr().unwrap());
        let received = Arc::new(Mutex::new(Vec::<u64>::new()));
        let log = received.clone();
        std::thread::spawn(move || {
            for stream in listener.incoming() {
                let Ok(mut stream) = stream else { return };
                let mut buf = vec![0; 1 << 16];
                // The HEAD asking for a kept prefix: none.
                if stream
                    .peek(&mut buf[..5])
                    .is_ok_and(|k| &buf[..k] == b"HEAD ")
                {
                    let _ = stream.read(&mut buf);
                    let _ = stream.write_all(
                        b"HTTP/1.1 200 X\r\nupload-offset: 0\r\ncontent-length: 0\r\nconnection: close\r\n\r\n",
                    );
                    continue;
                }
                let mut n = 0u64;
                while let Ok(k @ 1..) = stream.read(&mut buf) {
                    n += k as u64;
                }
                log.lock().unwrap().push(n);
            }
        });
        let cancel = AtomicBool::new(false);
        let mut last = 0;
        let err = fast(&base)
            .upload_recording_cancellable(
                "s1",
                &path,
                &mut |sent, _| {
                    last = sent;
                    if sent >= 4 << 20 {
                        cancel.store(true, Ordering::Release);
                    }
                },
                &cancel,
            )
            .unwrap_err();
        assert!(matches!(err, Error::Cancelled), "{err:?}");
        assert!(
            (4 << 20..8 << 20).contains(&last),
            "stopped after {last} bytes"
        );
        // The server sees the connection close early, once: no retry.
        let deadline = Instant::now() + Duration::from_secs(10);
        while received.lock().unwrap().is_empty() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
        }
        std::thread::sleep(Duration::from_millis(200));
        let received = received.lock().unwrap();
        assert_eq!(received.len(), 1, "{received:?}");
        assert!(
            received[0] < total / 2,
            "the server got {} bytes",
            received[0]
        );
    }

    #[test]
    fn a_cancel_before_the_upload_sends_nothing() {
        let (base, seen) = serve(vec![Reply::Answer(202, "{}")]);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rec.mp4");
        std::fs::write(&path, b"data").unwrap();
        let err = fast(&base)
            .upload_recording_cancellable("s1", &path, &mut |_, _| {}, &AtomicBool::new(true))
            .unwrap_err();
        assert!(matches!(err, Error::Cancelled), "{err:?}");
        std::thread::sleep(Duration::from_millis(100));
        assert!(seen.lock().unwrap().is_empty());
    }

    #[test]
    fn upload_of_a_missing_file_names_it() {
        let client = fast("http://127.0.0.1:9");
        let err = client
            .upload_recording("s1", Path::new("/no/such/rec.mp4"), &mut |_, _| {})
            .unwrap_err();
        assert!(err.to_string().contains("/no/such/rec.mp4"), "{err}");
    }

    #[test]
    fn status_parses_and_trial_upload_is_plain_text() {
        let (base, seen) = serve(vec![
            Reply::Answer(
                200,
                r#"{"id":"s1","state":"playing","progress":0.5,"eta_s":3.5,"trials_done":2,"trials_total":4,"error":null}"#,
            ),
            Reply::Answer(201, "{}"),
        ]);
        let client = fast(&base);
        let status = client.status("s1").unwrap();
        assert_eq!(status.state, SessionState::Playing);
        assert_eq!(
            (status.trials_done, status.trials_total, status.eta_s),
            (2, 4, Some(3.5))
        );
        assert_eq!(status.results_trials, 0);
        client.upload_trial("s1", "1 0 0 0 0 0 0 1\n").unwrap();
        let seen = seen.lock().unwrap();
        assert_eq!(seen[1].path, "/v1/sessions/s1/trials");
        assert_eq!(seen[1].body, b"1 0 0 0 0 0 0 1\n");
        assert!(
            seen[1]
                .header("content-type")
                .unwrap()
                .starts_with("text/plain")
        );
    }

    #[test]
    fn status_reads_the_venue_and_both_forms_of_alignment() {
        const HEAD: &str = r#""id":"s1","state":"done","progress":1.0,"eta_s":null,"trials_done":2,"trials_total":2,"error":null"#;
        let parse = |extra: &str| -> SessionStatus {
            serde_json::from_str(&format!("{{{HEAD}{extra}}}")).unwrap()
        };
        let aligned = parse(
            r#","venue":"v0123456789abcdef","alignment":{"anchor":"hall","observations":12,"position_spread_m":0.004,"heading_spread_deg":0.3}"#,
        );
        assert_eq!(aligned.venue.as_deref(), Some("v0123456789abcdef"));
        assert_eq!(
            aligned.alignment,
            Some(crate::VenueAlignment::Aligned {
                anchor: "hall".into(),
                observations: 12,
                position_spread_m: 0.004,
                heading_spread_deg: 0.3,
            })
        );
        let not = parse(
            r#","venue":"v0123456789abcdef","alignment":{"error":"no full observation of hall"}"#,
        );
        assert_eq!(
            not.alignment,
            Some(crate::VenueAlignment::NotAligned {
                error: "no full observation of hall".into()
            })
        );
        // Null, or absent (an older backend): none.
        for extra in [r#","venue":null,"alignment":null"#, ""] {
            let st = parse(extra);
            assert_eq!((st.venue, st.alignment), (None, None));
        }
    }

    #[test]
    fn ids_and_keys_are_checked_and_unique() {
        assert!(check_session_id("a-B_9").is_ok());
        for bad in ["", "../x", "a/b", "a b", "a%2e"] {
            assert!(check_session_id(bad).is_err(), "{bad}");
        }
        let keys: std::collections::HashSet<String> =
            (0..1000).map(|_| idempotency_key()).collect();
        assert_eq!(keys.len(), 1000);
    }
}
