//! Read-only share links of one session's report: `POST /v1/sessions/{id}/share` makes one
//! (a URL with its own random token, stored hashed), `DELETE /v1/sessions/{id}/share` revokes
//! every link of the session, and `GET /share/{token}` opens the report without an account.
//! The page fetches its data through the same token (`GET /share/{token}/scene.json`, the
//! downloads, the regions' thumbnails, `report` as one file): one session's data, nothing else.

use axum::extract::{Path, RawQuery, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::Response;
use serde_json::json;

use crate::app_state::App;
use crate::auth::new_token;
use crate::error::Error;
use crate::http::helpers::{AppState, Found, json_value};
use crate::ingest::evidence::{EvidenceFiles, MAX_SUBTRAJECTORIES};
use crate::model::Session;

/// The `Host` the client reached us by, if it is a plain host name or address with a port.
fn host(headers: &HeaderMap) -> Result<&str, Error> {
    headers
        .get(header::HOST)
        .and_then(|v| v.to_str().ok())
        .filter(|h| {
            !h.is_empty()
                && h.len() <= 255
                && h.chars()
                    .all(|c| c.is_ascii_alphanumeric() || ".:-[]".contains(c))
        })
        .ok_or_else(|| Error::BadRequest("a share link needs a plain Host header".into()))
}

/// `POST /v1/sessions/{id}/share`: a new link (201 `{"url": …}`); the link is shown once.
pub(crate) async fn create(
    State(shared): AppState,
    Found(session): Found,
    headers: HeaderMap,
) -> Result<Response, Error> {
    let token = new_token()?;
    shared.db.insert_share(&session.id, &token)?;
    let scheme = if shared.secure_cookies {
        "https"
    } else {
        "http"
    };
    let url = format!("{scheme}://{}/share/{token}", host(&headers)?);
    Ok(json_value(
        StatusCode::CREATED,
        &json!({"id": session.id, "url": url}),
    ))
}

/// `DELETE /v1/sessions/{id}/share`: every link of the session stops working.
pub(crate) async fn revoke(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    let revoked = shared.db.revoke_shares(&session.id)?;
    Ok(json_value(
        StatusCode::OK,
        &json!({"id": session.id, "revoked": revoked}),
    ))
}

/// The session share link `token` was made for; an unknown or revoked link is 404.
fn shared_session(shared: &App, token: &str) -> Result<Session, Error> {
    let gone = || Error::NotFound("no such share link (revoked, or its session deleted)".into());
    let id = shared.db.shared_session(token)?.ok_or_else(gone)?;
    shared.session(&id).map_err(|_| gone())
}

/// `GET /share/{token}`: the report the link was made for; an unknown or revoked link is 404.
pub(crate) async fn view(
    State(shared): AppState,
    Path(token): Path<String>,
) -> Result<Response, Error> {
    let session = shared_session(&shared, &token)?;
    // The token is lower-case hex (checked by the lookup): safe in a URL path as it is.
    let base = format!("/share/{token}/");
    super::pages::report_answer(shared.clone(), session, base, false).await
}

/// `GET /share/{token}/{name}`: the shared session's 3-D scene data and downloads, by a
/// fixed list of names (the same answers as the owner's `/v1/sessions/{id}/{name}`).
pub(crate) async fn data(
    State(shared): AppState,
    Path((token, name)): Path<(String, String)>,
    query: RawQuery,
) -> Result<Response, Error> {
    let session = Found(shared_session(&shared, &token)?);
    let shared = State(shared);
    match name.as_str() {
        "scene.json" => super::scene::json(shared, session).await,
        "scene.glb" => super::scene::glb(shared, session).await,
        "trajectory.tum" => super::scene::trajectory(shared, session).await,
        "trials.zip" => super::scene::trials_zip(shared, session).await,
        "results.csv" => super::results::csv(shared, session).await,
        "results.json" => super::results::json(shared, session, query).await,
        // The report as one file that opens from disk (`report?download=1`).
        "report" => {
            let base = format!("/share/{token}/");
            super::pages::report_answer(shared.0, session.0, base, true).await
        }
        _ => Err(Error::NotFound(format!("a share link has no {name:?}"))),
    }
}

/// `GET /share/{token}/subtrajectories/{k}/image.jpg`: a thumbnail of the shared session.
pub(crate) async fn image(
    State(shared): AppState,
    Path((token, k)): Path<(String, String)>,
) -> Result<Response, Error> {
    let session = shared_session(&shared, &token)?;
    let none = || Error::NotFound(format!("the shared session has no image {k:?}"));
    let k: usize = k
        .parse()
        .ok()
        .filter(|k| *k < MAX_SUBTRAJECTORIES)
        .ok_or_else(none)?;
    let jpeg = EvidenceFiles {
        blobs: &*shared.blobs,
        id: &session.id,
    }
    .read_thumbnail(k)?
    .ok_or_else(none)?;
    Ok(super::evidence::jpeg_response(jpeg))
}
