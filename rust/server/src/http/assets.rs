//! `GET /assets/{name}`: the pages' scripts and styles, compiled into the binary, so the pages
//! work on a LAN with no internet. The report's script is `report.bundle.js`: `report.js`
//! with the parts of three.js it uses (vendored at the version pinned in `tools/npm`),
//! bundled and minified by `scripts/vendor-three`. Names come from this fixed table, never
//! from the path.

use axum::extract::Path;
use axum::http::header;
use axum::response::{IntoResponse, Response};

use crate::error::Error;

const JS: &str = "text/javascript; charset=utf-8";

/// (name, content type, bytes).
const ASSETS: &[(&str, &str, &[u8])] = &[
    (
        "report.bundle.js",
        JS,
        include_bytes!("../../assets/report.bundle.js"),
    ),
    (
        "site.css",
        "text/css; charset=utf-8",
        include_bytes!("../../assets/site.css"),
    ),
    (
        "three/LICENSE",
        "text/plain; charset=utf-8",
        include_bytes!("../../assets/three/LICENSE"),
    ),
];

/// `GET /assets/{*name}`.
pub(crate) async fn get(Path(name): Path<String>) -> Result<Response, Error> {
    let (_, content_type, bytes) = ASSETS
        .iter()
        .find(|(n, _, _)| *n == name)
        .ok_or_else(|| Error::NotFound(format!("no asset {name:?}")))?;
    Ok((
        [
            (header::CONTENT_TYPE, *content_type),
            // The assets change only with the binary; an hour keeps reloads off the network.
            (header::CACHE_CONTROL, "public, max-age=3600"),
            (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
        ],
        *bytes,
    )
        .into_response())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn an_asset_has_its_type_and_cache_headers_and_an_unknown_name_is_404() {
        let response = get(Path("site.css".to_owned())).await.unwrap();
        let headers = response.headers();
        assert_eq!(headers[header::CONTENT_TYPE], "text/css; charset=utf-8");
        assert_eq!(headers[header::CACHE_CONTROL], "public, max-age=3600");
        assert_eq!(headers[header::X_CONTENT_TYPE_OPTIONS], "nosniff");
        let e = get(Path("../Cargo.toml".to_owned())).await.unwrap_err();
        assert!(matches!(e, Error::NotFound(_)), "{e}");
    }
}
