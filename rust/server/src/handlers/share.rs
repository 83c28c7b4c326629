//! Read-only share links of one session's report: `POST /v1/sessions/{id}/share` makes one
//! (a URL with its own random token, stored hashed), `DELETE /v1/sessions/{id}/share` revokes
//! every link of the session, and `GET /share/{token}` opens the report without an account.

use axum::extract::{Path, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::Response;
use serde_json::json;

use crate::Error;
use crate::auth::new_token;
use crate::http::{AppState, Found, json_value};

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

/// `GET /share/{token}`: the report the link was made for; an unknown or revoked link is 404.
pub(crate) async fn view(
    State(shared): AppState,
    Path(token): Path<String>,
) -> Result<Response, Error> {
    let gone = || Error::NotFound("no such share link (revoked, or its session deleted)".into());
    let id = shared.db.shared_session(&token)?.ok_or_else(gone)?;
    let session = shared.session(&id).map_err(|_| gone())?;
    let html = super::pages::render_report(shared.clone(), session).await?;
    Ok(crate::templates::page(html))
}
