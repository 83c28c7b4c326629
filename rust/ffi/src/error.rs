use std::str::Utf8Error;
use std::sync::{Mutex, MutexGuard};

crate::descriptors::c_enum! {
    /// Status codes of every C ABI function (`int32_t`); negative is an error.
    ///
    /// JNI reports the same codes as `SitarException.code`.
    pub enum SitarStatus as kotlin SitarStatus, csharp SitarErrorCode {
        /// Success.
        SITAR_OK = 0,
        /// A required pointer argument was NULL.
        SITAR_ERR_NULL = -1,
        /// An argument is out of range, malformed or not valid UTF-8.
        SITAR_ERR_INVALID_ARGUMENT = -2,
        /// A NULL, stale, freed or garbage handle, or a handle of another kind.
        SITAR_ERR_INVALID_HANDLE = -3,
        /// The call is not valid in the object's current state.
        SITAR_ERR_INVALID_STATE = -4,
        /// Text (JSON config, results CSV/JSON) could not be parsed.
        SITAR_ERR_PARSE = -5,
        /// A file could not be read or written.
        SITAR_ERR_IO = -6,
        /// The backend could not be reached or answered with an error.
        SITAR_ERR_NETWORK = -7,
        /// An output buffer is too small; the needed length was written to `*out_len`.
        SITAR_ERR_BUFFER_TOO_SMALL = -8,
        /// A panic inside the library was caught (a bug; please report it).
        SITAR_ERR_PANIC = -99,
    }
}

/// Everything a bridge call can fail with; each maps to one [`SitarStatus`].
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A required pointer or object argument was NULL.
    #[error("argument `{0}` is NULL")]
    Null(&'static str),
    /// An argument is out of range or malformed.
    #[error("invalid argument `{name}`: {reason}")]
    InvalidArgument {
        /// The parameter name.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A string argument is not valid UTF-8.
    #[error("argument `{name}` is not valid UTF-8: {source}")]
    Utf8 {
        /// The parameter name.
        name: &'static str,
        /// Where decoding failed.
        source: Utf8Error,
    },
    /// The handle is 0, was never issued, was freed, or belongs to another kind of object.
    #[error(
        "{kind} handle {handle} is not valid (0, never issued, already freed, or of another kind)"
    )]
    InvalidHandle {
        /// The expected kind of object ("session", "upload", "playback").
        kind: &'static str,
        /// The handle that was passed.
        handle: u64,
    },
    /// The call is not valid in the current state.
    #[error("{0}")]
    InvalidState(String),
    /// An output buffer is too small.
    #[error("buffer too small: {needed} elements needed, capacity is {capacity}")]
    BufferTooSmall {
        /// Elements (or bytes of text without the NUL) needed.
        needed: usize,
        /// Capacity the caller passed.
        capacity: usize,
    },
    /// Upload options JSON is malformed.
    #[error("upload options: {0}")]
    Options(#[from] serde_json::Error),
    /// An error from the on-device logic.
    #[error(transparent)]
    Core(#[from] sitar_core::Error),
    /// The scene export failed.
    #[error(transparent)]
    Scene(#[from] sitar_scene::Error),
    /// An error talking to the backend.
    #[error(transparent)]
    Client(#[from] sitar_client::Error),
    /// A file operation of this crate failed.
    #[error("{context}: {source}")]
    Io {
        /// What was being done, with the path.
        context: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A panic was caught; the message is the panic payload.
    #[error("internal panic: {0}")]
    Panic(String),
    /// A JNI call failed (Kotlin bridge only).
    #[error("JNI: {0}")]
    Jni(String),
}

impl Error {
    /// The status code reported for this error.
    pub fn status(&self) -> SitarStatus {
        use SitarStatus::*;
        match self {
            Error::Null(_) => SITAR_ERR_NULL,
            Error::InvalidArgument { .. } | Error::Utf8 { .. } => SITAR_ERR_INVALID_ARGUMENT,
            Error::InvalidHandle { .. } => SITAR_ERR_INVALID_HANDLE,
            Error::InvalidState(_) => SITAR_ERR_INVALID_STATE,
            Error::BufferTooSmall { .. } => SITAR_ERR_BUFFER_TOO_SMALL,
            Error::Options(_) => SITAR_ERR_PARSE,
            Error::Core(e) => core_status(e),
            Error::Client(e) => client_status(e),
            Error::Scene(sitar_scene::Error::NoTrajectory) => SITAR_ERR_INVALID_STATE,
            Error::Scene(_) => SITAR_ERR_INVALID_ARGUMENT,
            Error::Io { .. } => SITAR_ERR_IO,
            Error::Panic(_) => SITAR_ERR_PANIC,
            Error::Jni(_) => SITAR_ERR_INVALID_ARGUMENT,
        }
    }

    /// The status code as the C ABI returns it.
    pub fn code(&self) -> i32 {
        self.status() as i32
    }

    pub(crate) fn invalid(name: &'static str, reason: impl Into<String>) -> Self {
        Error::InvalidArgument {
            name,
            reason: reason.into(),
        }
    }
}

fn core_status(e: &sitar_core::Error) -> SitarStatus {
    use sitar_core::Error as E;
    use SitarStatus::*;
    match e {
        E::InvalidState(..) => SITAR_ERR_INVALID_STATE,
        E::Parse { .. } | E::Config { .. } => SITAR_ERR_PARSE,
        E::Io { .. } => SITAR_ERR_IO,
        _ => SITAR_ERR_INVALID_ARGUMENT,
    }
}

fn client_status(e: &sitar_client::Error) -> SitarStatus {
    use sitar_client::Error as E;
    use SitarStatus::*;
    match e {
        E::InvalidUrl(_) | E::InvalidArgument(_) => SITAR_ERR_INVALID_ARGUMENT,
        E::Io { .. } | E::Thread(_) => SITAR_ERR_IO,
        E::SessionFailed { .. } => SITAR_ERR_INVALID_STATE,
        E::Panicked(_) => SITAR_ERR_PANIC,
        // An upload job's results sink is ours: its error keeps its own code.
        E::Results(sink) => sink
            .downcast_ref::<Error>()
            .map_or(SITAR_ERR_INVALID_ARGUMENT, Error::status),
        _ => SITAR_ERR_NETWORK,
    }
}

/// The status code of a client error (an upload job's failure).
pub(crate) fn client_code(e: &sitar_client::Error) -> i32 {
    client_status(e) as i32
}

/// Locks `m`; a lock poisoned by an earlier panic is an error of the object it guards.
pub(crate) fn lock<T>(m: &Mutex<T>) -> Result<MutexGuard<'_, T>, Error> {
    m.lock()
        .map_err(|_| Error::Panic("an earlier panic left this object unusable; free it".to_owned()))
}
