//! The one guard every entry point goes through: catches panics, maps errors
//! to status codes and keeps the calling thread's last error message.

use std::any::Any;
use std::cell::RefCell;
use std::fmt::Write as _;
use std::panic::{catch_unwind, AssertUnwindSafe};

use crate::error::{Error, SitarStatus};

thread_local! {
    static LAST_ERROR: RefCell<String> = const { RefCell::new(String::new()) };
}

/// Runs `f`, turning an error or a panic into a status code and the thread's
/// last error message. Success does not touch the last error (the frame path
/// stays allocation-free).
pub(crate) fn run_ffi_safe<F>(f: F) -> i32
where
    F: FnOnce() -> Result<(), Error>,
{
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => SitarStatus::SITAR_OK as i32,
        Ok(Err(e)) => record(&e),
        Err(payload) => record(&Error::Panic(panic_message(payload.as_ref()))),
    }
}

/// Stores `e` as the thread's last error and returns its code.
pub(crate) fn record(e: &Error) -> i32 {
    log::debug!("sitar error: {e}");
    LAST_ERROR.with(|cell| {
        if let Ok(mut s) = cell.try_borrow_mut() {
            s.clear();
            let _ = write!(s, "{e}");
        }
    });
    e.code()
}

/// The thread's last error message ("" if none yet), passed to `f`.
pub(crate) fn with_last_error<R>(f: impl FnOnce(&str) -> R) -> R {
    LAST_ERROR.with(|cell| match cell.try_borrow() {
        Ok(s) => f(&s),
        Err(_) => f(""),
    })
}

pub(crate) fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic with a non-string payload".to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_sets_code_and_message() {
        let code = run_ffi_safe(|| Err(Error::Null("pose")));
        assert_eq!(code, SitarStatus::SITAR_ERR_NULL as i32);
        with_last_error(|m| assert_eq!(m, "argument `pose` is NULL"));
    }

    #[test]
    fn panic_becomes_panic_code() {
        let code = run_ffi_safe(|| panic!("boom {}", 7));
        assert_eq!(code, SitarStatus::SITAR_ERR_PANIC as i32);
        with_last_error(|m| assert_eq!(m, "internal panic: boom 7"));
    }

    #[test]
    fn success_keeps_previous_message() {
        run_ffi_safe(|| Err(Error::InvalidState("first".into())));
        assert_eq!(run_ffi_safe(|| Ok(())), 0);
        with_last_error(|m| assert_eq!(m, "first"));
    }
}
