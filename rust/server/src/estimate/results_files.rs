//! A session's published results (`results.csv`, `results.json` in its folder): written
//! when an estimate is published, read by the results routes, the report and the legacy
//! route.

use crate::Error;
use crate::app_state::App;
use crate::estimate::publishing::Published;
use crate::session::Session;

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
    let files = &shared.files;
    files.write_atomic(&files.results_csv(id), published.csv.as_bytes())?;
    files.write_atomic(&files.results_json(id), published.json.as_bytes())?;
    append_history(&files.session_dir(id).join(HISTORY), published);
    shared.lifecycle().publish(id, published.trials)
}

/// One line per published estimate (at most one per trial): how the estimate changed as
/// trials arrived, for the report.
pub(crate) const HISTORY: &str = "history.jsonl";

/// Appends `{"trials","mean","max","high","medium","low"}` (window errors in the results'
/// unit; sub-trajectory classes). A history that cannot be written only loses the report's
/// history table, so the error is logged, not returned.
fn append_history(path: &std::path::Path, published: &Published) {
    use std::io::Write as _;
    let count = |c: sitar_core::ErrorClass| published.classes.values().filter(|v| **v == c).count();
    let line = serde_json::json!({
        "trials": published.trials,
        "mean": published.mean_error,
        "max": published.max_error,
        "high": count(sitar_core::ErrorClass::High),
        "medium": count(sitar_core::ErrorClass::Medium),
        "low": count(sitar_core::ErrorClass::Low),
    });
    let written = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .and_then(|mut f| writeln!(f, "{line}"));
    if let Err(e) = written {
        log::warn!("cannot append to {}: {e}", path.display());
    }
}

/// The published estimates of `session` in order (empty when none was recorded).
pub(crate) fn history(shared: &App, session: &Session) -> Vec<serde_json::Value> {
    std::fs::read_to_string(shared.files.session_dir(&session.id).join(HISTORY))
        .map(|text| {
            text.lines()
                .filter_map(|l| serde_json::from_str(l).ok())
                .collect()
        })
        .unwrap_or_default()
}

/// The latest published results of `session`; a 409 naming the state when there are none.
pub(crate) fn read(shared: &App, session: &Session, form: Form) -> Result<String, Error> {
    if session.results_trials == 0 {
        return Err(Error::Conflict(format!(
            "session {} has no results yet (state {})",
            session.id, session.state
        )));
    }
    let path = match form {
        Form::Csv => shared.files.results_csv(&session.id),
        Form::Json => shared.files.results_json(&session.id),
    };
    std::fs::read_to_string(&path).map_err(|e| Error::io("cannot read", &path, e))
}
