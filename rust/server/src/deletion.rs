//! `DELETE /v1/sessions/{id}`: an operator's way to free the data directory. A
//! session is deleted whole (its row, trials, jobs and folder) or not at all,
//! and never while a job works on it.

use std::sync::Arc;
use std::time::Duration;

use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::Response;
use serde_json::json;

use crate::Error;
use crate::routes::{json_response, session_row};
use crate::state::Shared;

/// How long a delete waits for a request that is writing into the session.
const WRITER_WAIT: Duration = Duration::from_secs(5);

pub(crate) async fn delete_session(
    State(shared): State<Arc<Shared>>,
    Path(id): Path<String>,
) -> Result<Response, Error> {
    let row = session_row(&shared, &id)?;
    let lock = shared.session_lock(&row.id);
    let Ok(_held) = tokio::time::timeout(WRITER_WAIT, lock.lock()).await else {
        return Err(Error::Conflict(format!(
            "session {id} is receiving an upload; try again when it ends"
        )));
    };
    // Read again under the lock: the state may have moved on meanwhile.
    let row = session_row(&shared, &id)?;
    let idle = match row.state.as_str() {
        "created" | "done" | "failed" => true,
        // An `upload` session waits for trials; any other has its playback job.
        "uploaded" => row.playback == "upload",
        _ => false,
    };
    if !idle || shared.live(&id).is_some() {
        return Err(Error::Conflict(format!(
            "session {id} is {}: a job works on it; delete it once it is done or failed",
            row.state
        )));
    }
    let trash = shared.files.trash_session_dir(&id)?;
    if let Err(e) = shared.db.delete_session(&id) {
        if let Some(trash) = &trash {
            shared.files.restore_session_dir(&id, trash)?;
        }
        return Err(e);
    }
    shared.forget_session_lock(&id);
    if let Some(trash) = trash {
        // Already out of sight; what a failure leaves, the next start removes.
        if let Err(e) = std::fs::remove_dir_all(&trash) {
            log::warn!("cannot remove {}: {e}", trash.display());
        }
    }
    log::info!("session {id} deleted");
    Ok(json_response(
        StatusCode::OK,
        &json!({"id": id, "deleted": true}).to_string(),
    ))
}
