//! The crate's one error type.

use std::path::PathBuf;

/// Why a depth sample could not be used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum InvalidDepth {
    /// The sample pixel holds 0 (ARCore's "no depth").
    NoDepth {
        /// Column of the sample pixel (sensor image).
        x: u32,
        /// Row of the sample pixel (sensor image).
        y: u32,
    },
    /// The sample pixel lies outside the image.
    OutOfBounds {
        /// Column of the sample pixel (sensor image).
        x: u32,
        /// Row of the sample pixel (sensor image).
        y: u32,
    },
    /// Every neighbour in the 5×5 window along one image axis was missing or rejected by the 20 % rule.
    NoValidNeighbours {
        /// Column of the sample pixel (sensor image).
        x: u32,
        /// Row of the sample pixel (sensor image).
        y: u32,
    },
}

impl InvalidDepth {
    /// A short machine name: `no_depth`, `out_of_bounds` or `no_valid_neighbours`.
    pub fn code(&self) -> &'static str {
        match self {
            Self::NoDepth { .. } => "no_depth",
            Self::OutOfBounds { .. } => "out_of_bounds",
            Self::NoValidNeighbours { .. } => "no_valid_neighbours",
        }
    }

    /// The sample pixel `(x, y)`.
    pub fn pixel(&self) -> (u32, u32) {
        match *self {
            Self::NoDepth { x, y }
            | Self::OutOfBounds { x, y }
            | Self::NoValidNeighbours { x, y } => (x, y),
        }
    }

    /// Rebuilds a value from [`InvalidDepth::code`] and the pixel.
    pub fn from_code(code: &str, x: u32, y: u32) -> Option<Self> {
        match code {
            "no_depth" => Some(Self::NoDepth { x, y }),
            "out_of_bounds" => Some(Self::OutOfBounds { x, y }),
            "no_valid_neighbours" => Some(Self::NoValidNeighbours { x, y }),
            _ => None,
        }
    }
}

impl std::fmt::Display for InvalidDepth {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (x, y) = self.pixel();
        match self {
            Self::NoDepth { .. } => write!(f, "no depth (0 mm) at pixel ({x}, {y})"),
            Self::OutOfBounds { .. } => write!(f, "pixel ({x}, {y}) is outside the depth image"),
            Self::NoValidNeighbours { .. } => write!(
                f,
                "no valid neighbour around pixel ({x}, {y}) (all missing or more than 20 % off)"
            ),
        }
    }
}

/// Everything that can go wrong in `sitar-core`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A call that the session's current state does not allow (e.g. `frame` before `start`).
    #[error("invalid state: {0}")]
    InvalidState(&'static str),
    /// An argument outside its valid range; `name` is the parameter.
    #[error("invalid argument `{name}`: {reason}")]
    InvalidArgument {
        /// The parameter's name.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// Malformed text (results, TUM, tables); `line` is 1-based (0 when the text is not line-oriented).
    #[error("{source_name}: line {line}, field `{field}`: {message}")]
    Parse {
        /// What was parsed (file name or a description such as `results`).
        source_name: String,
        /// 1-based line, 0 when unknown.
        line: usize,
        /// The field (column or JSON path).
        field: String,
        /// What is wrong.
        message: String,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A session config key is unknown, has the wrong type or an invalid value.
    #[error("config key `{key}`: {message}")]
    Config {
        /// The key.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A depth sample is unusable.
    #[error("invalid depth: {0}")]
    InvalidDepth(InvalidDepth),
}

impl Error {
    pub(crate) fn arg(name: &'static str, reason: impl Into<String>) -> Self {
        Self::InvalidArgument {
            name,
            reason: reason.into(),
        }
    }

    pub(crate) fn parse(
        source_name: &str,
        line: usize,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self::Parse {
            source_name: source_name.to_owned(),
            line,
            field: field.into(),
            message: message.into(),
        }
    }

    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        Self::Io {
            path: path.to_owned(),
            source,
        }
    }
}
