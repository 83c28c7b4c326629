//! The per-token limits at the door (`auth::Limits`, counted by `auth::UploadLimiter`):
//! a request that creates a session is counted, and an upload's body holds a slot and has
//! its bytes counted while it is read (429 with `Retry-After` over a limit).

use std::sync::Arc;

use axum::body::Body;
use axum::extract::{Request, State};
use axum::http::Method;
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use futures_util::StreamExt;

use crate::app_state::App;
use crate::model::Caller;
use crate::storage::now_ms;

fn creates_session(method: &Method, path: &str) -> bool {
    method == Method::POST && matches!(path, "/v1/sessions" | "/recording")
}

fn is_upload(method: &Method, path: &str) -> bool {
    let in_session = |suffix: &str| {
        path.strip_prefix("/v1/sessions/")
            .and_then(|rest| rest.strip_suffix(suffix))
            .is_some_and(|id| !id.is_empty() && !id.contains('/'))
    };
    // Every PUT under a session is an upload: the recording and the evidence files.
    (method == Method::PUT && path.starts_with("/v1/sessions/"))
        || (method == Method::POST
            && (in_session("/trials") || matches!(path, "/recording" | "/timestamps")))
}

/// The middleware: runs after authentication, on the caller's token.
pub(crate) async fn limit_uploads(
    State(shared): State<Arc<App>>,
    request: Request,
    next: Next,
) -> Response {
    let Some(Caller::Token { id, .. }) = request.extensions().get::<Caller>().cloned() else {
        return next.run(request).await;
    };
    let (method, path) = (request.method().clone(), request.uri().path().to_owned());
    if creates_session(&method, &path)
        && let Err(e) = shared.limiter.create_session(&*shared.db, id, now_ms())
    {
        return e.into_response();
    }
    if !is_upload(&method, &path) {
        return next.run(request).await;
    }
    let mut guard = match shared.limiter.start_upload(shared.db.clone(), id, now_ms()) {
        Ok(guard) => guard,
        Err(e) => return e.into_response(),
    };
    let (parts, body) = request.into_parts();
    let counted = body.into_data_stream().map(move |chunk| {
        // The whole guard moves into the stream (not just its counter): the slot is held
        // until the body is done with.
        let guard = &mut guard;
        if let Ok(bytes) = &chunk {
            guard.bytes += bytes.len() as u64;
        }
        chunk
    });
    next.run(Request::from_parts(parts, Body::from_stream(counted)))
        .await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upload_routes_are_recognised() {
        assert!(is_upload(&Method::PUT, "/v1/sessions/s01/recording"));
        assert!(is_upload(&Method::PUT, "/v1/sessions/s01/evidence.csv"));
        assert!(is_upload(
            &Method::PUT,
            "/v1/sessions/s01/subtrajectories/3/image.jpg"
        ));
        assert!(!is_upload(&Method::GET, "/v1/sessions/s01/subtrajectories"));
        assert!(is_upload(&Method::POST, "/v1/sessions/s01/trials"));
        assert!(is_upload(&Method::POST, "/recording"));
        assert!(is_upload(&Method::POST, "/timestamps"));
        assert!(!is_upload(&Method::HEAD, "/v1/sessions/s01/recording"));
        assert!(!is_upload(&Method::POST, "/v1/sessions"));
        assert!(creates_session(&Method::POST, "/v1/sessions"));
        assert!(!creates_session(&Method::GET, "/v1/sessions"));
    }
}
