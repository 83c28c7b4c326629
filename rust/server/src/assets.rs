//! `GET /assets/{name}`: the pages' scripts and styles, compiled into the binary, so the pages
//! work on a LAN with no internet. The report's script is `report.bundle.js`: `report.js`
//! with the parts of three.js it uses (vendored at the version pinned in `tools/npm`),
//! bundled and minified by `scripts/vendor-three`. Names come from this fixed table, never
//! from the path.

use axum::extract::Path;
use axum::http::{HeaderValue, header};
use axum::response::{IntoResponse, Response};

use crate::Error;

const JS: &str = "text/javascript; charset=utf-8";

/// (name, content type, bytes).
const ASSETS: &[(&str, &str, &[u8])] = &[
    (
        "report.bundle.js",
        JS,
        include_bytes!("../assets/report.bundle.js"),
    ),
    (
        "site.css",
        "text/css; charset=utf-8",
        include_bytes!("../assets/site.css"),
    ),
    (
        "three/LICENSE",
        "text/plain; charset=utf-8",
        include_bytes!("../assets/three/LICENSE"),
    ),
];

/// `GET /assets/{*name}`.
pub(crate) async fn get(Path(name): Path<String>) -> Result<Response, Error> {
    let (_, content_type, bytes) = ASSETS
        .iter()
        .find(|(n, _, _)| *n == name)
        .ok_or_else(|| Error::NotFound(format!("no asset {name:?}")))?;
    let mut response = (*bytes).into_response();
    let headers = response.headers_mut();
    headers.insert(header::CONTENT_TYPE, HeaderValue::from_static(content_type));
    // The assets change only with the binary; an hour keeps reloads off the network.
    headers.insert(
        header::CACHE_CONTROL,
        HeaderValue::from_static("public, max-age=3600"),
    );
    headers.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    Ok(response)
}
