//! A session's published results (`results.csv`, `results.json` in its folder): written
//! when an estimate is published, read by the results routes, the report and the legacy
//! route.

use crate::Error;
use crate::estimation::Published;
use crate::session::Session;
use crate::shared::Shared;

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
pub(crate) fn write(shared: &Shared, id: &str, published: &Published) -> Result<(), Error> {
    let lock = shared.session_lock(id);
    let _held = lock.blocking_lock();
    shared.session(id)?;
    let files = &shared.files;
    files.write_atomic(&files.results_csv(id), published.csv.as_bytes())?;
    files.write_atomic(&files.results_json(id), published.json.as_bytes())?;
    shared.lifecycle().publish(id, published.trials)
}

/// The latest published results of `session`; a 409 naming the state when there are none.
pub(crate) fn read(shared: &Shared, session: &Session, form: Form) -> Result<String, Error> {
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
