//! The route table and the middleware stack, and nothing else: handlers live in
//! `handlers/`, one file per resource.

use std::sync::Arc;

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::http::StatusCode;
use axum::response::Response;
use axum::routing::{get, post, put};

use crate::app_state::App;
use crate::error::Error;
use crate::http::authenticate::{self, CallerName};
use crate::http::handlers::{
    devices, evidence, health, legacy, pages, phone_log, recording, results, scene, sessions,
    share, trials, venues, worker,
};
use crate::http::helpers::json_response;
use crate::http::upload_limits;

pub(crate) fn router(shared: Arc<App>) -> Router {
    Router::new()
        .route("/healthz", get(health::get))
        .route("/", get(pages::overview))
        // Browsers ask for it on every refresh of the page; no icon, no log noise.
        .route("/favicon.ico", get(|| async { StatusCode::NO_CONTENT }))
        .route("/v1/sessions", post(sessions::create).get(sessions::list))
        .route(
            "/v1/sessions/{id}",
            get(sessions::status).delete(sessions::delete),
        )
        .route(
            "/v1/sessions/{id}/recording",
            put(recording::put_recording).head(recording::kept_offset),
        )
        .route("/v1/sessions/{id}/cancel", post(sessions::cancel))
        .route("/v1/sessions/{id}/trials", post(trials::post))
        .route("/v1/sessions/{id}/estimate", post(results::estimate))
        .route("/v1/sessions/{id}/results.csv", get(results::csv))
        .route("/v1/sessions/{id}/results.json", get(results::json))
        .route("/v1/sessions/{id}/report", get(pages::report))
        .route(
            "/v1/sessions/{id}/evidence.csv",
            put(evidence::put_evidence),
        )
        .route(
            "/v1/sessions/{id}/subtrajectories.csv",
            put(evidence::put_spans),
        )
        .route(
            "/v1/sessions/{id}/trajectory.txt",
            put(phone_log::put_trajectory),
        )
        .route("/v1/sessions/{id}/anchors.csv", put(phone_log::put_anchors))
        .route("/v1/sessions/{id}/walk.txt", put(phone_log::put_walk))
        .route("/v1/sessions/{id}/subtrajectories", get(evidence::list))
        .route(
            "/v1/sessions/{id}/subtrajectories/{k}/image.jpg",
            put(evidence::put_image).get(evidence::get_image),
        )
        .route(
            "/v1/sessions/{id}/share",
            post(share::create).delete(share::revoke),
        )
        .route("/share/{token}", get(share::view))
        .route("/share/{token}/{name}", get(share::data))
        .route(
            "/share/{token}/subtrajectories/{k}/image.jpg",
            get(share::image),
        )
        .route("/v1/sessions/{id}/scene.glb", get(scene::glb))
        .route("/v1/sessions/{id}/scene.json", get(scene::json))
        .route("/v1/sessions/{id}/trajectory.tum", get(scene::trajectory))
        .route("/v1/sessions/{id}/trials.zip", get(scene::trials_zip))
        .route("/v1/venues", post(venues::create).get(venues::list))
        .route("/v1/venues/{id}", get(venues::get).delete(venues::delete))
        .route("/v1/venues/{id}/map.json", get(venues::map_json))
        .route("/v1/venues/{id}/map.glb", get(venues::map_glb))
        .route("/v1/venues/{id}/report", get(venues::report))
        .route(
            "/v1/venues/{id}/members/{token_name}",
            put(venues::add_member).delete(venues::remove_member),
        )
        .route("/assets/{*name}", get(crate::http::assets::get))
        .route("/v1/devices", get(devices::list))
        // Playback hosts (`sitar worker`; worker tokens only, and they nothing else).
        .route("/v1/worker/hosts", post(worker::register))
        .route("/v1/worker/hosts/{host}/heartbeat", post(worker::heartbeat))
        .route("/v1/worker/hosts/{host}/leases", post(worker::claim))
        .route(
            "/v1/worker/hosts/{host}/leases/{lease}/recording",
            get(worker::recording),
        )
        .route(
            "/v1/worker/hosts/{host}/leases/{lease}/trial",
            put(worker::trial),
        )
        .route(
            "/v1/worker/hosts/{host}/leases/{lease}/failure",
            post(worker::failure),
        )
        .route("/recording", post(legacy::recording))
        .route("/timestamps", post(legacy::timestamps))
        .route("/results.csv", get(legacy::results))
        .fallback(|| async { Error::NotFound("no such route".into()) })
        .method_not_allowed_fallback(|| async {
            json_response(
                StatusCode::METHOD_NOT_ALLOWED,
                &crate::error::error_body("method_not_allowed", "method not allowed on this route"),
            )
        })
        // Middleware, innermost first. Body limits are ours, per route, checked while
        // streaming.
        .layer(DefaultBodyLimit::disable())
        .layer(axum::middleware::from_fn_with_state(
            shared.clone(),
            crate::http::request_limits::bound_bodies,
        ))
        .layer(axum::middleware::from_fn_with_state(
            shared.clone(),
            upload_limits::limit_uploads,
        ))
        .layer(axum::middleware::from_fn_with_state(
            shared.clone(),
            authenticate::authenticate,
        ))
        .layer(axum::middleware::from_fn(
            crate::http::json_errors::json_rejections,
        ))
        .layer(axum::middleware::from_fn(log_request))
        .with_state(shared)
}

/// One log line per request: method, path (server-made ids only, no query, share tokens
/// hidden), the caller's token name (never the token), status, time.
/// Successful `GET`/`HEAD`s log at debug: phones poll their status every half second.
async fn log_request(request: axum::extract::Request, next: axum::middleware::Next) -> Response {
    let method = request.method().clone();
    let path = match request.uri().path() {
        p if p.starts_with("/share/") => "/share/…".to_owned(),
        p => p.to_owned(),
    };
    let started = std::time::Instant::now();
    let response = next.run(request).await;
    let status = response.status();
    let caller = response
        .extensions()
        .get::<CallerName>()
        .map_or("-", |c| c.0.as_str());
    let quiet =
        matches!(method, axum::http::Method::GET | axum::http::Method::HEAD) && status.is_success();
    let level = if quiet {
        log::Level::Debug
    } else {
        log::Level::Info
    };
    log::log!(
        level,
        "{method} {path} [{caller}] → {} in {:.1} ms",
        status.as_u16(),
        started.elapsed().as_secs_f64() * 1e3
    );
    response
}
