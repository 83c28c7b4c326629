//! The crate's single error type.

use std::path::PathBuf;

/// Everything that can go wrong in `sitar-estimator`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be opened or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A trajectory file is malformed; names the file (or source), line and column (1-based).
    #[error("{file}:{line}:{column}: {message}")]
    Parse {
        /// File path or source name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// 1-based column (character) of the offending token.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// A trajectory is internally inconsistent (lengths, order of stamps, non-finite values).
    #[error("invalid trajectory: {0}")]
    InvalidTrajectory(String),
    /// An option or argument is out of range or inconsistent.
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    /// Association found no stamps of the two trajectories within `max_diff`.
    #[error(
        "no matching timestamps between {first} and {second} (max diff {max_diff_s} s, offset {offset_s} s)"
    )]
    NoMatches {
        /// Name of the first trajectory.
        first: String,
        /// Name of the second trajectory.
        second: String,
        /// The association tolerance in seconds.
        max_diff_s: f64,
        /// The time offset applied to the second trajectory, seconds.
        offset_s: f64,
    },
    /// Alignment is impossible: too few points or a degenerate (rank-deficient) covariance.
    #[error("degenerate alignment: {0}")]
    DegenerateAlignment(String),
    /// The metric has no pose pairs (trajectory shorter than delta, empty input).
    #[error("no pose pairs: {0}")]
    NoPairs(String),
}
