//! What the server holds, at a glance: `GET /v1/sessions` (JSON) and `GET /`
//! (an HTML page for the person next to the playback phones, refreshed every
//! few seconds, linking every session's report and results).

use std::fmt::Write;
use std::sync::Arc;

use axum::extract::{RawQuery, State};
use axum::http::StatusCode;
use axum::response::{Html, IntoResponse, Response};
use serde_json::json;

use crate::Error;
use crate::report::escape;
use crate::routes::{json_response, status_json};
use crate::state::Shared;

const DEFAULT_LIMIT: u32 = 50;
const MAX_LIMIT: u32 = 500;

/// `?limit=N` (1 … 500, default 50); anything else is a 400 naming the parameter.
fn limit(query: Option<&str>) -> Result<u32, Error> {
    let mut limit = DEFAULT_LIMIT;
    for pair in query.unwrap_or("").split('&').filter(|p| !p.is_empty()) {
        let (key, value) = pair.split_once('=').unwrap_or((pair, ""));
        if key != "limit" {
            return Err(Error::BadRequest(format!(
                "unknown query parameter {key:?}: only limit is known"
            )));
        }
        limit = value
            .parse()
            .ok()
            .filter(|n| (1..=MAX_LIMIT).contains(n))
            .ok_or_else(|| {
                Error::BadRequest(format!(
                    "limit {value:?} is not a whole number from 1 to {MAX_LIMIT}"
                ))
            })?;
    }
    Ok(limit)
}

/// `GET /v1/sessions[?limit=N]`: the newest sessions, newest first, each as its status.
pub(crate) async fn list(
    State(shared): State<Arc<Shared>>,
    RawQuery(query): RawQuery,
) -> Result<Response, Error> {
    let limit = limit(query.as_deref())?;
    let sessions = shared
        .db
        .recent_sessions(limit)?
        .iter()
        .map(|row| status_json(&shared, row))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(json_response(
        StatusCode::OK,
        &json!({"sessions": sessions}).to_string(),
    ))
}

/// `GET /`: the newest sessions and the known playback devices as one HTML page.
pub(crate) async fn page(State(shared): State<Arc<Shared>>) -> Result<Response, Error> {
    let rows = shared.db.recent_sessions(DEFAULT_LIMIT)?;
    let mut sessions = String::new();
    for row in &rows {
        let status = status_json(&shared, row)?;
        let id = escape(&row.id);
        let mut links = format!("<a href=\"/v1/sessions/{id}\">status</a>");
        if row.results_trials > 0 {
            let _ = write!(
                links,
                " · <a href=\"/v1/sessions/{id}/report\">report</a> · \
                 <a href=\"/v1/sessions/{id}/results.csv\">results.csv</a>"
            );
        }
        let note = row
            .error
            .as_deref()
            .or(row.stop_reason.as_deref())
            .unwrap_or("");
        let _ = writeln!(
            sessions,
            "<tr class=\"{state}\"><td><code>{id}</code></td><td>{state}</td>\
             <td>{progress:.0} %</td><td>{done}/{total}</td><td>{playback}</td><td>{setting}</td>\
             <td>{links}</td><td>{note}</td></tr>",
            state = escape(&row.state),
            progress = status["progress"].as_f64().unwrap_or(0.0) * 100.0,
            done = status["trials_done"].as_u64().unwrap_or(0),
            total = row.trials_total,
            playback = escape(&row.playback),
            setting = escape(&row.setting),
            note = escape(note),
        );
    }
    if rows.is_empty() {
        sessions.push_str("<tr><td colspan=\"8\">No sessions yet.</td></tr>\n");
    }
    let mut devices = String::new();
    for (serial, state, session, _seen) in shared.db.devices()? {
        let _ = write!(
            devices,
            "<li><code>{}</code> {}{}</li>",
            escape(&serial),
            escape(&state),
            session
                .map(|s| format!(" (session <code>{}</code>)", escape(&s)))
                .unwrap_or_default()
        );
    }
    if devices.is_empty() {
        devices.push_str("<li>none seen yet (<a href=\"/v1/devices\">look now</a>)</li>");
    }
    let html = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta http-equiv=\"refresh\" content=\"5\"><title>SiTAR backend</title>\
         <style>body{{font-family:sans-serif;margin:2em}}table{{border-collapse:collapse}}\
         td,th{{border-bottom:1px solid #ddd;padding:.3em .8em;text-align:left}}\
         tr.failed td{{color:#b00}}</style></head><body>\
         <h1>SiTAR backend</h1><p>Playback: <b>{playback}</b>. The newest {n} sessions; \
         this page refreshes every 5 s (JSON: <a href=\"/v1/sessions\">/v1/sessions</a>).</p>\
         <table><thead><tr><th>session</th><th>state</th><th>progress</th><th>trials</th>\
         <th>playback</th><th>setting</th><th>links</th><th>note</th></tr></thead>\
         <tbody>\n{sessions}</tbody></table>\
         <h2>Playback devices</h2><ul>{devices}</ul></body></html>\n",
        playback = escape(shared.config.playback.as_str()),
        n = rows.len(),
    );
    Ok(Html(html).into_response())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limit_takes_one_number_in_range_and_names_what_is_wrong() {
        assert_eq!(limit(None).unwrap(), DEFAULT_LIMIT);
        assert_eq!(limit(Some("")).unwrap(), DEFAULT_LIMIT);
        assert_eq!(limit(Some("limit=7")).unwrap(), 7);
        assert_eq!(limit(Some("limit=500")).unwrap(), 500);
        for bad in [
            "limit=0",
            "limit=501",
            "limit=-1",
            "limit=",
            "limit=x",
            "page=2",
        ] {
            let err = limit(Some(bad)).unwrap_err().to_string();
            let named = if bad.starts_with("page") {
                "page"
            } else {
                "limit"
            };
            assert!(err.contains(named), "{bad}: {err}");
        }
    }
}
