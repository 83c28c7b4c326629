//! `GET /v1/sessions/{id}/scene.glb`: the session's scene as glTF 2.0 binary.

use axum::extract::State;
use axum::http::header;
use axum::response::{IntoResponse, Response};

use crate::Error;
use crate::http::{AppState, Found};
use crate::scene;

/// `GET /v1/sessions/{id}/scene.glb`: trajectory by class, frustums, markers, surface points.
pub(crate) async fn glb(State(shared): AppState, Found(session): Found) -> Result<Response, Error> {
    let glb = tokio::task::spawn_blocking(move || {
        let (phone, _) = scene::load(&shared, &session)?;
        sitar_scene::to_glb(&sitar_scene::SceneParts::from_session(&phone))
            .map_err(|e| Error::Conflict(format!("no scene for session {}: {e}", session.id)))
    })
    .await
    .map_err(|e| Error::Internal(format!("scene export: {e}")))??;
    Ok((
        [
            (header::CONTENT_TYPE, "model/gltf-binary"),
            (
                header::CONTENT_DISPOSITION,
                "attachment; filename=\"scene.glb\"",
            ),
        ],
        glb,
    )
        .into_response())
}
