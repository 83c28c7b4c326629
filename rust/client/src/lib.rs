//! Blocking HTTP client of the SiTAR backend (`sitar serve`).
//!
//! [`Client`] speaks the versioned API: create a session, stream the
//! recording from disk, upload trials from an outside SLAM run, poll the
//! status, download results as legacy CSV or JSON. Every call has a timeout;
//! connection errors, timeouts and 5xx answers are retried with exponential
//! backoff; `POST`s carry an [`IDEMPOTENCY_HEADER`] key that stays the same
//! across retries, so a retry never creates a second session or trial. A
//! recording upload cut off by a dropped connection is resumed from the bytes
//! the server kept ([`UPLOAD_OFFSET_HEADER`]), on a retry or in a later call
//! for the same file, not sent again from the start.
//! [`Client::upload_recording_cancellable`] stops a recording upload mid-transfer
//! when its flag is set (the app's cancel button).
//!
//! [`UploadJob`] is the phone's whole round trip on a thread of its own: create (or
//! continue) a session, send the recording resumably, poll, ask for the estimate of an
//! `upload` session once all trials arrived, and hand every published result (progressive,
//! then final) to a sink; the app polls [`JobProgress`] snapshots and may cancel. The native
//! library bridges it one-to-one (`sitar_upload_*`). With the phone's session folder the job
//! also sends the phone's own log ([`Client::upload_phone_logs`]: `trajectory.txt`,
//! `subtrajectories.csv`, `anchors.csv`, `walk.txt`) before the recording, and its camera evidence after;
//! [`SessionFrame`] puts the session's convention and venue into the session request.
//!
//! ```
//! use sitar_client::{Client, Error, NewSession};
//!
//! // URLs are checked up front.
//! assert!(matches!(Client::new("ftp://example"), Err(Error::InvalidUrl(_))));
//! let client = Client::new("http://127.0.0.1:8000/")?;
//! assert_eq!(client.base_url(), "http://127.0.0.1:8000");
//!
//! // A session id that is not server-made never reaches the network.
//! assert!(matches!(client.status("../../etc"), Err(Error::InvalidArgument(_))));
//!
//! # fn flow(client: &Client, path: &std::path::Path) -> Result<(), Error> {
//! let id = client.create_session(&NewSession {
//!     trials: 5,
//!     setting: "trim_mean_30".into(),
//!     playback: "sim".into(),
//!     window_frames: None,
//!     pose_relation: None,
//! })?;
//! client.upload_recording(&id, path, &mut |sent, total| eprintln!("{sent}/{total}"))?;
//! let status = client.wait(&id, std::time::Duration::from_millis(200),
//!                          std::time::Duration::from_secs(120), &mut |_| {})?;
//! let csv = client.results_csv(&id)?;
//! # let _ = (status, csv); Ok(()) }
//! # Ok::<(), Error>(())
//! ```
#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod client;
mod error;
mod job;
mod job_run;
mod job_state;
mod phone_logs;
mod pin;
pub mod platform_tls;
#[cfg(test)]
mod test_server;
mod types;
mod worker_api;

pub use client::{Client, IDEMPOTENCY_HEADER, UPLOAD_OFFSET_HEADER, check_session_id};
pub use error::Error;
pub use job::UploadJob;
pub use job_state::{JobOptions, JobProgress, JobState, SinkError, UPLOAD_SHARE};
pub use phone_logs::{PHONE_LOG_FILES, PhoneLogsSent};
pub use types::{
    NewSession, SessionFrame, SessionOptions, SessionState, SessionStatus, VenueAlignment,
};
pub use worker_api::{WorkerHeartbeat, WorkerHost, WorkerLease};
