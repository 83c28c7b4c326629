//! A session's published results (`results.csv`, `results.json` in its folder): written
//! when an estimate is published, read by the results routes, the report and the legacy
//! route.

use crate::error::Error;
use crate::estimate::publishing::Published;
use crate::model::Session;
use crate::session::Lifecycle;
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

/// Writes a published estimate into the session's folder, then records it. The caller
/// holds the session's lock and has seen the session still there, so a delete never sees
/// half of it and a session deleted meanwhile gets nothing. Blocking.
pub(crate) fn write(
    blobs: &dyn BlobStore,
    lifecycle: &Lifecycle<'_>,
    id: &str,
    published: &Published,
) -> Result<(), Error> {
    blobs.put(id, SessionObject::ResultsCsv, published.csv.as_bytes())?;
    blobs.put(id, SessionObject::ResultsJson, published.json.as_bytes())?;
    append_history(blobs, id, published);
    lifecycle.publish(id, published.trials)
}

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
pub(crate) fn history(blobs: &dyn BlobStore, session: &Session) -> Vec<serde_json::Value> {
    let text = match blobs.get(&session.id, SessionObject::History) {
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
pub(crate) fn read(blobs: &dyn BlobStore, session: &Session, form: Form) -> Result<String, Error> {
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
    let bytes = blobs.get(&session.id, object)?.ok_or_else(|| {
        Error::Internal(format!(
            "session {}: {} is missing",
            session.id,
            object.relative_path()
        ))
    })?;
    String::from_utf8(bytes)
        .map_err(|e| Error::Internal(format!("{}: {e}", object.relative_path())))
}
