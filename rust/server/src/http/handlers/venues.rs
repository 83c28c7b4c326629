//! The venue resource: `POST /v1/venues`, `GET /v1/venues[?limit=N]`,
//! `GET|DELETE /v1/venues/{id}`, `PUT|DELETE /v1/venues/{id}/members/{token_name}`.
//!
//! A venue belongs to the token that made it; admins see all; its owner grants other tokens
//! membership. Anyone else gets the 404 of a venue that does not exist; a member asking
//! for what only the owner may do gets a 403.

use axum::extract::{Path, RawQuery, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Deserialize;
use serde_json::{Value, json};

use crate::app_state::App;
use crate::error::Error;
use crate::error::short;
use crate::http::helpers::{
    AppState, blocking, check_declared_length, content_type, json_value, visible_venue,
};
use crate::http::pagination::list_limit;
use crate::model::{
    CELL_M_RANGE, Caller, DEFAULT_CELL_M, MAX_NAME_CHARS, NewVenue, Venue, check_token_name,
};
use crate::storage::body_stream;
use crate::venue::Standing;

/// The largest `POST /v1/venues` body.
const MAX_REQUEST_BYTES: u64 = 16 * 1024;
/// How much of a client's input an error message quotes at most.
const QUOTE_LIMIT: usize = 200;

/// The JSON body of `POST /v1/venues`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CreateRequest {
    name: String,
    anchor: String,
    #[serde(default)]
    cell_m: Option<f64>,
}

/// The body as a typed request; errors name the key (400 for the JSON's shape).
fn parse_create_request(body: &[u8]) -> Result<CreateRequest, Error> {
    let mut de = serde_json::Deserializer::from_slice(body);
    let req: CreateRequest = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let inner = short(&e.inner().to_string(), QUOTE_LIMIT);
        // serde names a missing key only in its message: put it first, as any other key.
        let key = match inner.strip_prefix("missing field `") {
            Some(rest) => rest.split('`').next().unwrap_or(".").to_owned(),
            None => e.path().to_string(),
        };
        match key.as_str() {
            "." => Error::BadRequest(format!("venue request: {inner}")),
            _ => Error::BadRequest(format!("{}: {inner}", short(&key, QUOTE_LIMIT))),
        }
    })?;
    de.end()
        .map_err(|e| Error::BadRequest(format!("venue request: after the JSON object: {e}")))?;
    Ok(req)
}

/// Checks the values of a venue request; a value out of range is a 422 naming its key.
fn check_values(req: &CreateRequest) -> Result<f64, Error> {
    let name = req.name.trim();
    if name.is_empty() || req.name.chars().count() > MAX_NAME_CHARS {
        return Err(Error::InvalidContent(format!(
            "name: must have 1 to {MAX_NAME_CHARS} characters"
        )));
    }
    if let Some(c) = req.name.chars().find(|c| c.is_control()) {
        return Err(Error::InvalidContent(format!(
            "name: contains the control character {c:?}"
        )));
    }
    sitar_core::venue::check_anchor_id(&req.anchor).map_err(|e| {
        Error::InvalidContent(format!("anchor: {}", short(&e.to_string(), QUOTE_LIMIT)))
    })?;
    let cell_m = req.cell_m.unwrap_or(DEFAULT_CELL_M);
    if !CELL_M_RANGE.contains(&cell_m) {
        return Err(Error::InvalidContent(format!(
            "cell_m: {cell_m} is not in {}..={} (metres)",
            CELL_M_RANGE.start(),
            CELL_M_RANGE.end()
        )));
    }
    Ok(cell_m)
}

/// `POST /v1/venues` → 201 `{"id"}`.
pub(crate) async fn create(
    State(shared): AppState,
    caller: Caller,
    headers: HeaderMap,
    body: axum::body::Body,
) -> Result<Response, Error> {
    let ct = content_type(&headers);
    if !matches!(
        ct.as_str(),
        "application/json" | "" | crate::http::helpers::CURL_DEFAULT_CONTENT_TYPE
    ) {
        return Err(Error::UnsupportedMediaType(format!(
            "POST /v1/venues takes application/json, not {}",
            short(&ct, QUOTE_LIMIT)
        )));
    }
    check_declared_length(&headers, MAX_REQUEST_BYTES, "venue request")?;
    let body = shared
        .blobs
        .receive_bytes(
            body_stream(body.into_data_stream()),
            MAX_REQUEST_BYTES,
            "venue request",
        )
        .await?;
    let req = parse_create_request(&body)?;
    let cell_m = check_values(&req)?;
    let id = shared.create_venue(&NewVenue {
        name: &req.name,
        anchor: &req.anchor,
        cell_m,
        owner: caller.owner(),
    })?;
    Ok((
        StatusCode::CREATED,
        [(header::LOCATION, format!("/v1/venues/{id}"))],
        axum::Json(json!({"id": id})),
    )
        .into_response())
}

/// A venue as its routes answer it: what it is, how the caller stands to it, its sessions'
/// convention and count, and the caller's own sessions in it (an admin's: all).
fn venue_json(
    shared: &App,
    caller: &Caller,
    venue: &Venue,
    standing: Standing,
) -> Result<Value, Error> {
    let sessions = shared.db.venue_sessions(&venue.id)?;
    let yours: Vec<&str> = sessions
        .iter()
        .filter(|s| caller.may_see(s))
        .map(|s| s.id.as_str())
        .collect();
    Ok(json!({
        "id": venue.id,
        "name": venue.name,
        "anchor": venue.anchor,
        "cell_m": venue.cell_m,
        "role": match standing {
            Standing::Admin => "admin",
            Standing::Owner => "owner",
            Standing::Member => "member",
        },
        "convention": sessions.first().map(|s| s.convention.name()),
        "session_count": sessions.len(),
        "sessions": yours,
    }))
}

/// `GET /v1/venues[?limit=N]`: the caller's venues (owned and member of; an admin's: all),
/// newest first.
pub(crate) async fn list(
    State(shared): AppState,
    caller: Caller,
    RawQuery(query): RawQuery,
) -> Result<Response, Error> {
    let limit = list_limit(query.as_deref())?;
    let venues = shared.db.venues_for(caller.scope(), limit)?;
    let mut out = Vec::with_capacity(venues.len());
    for venue in &venues {
        if let Some(standing) = Standing::of(&*shared.db, &caller, venue)? {
            out.push(venue_json(&shared, &caller, venue, standing)?);
        }
    }
    Ok(json_value(StatusCode::OK, &json!({"venues": out})))
}

/// `GET /v1/venues/{id}`; its owner and admins also see the members' token names.
pub(crate) async fn get(
    State(shared): AppState,
    caller: Caller,
    Path(id): Path<String>,
) -> Result<Response, Error> {
    let (venue, standing) = visible_venue(&shared, &caller, &id)?;
    let mut doc = venue_json(&shared, &caller, &venue, standing)?;
    if standing.manages() {
        doc["members"] = shared.db.members(&venue.id)?.into();
    }
    Ok(json_value(StatusCode::OK, &doc))
}

/// `?min_sessions=N` (1 … 100 000, default 1); anything else is a 400 naming the parameter.
fn min_sessions(query: Option<&str>) -> Result<u32, Error> {
    let mut n = 1;
    for pair in query.unwrap_or("").split('&').filter(|p| !p.is_empty()) {
        let (key, value) = pair.split_once('=').unwrap_or((pair, ""));
        if key != "min_sessions" {
            return Err(Error::BadRequest(format!(
                "unknown query parameter {:?}: only min_sessions is known",
                short(key, QUOTE_LIMIT)
            )));
        }
        n = value
            .parse()
            .ok()
            .filter(|n| (1..=100_000).contains(n))
            .ok_or_else(|| {
                Error::BadRequest(format!(
                    "min_sessions {:?} is not a whole number from 1 to 100000",
                    short(value, QUOTE_LIMIT)
                ))
            })?;
    }
    Ok(n)
}

/// `GET /v1/venues/{id}/map.json[?min_sessions=N]`: the venue map (sitar-core's
/// `VenueMap`), built from its sessions' files now.
pub(crate) async fn map_json(
    State(shared): AppState,
    caller: Caller,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
) -> Result<Response, Error> {
    let min_sessions = min_sessions(query.as_deref())?;
    let (venue, _) = visible_venue(&shared, &caller, &id)?;
    let map = blocking("venue map", move || {
        crate::venue::map::venue_map(&*shared.db, &*shared.blobs, &venue, min_sessions)
    })
    .await?;
    let value = serde_json::to_value(&map).map_err(|e| Error::Internal(format!("map: {e}")))?;
    Ok(json_value(StatusCode::OK, &value))
}

/// Most cells `map.glb` holds: one glTF node each (~250 bytes), so at most ~50 MB.
pub(crate) const MAX_GLB_CELLS: usize = 200_000;

/// `GET /v1/venues/{id}/map.glb[?min_sessions=N]`: the venue map as glTF 2.0 binary
/// (`sitar_scene::venue_to_glb`: one named node per cell, for Unity and Blender), built
/// from its sessions' files now, as `map.json`. A map of more than [`MAX_GLB_CELLS`] cells
/// is a 409 that says to raise `min_sessions`.
pub(crate) async fn map_glb(
    State(shared): AppState,
    caller: Caller,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
) -> Result<Response, Error> {
    let min_sessions = min_sessions(query.as_deref())?;
    let (venue, _) = visible_venue(&shared, &caller, &id)?;
    let glb = blocking("venue map.glb", move || {
        let map = crate::venue::map::venue_map(&*shared.db, &*shared.blobs, &venue, min_sessions)?;
        if map.cells.len() > MAX_GLB_CELLS {
            return Err(Error::Conflict(format!(
                "venue {}: the map has {} cells with min_sessions={min_sessions}; map.glb holds at \
                 most {MAX_GLB_CELLS}: ask with a higher min_sessions",
                venue.id,
                map.cells.len()
            )));
        }
        sitar_scene::venue_to_glb(&map)
            .map_err(|e| Error::Internal(format!("venue {}: map.glb: {e}", venue.id)))
    })
    .await?;
    Ok(crate::http::helpers::attachment(
        "model/gltf-binary",
        &format!("venue-{id}.glb"),
        glb,
    ))
}

/// `GET /v1/venues/{id}/report[?download=1]`: the venue's page (`crate::report::venue_page`);
/// with `download=1` the same page as one file that opens from disk.
pub(crate) async fn report(
    State(shared): AppState,
    caller: Caller,
    Path(id): Path<String>,
    RawQuery(query): RawQuery,
) -> Result<Response, Error> {
    let download = query.as_deref().unwrap_or("").split('&').any(|pair| {
        let (key, value) = pair.split_once('=').unwrap_or((pair, "1"));
        key == "download" && matches!(value, "1" | "true" | "yes")
    });
    let (venue, _) = visible_venue(&shared, &caller, &id)?;
    let html = blocking("venue report", move || {
        crate::report::venue_page::VenueReport {
            db: &*shared.db,
            blobs: &*shared.blobs,
            venue: &venue,
            caller: &caller,
            standalone: download,
        }
        .render()
    })
    .await?;
    Ok(if download {
        crate::report::templates::attachment_page(
            html,
            &format!("venue-{id}.html"),
            &crate::report::page::standalone_csp(),
        )
    } else {
        crate::report::templates::page(html)
    })
}

/// The venue, if the caller may manage it (a member: 403; anyone else: 404).
fn managed(shared: &App, caller: &Caller, id: &str) -> Result<Venue, Error> {
    let (venue, standing) = visible_venue(shared, caller, id)?;
    if standing.manages() {
        Ok(venue)
    } else {
        Err(Error::Forbidden(format!(
            "token {:?} is a member of venue {id}; only its owner or an admin may change it",
            caller.name()
        )))
    }
}

/// `DELETE /v1/venues/{id}` → 200 `{"id","deleted":true}`; its sessions stay, in no venue.
pub(crate) async fn delete(
    State(shared): AppState,
    caller: Caller,
    Path(id): Path<String>,
) -> Result<Response, Error> {
    let venue = managed(&shared, &caller, &id)?;
    if !shared.db.delete_venue(&venue.id)? {
        return Err(Error::NotFound(format!("no venue {id:?}")));
    }
    Ok(json_value(
        StatusCode::OK,
        &json!({"id": venue.id, "deleted": true}),
    ))
}

/// The 404 of a token name no token has.
fn unknown_token(name: &str) -> Error {
    Error::NotFound(format!("no token named {:?}", short(name, QUOTE_LIMIT)))
}

/// `PUT /v1/venues/{id}/members/{token_name}` → 200 `{"id","member"}`.
pub(crate) async fn add_member(
    State(shared): AppState,
    caller: Caller,
    Path((id, name)): Path<(String, String)>,
) -> Result<Response, Error> {
    let venue = managed(&shared, &caller, &id)?;
    if check_token_name(&name).is_err() || !shared.db.add_member(&venue.id, &name)? {
        return Err(unknown_token(&name));
    }
    Ok(json_value(
        StatusCode::OK,
        &json!({"id": venue.id, "member": name}),
    ))
}

/// `DELETE /v1/venues/{id}/members/{token_name}` → 200 `{"id","member","removed"}`
/// (`removed` false when it was no member).
pub(crate) async fn remove_member(
    State(shared): AppState,
    caller: Caller,
    Path((id, name)): Path<(String, String)>,
) -> Result<Response, Error> {
    let venue = managed(&shared, &caller, &id)?;
    let removed = match check_token_name(&name) {
        Ok(()) => shared.db.remove_member(&venue.id, &name)?,
        Err(_) => None,
    }
    .ok_or_else(|| unknown_token(&name))?;
    Ok(json_value(
        StatusCode::OK,
        &json!({"id": venue.id, "member": name, "removed": removed}),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn values(body: &str) -> Result<f64, Error> {
        check_values(&parse_create_request(body.as_bytes())?)
    }

    #[test]
    fn a_venue_request_is_checked_key_by_key() {
        assert_eq!(
            values(r#"{"name":"Lobby","anchor":"poster-1"}"#).unwrap(),
            0.25
        );
        assert_eq!(
            values(r#"{"name":"Lobby","anchor":"a","cell_m":2}"#).unwrap(),
            2.0
        );
        for (body, status, key) in [
            (r#"{"name":"L","anchor":"a","cell_m":0.01}"#, 422, "cell_m"),
            (r#"{"name":"L","anchor":"a","cell_m":2.5}"#, 422, "cell_m"),
            (r#"{"name":"L","anchor":"a,b"}"#, 422, "anchor"),
            (r#"{"name":"L","anchor":""}"#, 422, "anchor"),
            (r#"{"name":"  ","anchor":"a"}"#, 422, "name"),
            (r#"{"name":"L","anchor":"a","colour":1}"#, 400, "colour"),
            (r#"{"name":"L","anchor":"a","cell_m":"big"}"#, 400, "cell_m"),
            (r#"{"anchor":"a"}"#, 400, "name"),
            (
                r#"{"name":"L","anchor":"a"}x"#,
                400,
                "after the JSON object",
            ),
        ] {
            let e = values(body).unwrap_err();
            assert_eq!(e.status_and_code().0.as_u16(), status, "{body}: {e}");
            assert!(e.to_string().contains(key), "{body}: {e}");
        }
    }
}
