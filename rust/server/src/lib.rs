//! The SiTAR backend: sessions, storage, playback, jobs, report.
//!
//! The paper's server side (section 4.2), sturdy: an axum + tokio HTTP API
//! (versioned routes and the original Unity app's legacy routes), a SQLite
//! database for sessions, trials, jobs and devices plus files in one data
//! directory, uploads streamed to a temporary file and renamed when whole
//! (a recording upload that breaks off keeps its prefix and can be resumed),
//! server-made ids only, size limits answered with 413, JSON errors
//! `{"error":{"code":…,"message":…}}`, and jobs that survive a restart.
//!
//! Playback backends implement one trait, [`Playback`]: [`SimPlayback`]
//! replays a `sitar-sim` recording in scaled real time, [`AdbPlayback`]
//! drives real phones, [`UploadPlayback`] takes trials from outside. Every
//! finished trial from the 2nd on publishes a progressive estimate; with
//! adaptive stopping a session ends early once no window's class changed over
//! the last k trials.
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
//! let client = sitar_client::Client::new(&server.url())?;
//! client.health()?;
//! // Unknown sessions are a JSON 404.
//! let err = client.status("s0000000000000000").unwrap_err();
//! assert_eq!(err.status(), Some(404));
//! assert!(dir.path().join("sitar.db").is_file());
//! server.stop();
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod adb;
mod config;
mod db;
mod deletion;
mod error;
mod estimation;
mod files;
mod jobs;
mod mp4_check;
mod overview;
mod playback;
mod recording;
mod report;
mod routes;
mod server;
mod state;

pub use adb::{AdbPlayback, contract as adb_contract, mp4_duration_s};
pub use config::{AdbConfig, PlaybackKind, ServerConfig, SimConfig};
pub use error::Error;
pub use playback::{
    DeviceInfo, Playback, PlaybackJob, PlaybackPlan, SimPlayback, TrialOutput, UploadPlayback,
};
pub use routes::IDEMPOTENCY_HEADER;
pub use server::{Server, ServerHandle};
