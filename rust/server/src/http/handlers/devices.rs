//! `GET /v1/devices`: the playback devices of the configured backend, and every one seen.

use axum::extract::State;
use axum::response::{IntoResponse, Response};
use serde_json::json;

use crate::auth::Admin;
use crate::error::Error;
use crate::http::helpers::{AppState, blocking};

/// Admin only: devices are the lab's, not an app's.
pub(crate) async fn list(State(shared): AppState, _: Admin) -> Result<Response, Error> {
    let backend = shared.backend(shared.config.playback);
    let list = blocking("devices task", move || Ok(backend.devices())).await?;
    for d in &list {
        shared.db.upsert_device(&d.serial, &d.state, None)?;
    }
    let known: Vec<_> = shared
        .db
        .devices()?
        .into_iter()
        .map(|(serial, state, session, seen)| {
            json!({"serial": serial, "state": state, "session": session, "last_seen_ms": seen})
        })
        .collect();
    Ok(axum::Json(
        json!({"playback": shared.config.playback.as_str(), "devices": list, "known": known}),
    )
    .into_response())
}
