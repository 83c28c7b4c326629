use std::path::PathBuf;

/// Everything that can go wrong when talking to the SiTAR backend.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The base URL is not an `http://` or `https://` URL.
    #[error("invalid server URL {0:?}: expected http://host:port or https://host:port")]
    InvalidUrl(String),
    /// An argument was rejected before anything was sent (e.g. a session id with path characters).
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    /// The server could not be reached, or the connection broke, on every attempt.
    #[error("cannot reach {url} after {attempts} attempt(s): {message}")]
    Network {
        /// The URL that was called.
        url: String,
        /// How many attempts were made.
        attempts: u32,
        /// The last transport error.
        message: String,
    },
    /// The server's TLS certificate is not the pinned one (`server_cert_sha256`): nothing was
    /// sent. Not retried.
    #[error(
        "the TLS certificate of {url} has SHA-256 fingerprint {found}, not the pinned {expected}: \
         refusing to talk to it (a different server, or a new certificate?)"
    )]
    CertificateMismatch {
        /// The URL that was called.
        url: String,
        /// The pinned fingerprint (`AB:CD:…`).
        expected: String,
        /// The fingerprint of the certificate the server showed.
        found: String,
    },
    /// A call did not finish within its timeout on every attempt.
    #[error("{url} timed out after {attempts} attempt(s)")]
    Timeout {
        /// The URL that was called.
        url: String,
        /// How many attempts were made.
        attempts: u32,
    },
    /// The server answered with an error status (4xx, or 5xx on every attempt).
    #[error("server answered {status} {code}: {message}")]
    Server {
        /// The HTTP status code.
        status: u16,
        /// The machine-readable error code from the JSON body (`"http"` if the body had none).
        code: String,
        /// The human-readable message from the JSON body.
        message: String,
    },
    /// The server refused a file of the phone's session folder (see
    /// [`crate::Client::upload_phone_logs`]): a 4xx other than 404/405, or a 5xx on every
    /// attempt. Not retried.
    #[error("the server refused {file} ({status} {code}): {message}")]
    FileRefused {
        /// The file's name in the session folder (`trajectory.txt`, …).
        file: String,
        /// The HTTP status code.
        status: u16,
        /// The machine-readable error code from the JSON body.
        code: String,
        /// The server's message (a 422 names the line and column).
        message: String,
    },
    /// A local file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// The thread of an [`crate::UploadJob`] could not be started.
    #[error("cannot start the upload thread: {0}")]
    Thread(std::io::Error),
    /// The server reported the session of an [`crate::UploadJob`] as failed.
    #[error("the server failed session {id}: {reason}")]
    SessionFailed {
        /// The server's session id.
        id: String,
        /// The server's reason.
        reason: String,
    },
    /// The results sink of an [`crate::UploadJob`] refused the final results; the sink's
    /// own error (downcast it to get it back).
    #[error(transparent)]
    Results(crate::job_state::SinkError),
    /// An [`crate::UploadJob`]'s thread panicked (a bug; the message is the panic's).
    #[error("internal panic in the upload job: {0}")]
    Panicked(String),
    /// The caller cancelled the call (see [`crate::Client::upload_recording_cancellable`]).
    #[error("cancelled")]
    Cancelled,
    /// The server's answer was not what the API promises.
    #[error("unexpected answer from the server: {0}")]
    InvalidResponse(String),
}

impl Error {
    /// The HTTP status if the server answered with an error status.
    pub fn status(&self) -> Option<u16> {
        match self {
            Error::Server { status, .. } | Error::FileRefused { status, .. } => Some(*status),
            _ => None,
        }
    }
}
