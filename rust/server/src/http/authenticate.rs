//! The authentication middleware: finds the caller of every request (or answers 401), turns a
//! page visit with `?token=` into a cookie and a redirect, and names the caller to the request
//! log.

use std::sync::Arc;

use axum::extract::{Request, State};
use axum::http::{HeaderValue, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

use crate::app_state::App;
use crate::auth::secret::{self, COOKIE_NAME};
use crate::error::Error;
use crate::model::Caller;

/// The caller's name, put on the response for the request log.
#[derive(Debug, Clone)]
pub(crate) struct CallerName(pub String);

/// Routes open to everyone: the health check, share links (their own token is the path),
/// and the pages' vendored scripts and styles (a fixed table in the binary, no session data),
/// which a share link's page loads without a cookie.
fn is_open(path: &str) -> bool {
    path == "/healthz" || path.starts_with("/share/") || path.starts_with("/assets/")
}

/// The HTML pages (the overview, a session's and a venue's report), which take `?token=`
/// once and then live on the cookie.
fn is_page(method: &Method, path: &str) -> bool {
    let report_of = |prefix: &str| {
        path.strip_prefix(prefix)
            .and_then(|rest| rest.strip_suffix("/report"))
            .is_some_and(|id| !id.is_empty() && !id.contains('/'))
    };
    method == Method::GET && (path == "/" || report_of("/v1/sessions/") || report_of("/v1/venues/"))
}

/// The original Unity app's routes: it can only add `?token=` to its hard-coded address.
fn is_legacy(path: &str) -> bool {
    matches!(path, "/recording" | "/timestamps" | "/results.csv")
}

pub(crate) async fn authenticate(
    State(shared): State<Arc<App>>,
    mut request: Request,
    next: Next,
) -> Response {
    if is_open(request.uri().path()) {
        return next.run(request).await;
    }
    let caller = if shared.config.insecure_no_auth {
        Caller::Open
    } else {
        match identify(&shared, &request) {
            Ok(Found::Caller(caller)) => caller,
            Ok(Found::PageVisit(token)) => return redirect_with_cookie(&shared, &request, token),
            Err(e) => return e.into_response(),
        }
    };
    if let Err(e) = worker_stays_in_its_routes(&caller, request.uri().path()) {
        return e.into_response();
    }
    let name = caller.name().to_owned();
    request.extensions_mut().insert(caller);
    let mut response = next.run(request).await;
    response.extensions_mut().insert(CallerName(name));
    response
}

/// The playback hosts' routes: the only ones a worker token may use.
pub(crate) const WORKER_ROUTES: &str = "/v1/worker/";

/// A worker token may use the worker routes and nothing else (403 elsewhere); the worker
/// routes' own extractor refuses every other token.
fn worker_stays_in_its_routes(caller: &Caller, path: &str) -> Result<(), Error> {
    match caller {
        Caller::Token {
            role: crate::model::Role::Worker,
            name,
            ..
        } if !path.starts_with(WORKER_ROUTES) => Err(Error::Forbidden(format!(
            "token {name:?} has the worker role: it may use only the {WORKER_ROUTES} routes"
        ))),
        _ => Ok(()),
    }
}

enum Found<'a> {
    Caller(Caller),
    /// A page opened with a valid `?token=`: set the cookie, redirect.
    PageVisit(&'a str),
}

fn identify<'a>(shared: &App, request: &'a Request) -> Result<Found<'a>, Error> {
    let path = request.uri().path();
    let method = request.method();
    let query = request.uri().query().unwrap_or("");
    let unknown = || Error::Unauthorized("unknown or revoked token".into());
    if is_page(method, path) && secret::has_param(query, "token") {
        let token = secret::query_param(query, "token").ok_or_else(unknown)?;
        shared.db.caller(token)?.ok_or_else(unknown)?;
        return Ok(Found::PageVisit(token));
    }
    let headers = request.headers();
    let presented = if let Some(value) = headers.get(header::AUTHORIZATION) {
        let value = value.to_str().unwrap_or("");
        Some(secret::bearer(value).ok_or_else(|| {
            Error::Unauthorized("the Authorization header is not `Bearer TOKEN`".into())
        })?)
    } else if matches!(*method, Method::GET | Method::HEAD)
        && let Some(cookie) = headers
            .get_all(header::COOKIE)
            .iter()
            .filter_map(|v| v.to_str().ok())
            .find_map(|v| secret::cookie(v, COOKIE_NAME))
    {
        // Cookies only for reading: SameSite=Strict already keeps other sites' forms out,
        // and no write goes by a cookie at all.
        Some(cookie)
    } else if is_legacy(path) {
        secret::query_param(query, "token")
    } else {
        None
    };
    let token = presented.ok_or_else(|| {
        Error::Unauthorized("no token: send `Authorization: Bearer TOKEN`".into())
    })?;
    shared
        .db
        .caller(token)?
        .map(Found::Caller)
        .ok_or_else(unknown)
}

/// 303 to the same page without `token=`, setting the HttpOnly, SameSite=Strict cookie.
fn redirect_with_cookie(shared: &App, request: &Request, token: &str) -> Response {
    let rest = secret::without_param(request.uri().query().unwrap_or(""), "token");
    let path = request.uri().path();
    let location = if rest.is_empty() {
        path.to_owned()
    } else {
        format!("{path}?{rest}")
    };
    let secure = if shared.secure_cookies {
        "; Secure"
    } else {
        ""
    };
    let cookie = format!("{COOKIE_NAME}={token}; Path=/; HttpOnly; SameSite=Strict{secure}");
    let mut response = StatusCode::SEE_OTHER.into_response();
    let headers = response.headers_mut();
    if let (Ok(location), Ok(cookie)) = (
        HeaderValue::from_str(&location),
        HeaderValue::from_str(&cookie),
    ) {
        headers.insert(header::LOCATION, location);
        headers.insert(header::SET_COOKIE, cookie);
        headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
        response
    } else {
        Error::BadRequest("the page address cannot be redirected to".into()).into_response()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pages_legacy_and_open_routes_are_told_apart() {
        assert!(is_page(&Method::GET, "/"));
        assert!(is_page(&Method::GET, "/v1/sessions/s0123/report"));
        assert!(!is_page(&Method::GET, "/v1/sessions/s0123/x/report"));
        assert!(is_page(&Method::GET, "/v1/venues/v0123/report"));
        assert!(!is_page(&Method::GET, "/v1/venues/v0123/map.json"));
        assert!(!is_page(&Method::GET, "/v1/venues//report"));
        assert!(!is_page(&Method::POST, "/"));
        assert!(!is_page(&Method::GET, "/v1/sessions"));
        assert!(is_legacy("/results.csv"));
        assert!(!is_legacy("/v1/sessions/s0/results.csv"));
        assert!(is_open("/healthz"));
        assert!(is_open("/share/sitar_x"));
        assert!(!is_open("/healthz/x"));
        assert!(is_open("/assets/report.js"));
        assert!(!is_open("/v1/sessions/s0/assets/x"));
    }

    #[test]
    fn a_worker_token_stays_in_the_worker_routes() {
        let worker = Caller::Token {
            id: 1,
            name: "host-1".into(),
            role: crate::model::Role::Worker,
        };
        assert!(worker_stays_in_its_routes(&worker, "/v1/worker/hosts").is_ok());
        for path in [
            "/",
            "/v1/sessions",
            "/v1/devices",
            "/v1/workers",
            "/results.csv",
        ] {
            let err = worker_stays_in_its_routes(&worker, path).unwrap_err();
            assert_eq!(err.status_and_code().1, "forbidden", "{path}: {err}");
            assert!(err.to_string().contains("host-1"), "{err}");
        }
        let app = Caller::Token {
            id: 2,
            name: "phone".into(),
            role: crate::model::Role::App,
        };
        assert!(worker_stays_in_its_routes(&app, "/v1/sessions").is_ok());
    }
}
