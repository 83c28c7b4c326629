//! `GET /healthz`.

use axum::http::StatusCode;
use axum::response::Response;

use crate::http::helpers::json_response;

pub(crate) async fn get() -> Response {
    json_response(StatusCode::OK, r#"{"status":"ok"}"#)
}
