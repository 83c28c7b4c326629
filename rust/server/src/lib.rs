//! The SiTAR backend: sessions, storage, playback, jobs, report.
//!
//! The paper's server side (section 4.2), sturdy: an axum + tokio HTTP API
//! (versioned routes and the original Unity app's legacy routes), a metadata
//! store for sessions, trials, jobs, devices, tokens and usage and a blob store for every
//! byte of a session (two traits in `storage/`; the embedded default is SQLite in
//! `DATA/sitar.db` and the data directory's session folders), uploads streamed to a temporary file and renamed when whole
//! (a recording upload that breaks off keeps its prefix and can be resumed),
//! server-made ids only, size limits answered with 413, JSON errors
//! `{"error":{"code":…,"message":…}}`, and jobs that survive a restart.
//!
//! A session's life is one state machine (`created → uploaded → playing →
//! estimating → done`, or `failed`), written in one module; a request its state
//! does not allow is a 409 that names the state. Its estimate settings —
//! statistic (`setting`), window length (`window_frames`, default 10) and pose
//! relation (`trans_part` or `angle_deg`, evo's names) — are parsed once when it
//! is created and stored typed; the results JSON records them
//! (`"window_frames"`, `"pose_relation"`, `"unit"`).
//!
//! Playback backends implement one trait, [`Playback`]: [`SimPlayback`]
//! replays a `sitar-sim` recording in scaled real time, [`AdbPlayback`]
//! drives real phones, [`UploadPlayback`] takes trials from outside. Every
//! trial is parsed once on arrival and kept in memory while its session is in
//! flight (bounded: [`ServerConfig::live_session_bytes`],
//! [`ServerConfig::live_total_bytes`]); every finished trial from the 2nd on
//! publishes a progressive estimate over them, bitwise equal to a one-shot
//! estimate, to which the new trial adds only its pairs (the live session keeps
//! a `sitar_estimator::IncrementalEstimate`); with adaptive stopping a session ends early once no window's
//! class changed over the last k trials. A session with a calibration that has a model for
//! one run starts from the phone's walk (`PUT …/walk.txt`): its estimate alone is published
//! at once, before any replay (`"source": "walk"`), and every later one has the walk as the
//! live run and the trials as its replays (`"source": "replays"`, `"runs"` counting the walk).
//!
//! For the people who run it: `GET /` is an HTML overview of the newest
//! sessions (with links to their reports) and the playback devices,
//! `GET /v1/sessions` the same as JSON; `DELETE /v1/sessions/{id}` and the
//! optional [`ServerConfig::retention`] free the data directory; every request
//! is logged as one line through `log`.
//!
//! ```
//! use sitar_server::{PlaybackKind, Server, ServerConfig};
//!
//! let dir = tempfile::tempdir()?;
//! let mut config = ServerConfig::new(dir.path());
//! config.playback = PlaybackKind::Sim;
//! let server = Server::spawn(config, "127.0.0.1:0".parse()?)?;
//! // A new data directory gets an admin token, in a file only its owner reads.
//! let admin = std::fs::read_to_string(dir.path().join(sitar_server::ADMIN_TOKEN_FILE))?;
//! let client = sitar_client::Client::new(&server.url())?.with_server_token(&admin)?;
//! client.health()?;
//! // Unknown sessions are a JSON 404.
//! let err = client.status("s0000000000000000").unwrap_err();
//! assert_eq!(err.status(), Some(404));
//! assert!(dir.path().join("sitar.db").is_file());
//!
//! // A session with 20-frame windows and the rotational estimate.
//! use sitar_client::{NewSession, SessionOptions};
//! let new = NewSession {
//!     trials: 2,
//!     setting: "median".into(),
//!     playback: "upload".into(),
//!     window_frames: Some(20),
//!     pose_relation: Some("angle_deg".into()),
//! };
//! let id = client.create_session_with(&new, &SessionOptions::default())?;
//! assert_eq!(client.status(&id)?.window_frames, Some(20));
//! // A window of 1 frame is refused with a 400 that names the key.
//! let bad = NewSession { window_frames: Some(1), ..new.clone() };
//! let err = client.create_session(&bad).unwrap_err();
//! assert_eq!(err.status(), Some(400));
//! assert!(err.to_string().contains("window_frames"), "{err}");
//! server.stop();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![deny(missing_docs)]

// Folders by concern, lowest first: a module imports only modules above it in this list
// (its own submodules aside). The workspace's `tests/tests/server_layout.rs` checks that,
// that this list names exactly the modules declared here, that only `storage` speaks SQL or
// touches the data directory; `tests/tests/layout.rs` that no import cycle exists.
// error      — the one error enum
// model      — vocabulary: sessions, states, steps, estimate settings, venues, callers, roles, tokens, usage
// storage    — where bytes are kept: metadata store, blob store (traits); imports model alone
// session    — a session's life: the transitions, the only state writer
// auth       — tokens, callers, per-token limits and their counters
// estimate   — estimates over trials held in memory, published; results files; calibrations
// config     — the server's settings (auth limits, calibrations, TLS among them)
// venue      — venues: who sees them, sessions' alignment, venue maps
// ingest     — what arrives from phones: trials, evidence, phone logs, the MP4 check
// report     — what the report draws: page, charts, regions, scene
// playback   — how trials are played: the backends (adb, sim, upload, remote) and the queue
// app_state  — what handlers and jobs share: the stores, live sessions, queue, backends, locks
// jobs       — what runs for a session beyond one request: playback jobs, heartbeats, stop requests, deletions, sweeps
// http       — router, server, middleware (authentication, upload limits), handlers, status document, TLS
// migrate    — `sitar migrate`: an embedded installation into the cluster stores (feature `cluster`)
// fuzzing    — the parsers, for fuzz/ only (doc-hidden)
mod app_state;
mod auth;
mod config;
mod error;
mod estimate;
#[doc(hidden)]
pub mod fuzzing;
mod http;
mod ingest;
mod jobs;
#[cfg(feature = "cluster")]
mod migrate;
mod model;
mod playback;
mod report;
mod session;
mod storage;
mod venue;

pub use auth::{
    ADMIN_TOKEN_FILE, Limits, PresetToken, create_token, create_token_at, list_tokens,
    list_tokens_at, new_token, revoke_token, revoke_token_at,
};
pub use config::{AdbConfig, DELETE_SWEEP_RANGE, ServerConfig, SimConfig, TlsConfig};
pub use error::Error;
pub use estimate::calibrations::{Calibrations, MAX_CALIBRATIONS, is_calibration_name};
pub use http::helpers::IDEMPOTENCY_HEADER;
pub use http::server::{Server, ServerHandle};
#[cfg(feature = "cluster")]
pub use migrate::{MigrateOptions, Summary as MigrateSummary, TableCount, migrate};
pub use model::{PlaybackKind, Role, TokenInfo};

pub use playback::adb::{AdbPlayback, contract as adb_contract, mp4_duration_s};
pub use playback::{
    DeviceInfo, Playback, PlaybackJob, PlaybackPlan, SimPlayback, TrialOutput, UploadPlayback,
};
pub use storage::open::{CLUSTER, NO_CLUSTER};
