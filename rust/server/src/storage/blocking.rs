//! Waiting in a synchronous method for work done on the store's own threads (Postgres
//! connection threads, the S3 client's runtime) — never by entering a tokio runtime from
//! one, which panics. On a multi-threaded runtime the wait is inside `block_in_place`, so the
//! worker's other tasks move to another thread meanwhile.

use std::sync::mpsc::Receiver;

/// The answer sent on `receive`, or `None` when its sender went away without one.
#[cfg_attr(not(feature = "cluster"), allow(dead_code))] // the cluster stores use it
pub(crate) fn wait<T>(receive: Receiver<T>) -> Option<T> {
    let on_workers = tokio::runtime::Handle::try_current()
        .is_ok_and(|h| h.runtime_flavor() == tokio::runtime::RuntimeFlavor::MultiThread);
    if on_workers {
        tokio::task::block_in_place(|| receive.recv().ok())
    } else {
        receive.recv().ok()
    }
}
