//! The HTML templates (minijinja), compiled into the binary. Templates named `*.html`
//! escape every value unless marked `|safe` (only server-made SVG is).

use std::sync::OnceLock;

use axum::http::header;
use axum::response::{Html, IntoResponse, Response};
use minijinja::Environment;

use crate::error::Error;

fn environment() -> &'static Environment<'static> {
    static ENV: OnceLock<Environment<'static>> = OnceLock::new();
    ENV.get_or_init(|| {
        let mut env = Environment::new();
        env.add_filter("plural", plural);
        for (name, source) in [
            ("report.html", include_str!("../../templates/report.html")),
            (
                "overview.html",
                include_str!("../../templates/overview.html"),
            ),
            ("waiting.html", include_str!("../../templates/waiting.html")),
            ("venue.html", include_str!("../../templates/venue.html")),
        ] {
            // A template that does not compile is a bug caught by every test of the pages.
            if let Err(e) = env.add_template(name, source) {
                log::error!("template {name}: {e}");
            }
        }
        env
    })
}

/// `{{ n|plural("pair") }}`: `1 pair`, `3 pairs`, `0 pairs`; an irregular plural is the
/// second argument (`{{ n|plural("match", "matches") }}`).
fn plural(n: Option<i64>, one: String, many: Option<String>) -> String {
    let n = n.unwrap_or(0);
    if n == 1 {
        format!("1 {one}")
    } else {
        format!("{n} {}", many.unwrap_or_else(|| format!("{one}s")))
    }
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

/// The Content-Security-Policy of a stand-alone report (`?download=1`, the demo's file): its
/// one inline script and style by their SHA-256 (`'sha256-…'`), images only inline, nothing
/// fetched. Sent as a header with the download and kept in the file's `<meta>`, so it holds
/// when the file is opened from disk (`frame-ancestors` only works as a header).
pub(crate) fn standalone_csp(script_hash: &str, style_hash: &str) -> String {
    format!(
        "default-src 'none'; script-src {script_hash}; style-src {style_hash}; \
         img-src data:; base-uri 'none'; form-action 'none'"
    )
}

/// A page to save rather than show (`?download=1`): `file_name`, with its own `csp`.
pub(crate) fn attachment_page(html: String, file_name: &str, csp: &str) -> Response {
    let csp = format!("{csp}; frame-ancestors 'none'");
    let disposition = format!("attachment; filename=\"{file_name}\"");
    (
        [
            (header::CONTENT_SECURITY_POLICY, csp),
            (header::CONTENT_DISPOSITION, disposition),
            (header::X_CONTENT_TYPE_OPTIONS, "nosniff".to_owned()),
            (header::REFERRER_POLICY, "no-referrer".to_owned()),
        ],
        Html(html),
    )
        .into_response()
}

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
    fn plurals() {
        assert_eq!(plural(Some(1), "pair".into(), None), "1 pair");
        assert_eq!(plural(Some(0), "pair".into(), None), "0 pairs");
        assert_eq!(
            plural(
                Some(45),
                "sub-trajectory".into(),
                Some("sub-trajectories".into())
            ),
            "45 sub-trajectories"
        );
        let env = environment();
        let text = env
            .render_str(
                "{{ 1|plural('trial') }}, {{ 2|plural('trial') }}",
                serde_json::json!({}),
            )
            .unwrap();
        assert_eq!(text, "1 trial, 2 trials");
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
        let waiting = render(
            "waiting.html",
            &serde_json::json!({"id": hostile, "state": hostile, "waiting_for": hostile,
                                "error": hostile, "is_failure": true, "played": 1, "total": 3}),
        )
        .unwrap();
        // A stand-alone page: its two inline scripts are the bundle and the scene data, and
        // client strings in the page (not the scene, escaped by report.rs) stay escaped.
        let mut context = serde_json::json!({
            "id": hostile, "settings": [["Stop reason", hostile]], "regions": [], "markers": [],
            "partial": {"trials": 2, "total": 8, "state": hostile},
            "standalone": {"css": "body{}", "script": "let x = 1;", "scene": "{}", "csp": hostile},
        });
        let standalone = render("report.html", &context).unwrap();
        assert!(!standalone.contains("<script>alert"), "{standalone}");
        assert!(standalone.contains("&lt;script&gt;alert(1)&lt;"));
        assert_eq!(standalone.matches("<script").count(), 2);
        assert!(standalone.contains("<script type=\"module\">let x = 1;</script>"));
        assert!(standalone.contains("This copy was saved before the estimate was final."));
        assert!(!standalone.contains("http-equiv=\"refresh\""));
        assert!(!standalone.contains("/assets/"));
        context["standalone"] = serde_json::Value::Null;
        let served = render("report.html", &context).unwrap();
        // The served partial page reloads itself.
        assert!(served.contains("<meta http-equiv=\"refresh\""), "{served}");
        assert!(served.contains("This page reloads every"));
        // The venue page: client strings escaped; its one script the bundle, its view data a
        // JSON block (server-made, `<` written as `\u003c`).
        let venue = render(
            "venue.html",
            &serde_json::json!({"id": "v1", "name": hostile, "anchor": hostile,
                "sessions": [{"id": hostile, "reason": hostile, "aligned": false}],
                "regions": [], "coverage": [], "view": "{}", "topview": "<svg></svg>"}),
        )
        .unwrap();
        assert!(!venue.contains("<script>alert"), "{venue}");
        assert!(venue.contains("&lt;script&gt;alert(1)&lt;"), "{venue}");
        assert_eq!(venue.matches("<script").count(), 2, "{venue}");
        assert!(venue.contains("<script type=\"application/json\" id=\"venue-data\">{}</script>"));
        for page in [&overview, &report, &waiting] {
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
