//! The HTML pages: `GET /` (what the server holds, for the person next to the playback
//! phones, refreshed every few seconds) and `GET /v1/sessions/{id}/report`. Both are
//! minijinja templates (`templates/`, autoescaped) sent with the pages' CSP.

use std::fmt::Write;

use axum::extract::{RawQuery, State};
use axum::response::Response;
use serde_json::json;

use crate::auth::Admin;
use crate::error::Error;
use crate::estimate::results_files::{self, Form};
use crate::http::helpers::{AppState, Found, rendering};
use crate::http::session_status::status_json;
use crate::ingest::evidence::EvidenceFiles;
use crate::model::PlaybackKind;
use crate::report::index_ranges::index_ranges;
use crate::report::page::{self, ReportInput, Standalone};
use crate::report::region_evidence::CameraEvidence;
use crate::report::scene;
use crate::report::templates;

/// Sessions on the page (the newest).
const PAGE_SESSIONS: u32 = 50;

/// `2026-12-02 03:41:07` from milliseconds since the Unix epoch (UTC).
fn utc(ms: i64) -> String {
    let secs = ms.div_euclid(1000);
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    // Civil date from days since 1970-01-01 (Howard Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02}:{:02}",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// Why the devices table is empty, in the operator's terms.
fn why_no_devices(shared: &crate::app_state::App) -> String {
    match shared.config.playback {
        PlaybackKind::Sim => {
            "this server plays back on simulated phones (sim playback), not adb devices".into()
        }
        PlaybackKind::Upload => {
            "upload playback: the trials come from the app, no playback phones are driven".into()
        }
        PlaybackKind::Adb => {
            let adb = &shared.config.adb.adb_path;
            let found = adb.components().count() > 1 && adb.exists()
                || std::env::var_os("PATH").is_some_and(|paths| {
                    std::env::split_paths(&paths).any(|dir| dir.join(adb).is_file())
                });
            if found {
                "adb sees no authorised phone (plug one in over USB and accept the debugging prompt)".into()
            } else {
                format!(
                    "adb was not found ({}: install Android platform-tools or set the adb path)",
                    adb.display()
                )
            }
        }
    }
}

/// `GET /`: the newest sessions and the known playback devices as one HTML page.
pub(crate) async fn overview(State(shared): AppState, _: Admin) -> Result<Response, Error> {
    let rows = shared.db.recent_sessions(None, PAGE_SESSIONS)?;
    let mut sessions = Vec::new();
    for row in &rows {
        let status = status_json(&shared, row)?;
        let note = row
            .error
            .as_deref()
            .or(row.stop_reason.as_deref())
            .unwrap_or("");
        let played_by: Vec<serde_json::Value> = shared
            .db
            .trial_sources(&row.id)?
            .into_iter()
            .map(|(source, trials)| json!({"source": source, "trials": index_ranges(&trials)}))
            .collect();
        sessions.push(json!({
            "id": row.id,
            "created_at": shared.db.session_created_ms(&row.id)?.map(utc).unwrap_or_default(),
            "state": row.state.as_str(),
            "progress": format!("{:.0} %", status["progress"].as_f64().unwrap_or(0.0) * 100.0),
            "eta": status["eta_s"].as_f64().map(|e| format!("{e:.0} s")).unwrap_or_else(|| "—".into()),
            "trials_done": status["trials_done"].as_u64().unwrap_or(0),
            "total": row.trials_total,
            "played_by": played_by,
            "playback": row.playback.as_str(),
            "setting": settings_label(&row.settings),
            "has_results": row.results_trials > 0,
            "note": note,
        }));
    }
    let devices: Vec<serde_json::Value> = shared
        .db
        .devices()?
        .into_iter()
        .map(|(serial, state, session, _seen)| json!({"serial": serial, "state": state, "session": session}))
        .collect();
    let html = templates::render(
        "overview.html",
        &json!({
            "playback": shared.config.playback.as_str(),
            "sessions": sessions,
            "devices": devices,
            "devices_empty_reason": why_no_devices(&shared),
            "tls_fingerprint": shared.tls_fingerprint.as_deref(),
            "held": format!("{:.1}", shared.live.held_bytes() as f64 / (1 << 20) as f64),
            "bound": format!("{:.0}", shared.config.live_total_bytes as f64 / (1 << 20) as f64),
        }),
    )?;
    Ok(templates::page(html))
}

/// `trim_mean_30`, with the window and relation when they are not the defaults.
fn settings_label(settings: &crate::model::estimate_settings::EstimateSettings) -> String {
    let mut label = settings.setting.to_string();
    if settings.window_frames != crate::model::estimate_settings::DEFAULT_WINDOW_FRAMES
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

/// `GET /v1/sessions/{id}/report`: the latest results on the walk (see `crate::report::page`);
/// with `?download=1` the same page as one file that opens from disk.
pub(crate) async fn report(
    State(shared): AppState,
    Found(session): Found,
    RawQuery(query): RawQuery,
) -> Result<Response, Error> {
    let base = format!("/v1/sessions/{}/", session.id);
    report_answer(shared, session, base, wants_download(query.as_deref())).await
}

/// Whether a query asks for the page as a file (`download=1`, `download=true`, `download`).
pub(crate) fn wants_download(query: Option<&str>) -> bool {
    query.unwrap_or("").split('&').any(|pair| {
        let (key, value) = pair.split_once('=').unwrap_or((pair, "1"));
        key == "download" && matches!(value, "1" | "true" | "yes")
    })
}

/// The report as a page, or as a stand-alone file to save (`report-ID.html`). Before the
/// first estimate both are the waiting page (which a saved file never refreshes).
pub(crate) async fn report_answer(
    shared: std::sync::Arc<crate::app_state::App>,
    session: crate::model::Session,
    base: String,
    download: bool,
) -> Result<Response, Error> {
    if session.results_trials == 0 {
        let html = waiting_page(&shared, &session, !download)?;
        return Ok(templates::page(html));
    }
    let file_name = format!("report-{}.html", session.id);
    let (html, csp) = render_report(shared, session, base, download).await?;
    Ok(match csp {
        Some(csp) => templates::attachment_page(html, &file_name, &csp),
        None => templates::page(html),
    })
}

/// The page of a session with no estimate yet: what it waits for ("2 of 8 trials played"),
/// reloading itself every few seconds unless the session failed (then it says why).
fn waiting_page(
    shared: &crate::app_state::App,
    session: &crate::model::Session,
    refresh: bool,
) -> Result<String, Error> {
    use crate::model::SessionState;
    let status = status_json(shared, session)?;
    let failed = session.state == SessionState::Failed;
    let waiting_for = match session.state {
        SessionState::Created => "its recording (or, for an upload session, its trials)",
        SessionState::Uploaded if session.playback == PlaybackKind::Upload => "its trials",
        SessionState::Uploaded => "a playback phone",
        SessionState::Playing => "the second trial: an estimate compares pairs of trials",
        SessionState::Estimating => "the estimate, which is running",
        SessionState::Done | SessionState::Failed => "nothing",
    };
    templates::render(
        "waiting.html",
        &json!({
            "id": session.id,
            "state": session.state.as_str(),
            "played": status["trials_done"].as_u64().unwrap_or(0),
            "total": session.trials_total,
            "waiting_for": waiting_for,
            "error": session.error,
            "is_failure": failed,
            "refresh_s": (refresh && !failed).then_some(page::REFRESH_S),
        }),
    )
}

/// The report page of `session`: for its owner and for a share link alike; `base` is where
/// this reader fetches the session's data (`/v1/sessions/ID/` or `/share/TOKEN/`). A
/// `standalone` page carries everything inline and comes with its Content-Security-Policy.
pub(crate) async fn render_report(
    shared: std::sync::Arc<crate::app_state::App>,
    session: crate::model::Session,
    base: String,
    standalone: bool,
) -> Result<(String, Option<String>), Error> {
    rendering(shared, "report", move |shared| {
        let json = results_files::read(&*shared.blobs, &session, Form::Json)?;
        // No trajectory (e.g. trials without a readable reference) still gets a page.
        let phone = scene::load(shared.stores(), &session).ok();
        let history = results_files::history(&*shared.blobs, &session);
        // Unreadable evidence costs the regions their thumbnails, not the page.
        let evidence = CameraEvidence::load(&*shared.blobs, &session.id).unwrap_or_else(|e| {
            log::warn!("report of {}: evidence left out: {e}", session.id);
            None
        });
        let thumbnail = |k: u32| {
            EvidenceFiles {
                blobs: &*shared.blobs,
                id: &session.id,
            }
            .read_thumbnail(k as usize)
            .ok()
            .flatten()
        };
        // A stand-alone page carries the 3-D view's data (what `scene.json` serves).
        let scene = phone.as_deref().filter(|_| standalone).map(|(p, source)| {
            let thresholds = session
                .settings
                .thresholds(shared.config.thresholds, shared.config.thresholds_deg);
            let subs = crate::report::regions::sub_rows(p, thresholds);
            let unit = page::Unit::of(&session);
            crate::report::scene_view::scene_json(p, &subs, thresholds, &unit, source.describe())
        });
        let html = page::render(&ReportInput {
            row: &session,
            results_json: &json,
            config: &shared.config,
            phone: phone.as_deref().map(|(p, s)| (p, *s)),
            history,
            base: &base,
            evidence: evidence.as_ref(),
            standalone: standalone.then_some(Standalone {
                thumbnail: &thumbnail,
                scene,
            }),
        })?;
        // The stand-alone page's policy is in its <meta>; the download's header repeats it.
        let csp = standalone.then(page::standalone_csp);
        Ok((html, csp))
    })
    .await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_dates() {
        assert_eq!(utc(0), "1970-01-01 00:00:00");
        // 2024-02-29 12:34:56 UTC (a leap day).
        assert_eq!(utc(1_709_210_096_000), "2024-02-29 12:34:56");
    }

    #[test]
    fn a_download_is_asked_for_by_the_query() {
        for yes in [
            "download=1",
            "download",
            "a=b&download=true",
            "download=yes&x",
        ] {
            assert!(wants_download(Some(yes)), "{yes}");
        }
        for no in ["", "download=0", "downloads=1", "x=download"] {
            assert!(!wants_download(Some(no)), "{no}");
        }
        assert!(!wants_download(None));
    }
}
