//! The HTML templates (minijinja), compiled into the binary. Templates named `*.html`
//! escape every value unless marked `|safe` (only server-made SVG is).

use std::sync::OnceLock;

use axum::http::header;
use axum::response::{Html, IntoResponse, Response};
use minijinja::Environment;

use crate::Error;

fn environment() -> &'static Environment<'static> {
    static ENV: OnceLock<Environment<'static>> = OnceLock::new();
    ENV.get_or_init(|| {
        let mut env = Environment::new();
        for (name, source) in [
            ("report.html", include_str!("../../templates/report.html")),
            (
                "overview.html",
                include_str!("../../templates/overview.html"),
            ),
        ] {
            // A template that does not compile is a bug caught by every test of the pages.
            if let Err(e) = env.add_template(name, source) {
                log::error!("template {name}: {e}");
            }
        }
        env
    })
}

/// Renders template `name` with `context`.
pub(crate) fn render(name: &str, context: &serde_json::Value) -> Result<String, Error> {
    environment()
        .get_template(name)
        .and_then(|t| t.render(context))
        .map_err(|e| Error::Internal(format!("template {name}: {e}")))
}

/// The Content-Security-Policy of every HTML answer: scripts, styles, data only from this
/// backend; no inline script, no other origin, no framing.
pub(crate) const CSP: &str = "default-src 'none'; script-src 'self'; style-src 'self'; \
     img-src 'self' data:; connect-src 'self'; base-uri 'none'; form-action 'none'; \
     frame-ancestors 'none'";

/// An HTML answer with the page headers.
pub(crate) fn page(html: String) -> Response {
    (
        [
            (header::CONTENT_SECURITY_POLICY, CSP),
            (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
            (header::REFERRER_POLICY, "no-referrer"),
        ],
        Html(html),
    )
        .into_response()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_page_is_html_with_the_page_headers() {
        let response = page("<p>x</p>".to_owned());
        let headers = response.headers();
        assert_eq!(headers[header::CONTENT_TYPE], "text/html; charset=utf-8");
        assert_eq!(headers[header::CONTENT_SECURITY_POLICY], CSP);
        assert_eq!(headers[header::X_CONTENT_TYPE_OPTIONS], "nosniff");
        assert_eq!(headers[header::REFERRER_POLICY], "no-referrer");
    }

    #[test]
    fn client_strings_are_escaped_in_both_pages() {
        let hostile = "<script>alert(1)</script>\"'&\u{7}";
        let overview = render(
            "overview.html",
            &serde_json::json!({
                "playback": hostile,
                "sessions": [{"id": hostile, "state": "done", "setting": hostile, "note": hostile,
                              "played_by": [{"source": hostile, "trials": "0"}]}],
                "devices": [{"serial": hostile, "state": hostile, "session": hostile}],
                "devices_empty_reason": hostile,
            }),
        )
        .unwrap();
        let report = render(
            "report.html",
            &serde_json::json!({
                "id": hostile,
                "settings": [["Stop reason", hostile]],
                "regions": [{"rank": 1, "class": hostile, "thumbnail_url": hostile, "pictured": hostile,
                             "causes": [{"name": hostile, "reason": hostile, "count": 1}],
                             "markers": hostile, "subtrajectories": hostile}],
                "region_count": 1,
                "markers": [],
                "marker_count": 0,
                "has_evidence": true,
                "base": hostile,
                "source": hostile,
            }),
        )
        .unwrap();
        for page in [&overview, &report] {
            assert!(!page.contains("<script>alert"), "{page}");
            assert!(page.contains("&lt;script&gt;alert(1)&lt;"), "{page}");
            // No inline script at all: the only script is the module from /assets.
            assert_eq!(
                page.matches("<script").count(),
                page.matches("<script type=\"module\" src=\"/assets/report.bundle.js\">")
                    .count()
            );
        }
    }
}
