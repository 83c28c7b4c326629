//! The crate's single error type.

/// Everything that can go wrong in `sitar-sim`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An argument is out of range (non-positive duration or frame rate, empty room, …).
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    /// Bytes given to [`crate::Recording::from_bytes`] are not a recording of this format.
    #[error("not a sitar-sim recording: {0}")]
    NotARecording(String),
    /// The recording was written by a format version this build cannot read.
    #[error(
        "unsupported sitar-sim recording version {found} (this build reads version {supported})"
    )]
    UnsupportedVersion {
        /// Version found in the header.
        found: u32,
        /// Version this build reads.
        supported: u32,
    },
    /// The recording's content is malformed or inconsistent; names the field.
    #[error("invalid recording: {field}: {message}")]
    InvalidRecording {
        /// The offending field (JSON path-like, e.g. `walk.stamps[3]`).
        field: String,
        /// What is wrong.
        message: String,
    },
}
