//! The HTML pages: `GET /` (what the server holds, for the person next to the playback
//! phones, refreshed every few seconds, linking every session's report and results) and
//! `GET /v1/sessions/{id}/report`.

use std::fmt::Write;

use axum::extract::State;
use axum::response::{Html, IntoResponse, Response};

use crate::Error;
use crate::auth::Admin;
use crate::http::{AppState, Found};
use crate::published::{self, Form};
use crate::report::{self, escape};
use crate::status::status_json;

/// Sessions on the page (the newest).
const PAGE_SESSIONS: u32 = 50;

/// `GET /`: the newest sessions and the known playback devices as one HTML page.
pub(crate) async fn overview(State(shared): AppState, _: Admin) -> Result<Response, Error> {
    let rows = shared.db.recent_sessions(None, PAGE_SESSIONS)?;
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
            state = row.state.as_str(),
            progress = status["progress"].as_f64().unwrap_or(0.0) * 100.0,
            done = status["trials_done"].as_u64().unwrap_or(0),
            total = row.trials_total,
            playback = row.playback.as_str(),
            setting = escape(&settings_label(&row.settings)),
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
         <h2>Playback devices</h2><ul>{devices}</ul>\
         <p id=\"memory\">Trials in memory: {held:.1} of {bound:.0} MiB.</p>{tls}</body></html>\n",
        tls = shared
            .tls_fingerprint
            .as_deref()
            .map(|f| format!(
                "<p id=\"tls\">TLS certificate SHA-256: <code>{}</code></p>",
                escape(f)
            ))
            .unwrap_or_default(),
        playback = escape(shared.config.playback.as_str()),
        n = rows.len(),
        held = shared.live.held_bytes() as f64 / (1 << 20) as f64,
        bound = shared.config.live_total_bytes as f64 / (1 << 20) as f64,
    );
    Ok(Html(html).into_response())
}

/// `trim_mean_30`, with the window and relation when they are not the defaults.
fn settings_label(settings: &crate::settings::EstimateSettings) -> String {
    let mut label = settings.setting.to_string();
    if settings.window_frames != crate::settings::DEFAULT_WINDOW_FRAMES
        || settings.pose_relation != sitar_estimator::PoseRelation::TranslationPart
    {
        let _ = write!(
            label,
            " ({} frames, {})",
            settings.window_frames, settings.pose_relation
        );
    }
    label
}

/// `GET /v1/sessions/{id}/report`: the latest results drawn on the reference trial.
pub(crate) async fn report(
    State(shared): AppState,
    Found(session): Found,
) -> Result<Response, Error> {
    let json = published::read(&shared, &session, Form::Json)?;
    let first = shared
        .db
        .trials_in_order(&session.id)?
        .first()
        .map_or(0, |(index, _)| *index);
    let reference =
        std::fs::read_to_string(shared.files.trial(&session.id, first)).unwrap_or_default();
    let html = report::render(&session, &reference, &json, &shared.config)?;
    Ok(Html(html).into_response())
}
