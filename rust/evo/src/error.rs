//! The one error type of the crate. Its `Display` is one link of a cause chain (as
//! `anyhow` prints it): the CLI joins the chain with `: ` and prints the same text as before
//! the logic moved here, and the Python package raises it as one message.

/// What went wrong, with the option, file or line it concerns.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A bad option or an input the metric cannot use; the message names it.
    #[error("{0}")]
    Invalid(String),
    /// The trajectory library's error (files name their path, line and column).
    #[error(transparent)]
    Estimator(#[from] sitar_estimator::Error),
    /// An error with what was being done when it happened.
    #[error("{context}")]
    Context {
        /// What was being done (`computing the APE`, `run0.txt: estimating the time offset`).
        context: String,
        /// The cause.
        #[source]
        source: Box<Error>,
    },
    /// A message could not be written (the CLI's stdout; a closed pipe ends it quietly).
    #[error("cannot write to stdout")]
    Output(#[source] std::io::Error),
}

/// The crate's result.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// `bail!` for [`Error::Invalid`].
macro_rules! invalid {
    ($($arg:tt)*) => {
        return Err($crate::error::Error::Invalid(format!($($arg)*)))
    };
}
pub(crate) use invalid;

/// Adds what was being done to an error, as `anyhow::Context` does.
pub trait Context<T> {
    /// The error with `context` in front.
    fn context(self, context: impl Into<String>) -> Result<T>;
    /// The error with a lazily built context in front.
    fn with_context(self, context: impl FnOnce() -> String) -> Result<T>;
}

impl<T, E: Into<Error>> Context<T> for std::result::Result<T, E> {
    fn context(self, context: impl Into<String>) -> Result<T> {
        self.map_err(|e| Error::Context {
            context: context.into(),
            source: Box::new(e.into()),
        })
    }

    fn with_context(self, context: impl FnOnce() -> String) -> Result<T> {
        self.map_err(|e| Error::Context {
            context: context(),
            source: Box::new(e.into()),
        })
    }
}

impl Error {
    /// The whole cause chain on one line, outermost first, joined by `: ` (skipping a
    /// cause an outer message already quotes): the text Python's exception carries.
    pub fn chain_text(&self) -> String {
        let mut line = String::new();
        let mut cause: Option<&dyn std::error::Error> = Some(self);
        while let Some(error) = cause {
            let text = error.to_string();
            if !line.contains(&text) {
                if !line.is_empty() {
                    line.push_str(": ");
                }
                line.push_str(&text);
            }
            cause = error.source();
        }
        line
    }
}

/// Every cause joined by `: `, as `anyhow` prints `{:#}` (no de-duplication).
pub(crate) fn full_chain(error: &dyn std::error::Error) -> String {
    let mut text = error.to_string();
    let mut cause = error.source();
    while let Some(e) = cause {
        text.push_str(": ");
        text.push_str(&e.to_string());
        cause = e.source();
    }
    text
}
