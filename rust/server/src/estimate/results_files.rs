//! A session's published results (`results.csv`, `results.json` in its folder): written
//! when an estimate is published, read by the results routes, the report and the legacy
//! route.

use crate::Error;
use crate::app_state::App;
use crate::estimate::publishing::Published;
use crate::session::Session;
use crate::storage::BlobStore;
use crate::storage::keys::SessionObject;

/// Which of the two forms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Form {
    /// Legacy `start,error`.
    Csv,
    /// `{"version":1,…,"windows":[…]}`.
    Json,
}

/// Writes a published estimate into the session's folder, then records it. Holds the
/// session's lock, so a delete never sees half of it; a session deleted meanwhile gets
/// nothing. Blocking.
pub(crate) fn write(shared: &App, id: &str, published: &Published) -> Result<(), Error> {
    let lock = shared.session_lock(id);
    let _held = lock.blocking_lock();
    shared.session(id)?;
    let files = &shared.blobs;
    files.put(id, SessionObject::ResultsCsv, published.csv.as_bytes())?;
    files.put(id, SessionObject::ResultsJson, published.json.as_bytes())?;
    append_history(&**files, id, published);
    shared.lifecycle().publish(id, published.trials)
}

/// Appends `{"trials","mean","max","high","medium","low"}` (window errors in the results'
/// unit; sub-trajectory classes) to the session's history, one line per published estimate
/// (at most one per trial). A history that cannot be written only loses the report's
/// history table, so the error is logged, not returned.
fn append_history(blobs: &dyn BlobStore, id: &str, published: &Published) {
    let count = |c: sitar_core::ErrorClass| published.classes.values().filter(|v| **v == c).count();
    let line = serde_json::json!({
        "trials": published.trials,
        "mean": published.mean_error,
        "max": published.max_error,
        "high": count(sitar_core::ErrorClass::High),
        "medium": count(sitar_core::ErrorClass::Medium),
        "low": count(sitar_core::ErrorClass::Low),
    });
    if let Err(e) = blobs.append_line(id, SessionObject::History, &line.to_string()) {
        log::warn!("{e}");
    }
}

/// The published estimates of `session` in order (empty when none was recorded).
pub(crate) fn history(shared: &App, session: &Session) -> Vec<serde_json::Value> {
    let text = match shared.blobs.get(&session.id, SessionObject::History) {
        Ok(Some(bytes)) => String::from_utf8_lossy(&bytes).into_owned(),
        Ok(None) => return Vec::new(),
        Err(e) => {
            log::warn!("{e}");
            return Vec::new();
        }
    };
    text.lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect()
}

/// The latest published results of `session`; a 409 naming the state when there are none.
pub(crate) fn read(shared: &App, session: &Session, form: Form) -> Result<String, Error> {
    if session.results_trials == 0 {
        return Err(Error::Conflict(format!(
            "session {} has no results yet (state {})",
            session.id, session.state
        )));
    }
    let object = match form {
        Form::Csv => SessionObject::ResultsCsv,
        Form::Json => SessionObject::ResultsJson,
    };
    let bytes = shared.blobs.get(&session.id, object)?.ok_or_else(|| {
        Error::Internal(format!(
            "session {}: {} is missing",
            session.id,
            object.relative_path()
        ))
    })?;
    String::from_utf8(bytes)
        .map_err(|e| Error::Internal(format!("{}: {e}", object.relative_path())))
}
