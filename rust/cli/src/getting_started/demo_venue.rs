//! `sitar demo --venue`: three users walk the demo room, each session is uploaded, played and
//! estimated by the in-process backend as in `sitar demo`, all join one venue; prints each
//! session's alignment against the simulator's truth, the map's worst surface cells with what
//! they truly are, a match line against ground truth, and the venue report.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use glam::DVec3;
use sitar_client::{Client, NewSession, SessionState};
use sitar_core::venue::{CellKind, VenueMap, align};
use sitar_core::{DisplayRotation, ErrorClass, SessionConfig};
use sitar_sim::{Venue, VenueUser};

/// What `sitar demo --venue` runs with (from `sitar demo`'s flags).
#[derive(Debug, Clone)]
pub struct Options {
    /// Data directory of the in-process server.
    pub data: PathBuf,
    /// Users walking the room.
    pub users: usize,
    /// Playback trials per session.
    pub trials: u32,
    /// Walk duration (s).
    pub seconds: f64,
    /// Seed of the walks and the trials (user `i` from `seed + i`).
    pub seed: u64,
}

/// The venue walks' default length: five stops, so every walk passes the anchor.
pub const VENUE_SECONDS: f64 = 20.0;

/// The demo venue's users.
pub const VENUE_USERS: usize = 3;

/// Worst surface cells printed.
const WORST_CELLS: usize = 5;

/// The longest answer read from the backend (map.json, the report page).
const MAX_RESPONSE_BYTES: u64 = 256 << 20;

/// One user's session on the server.
struct Uploaded<'a> {
    user: &'a VenueUser,
    id: String,
}

/// Runs the venue demo against the in-process backend at `url` (started by `sitar demo`)
/// with its admin `token`.
pub fn run(options: &Options, url: &str, token: &str) -> Result<()> {
    let started = Instant::now();
    let venue = Venue::demo(options.users, options.seconds, 30.0, options.seed)
        .context("cannot simulate the venue's walks")?;
    let http = Http { url, token };
    let venue_id = http
        .create_venue(&venue)
        .context("cannot create the venue (POST /v1/venues)")?;
    println!(
        "venue       {venue_id}: the demo room, anchor `{}` (A4 on the north wall), {} users",
        venue.anchor.id,
        venue.users.len()
    );
    let client = Client::new(url)?.with_server_token(token)?;
    let mut uploaded = Vec::new();
    for user in &venue.users {
        let id = upload(&client, &http, options, &venue_id, user)?;
        uploaded.push(Uploaded { user, id });
    }
    for u in &uploaded {
        wait(&client, &u.id)?;
    }
    println!(
        "played      {} sessions × {} trials, estimated in {:.1} s",
        uploaded.len(),
        options.trials,
        started.elapsed().as_secs_f64()
    );
    for u in &uploaded {
        print_alignment(&http, &venue, u)?;
    }
    let map_json = http
        .get_text(&format!("/v1/venues/{venue_id}/map.json"))
        .context("cannot fetch the venue map")?;
    let map = VenueMap::from_json(&map_json).context("the venue map")?;
    print_worst_cells(&venue, &map);
    print_regions(&venue, &map);
    print_match(&venue, &map);
    let report = http
        // The one-file copy: script, style and 3-D view data inline, so it opens from disk.
        .get_text(&format!("/v1/venues/{venue_id}/report?download=1"))
        .context("cannot fetch the venue report")?;
    let path = options.data.join(format!("venue-report-{venue_id}.html"));
    std::fs::write(&path, report).with_context(|| format!("cannot write {}", path.display()))?;
    println!("report      {}", path.display());
    println!(
        "            served at {url}/v1/venues/{venue_id}/report?token={token} while the demo runs"
    );
    println!("total       {:.1} s", started.elapsed().as_secs_f64());
    Ok(())
}

/// One user's phone session: recorded in the phone's own world frame, saved as the phone
/// saves it, the recording and the phone's log uploaded into the venue, the camera evidence
/// after.
fn upload(
    client: &Client,
    http: &Http<'_>,
    options: &Options,
    venue_id: &str,
    user: &VenueUser,
) -> Result<String> {
    let session = user
        .phone_session(
            SessionConfig::from_json(r#"{"convention":"arcore"}"#)?,
            DisplayRotation::Deg90,
        )
        .with_context(|| format!("cannot record user {}'s phone session", user.index))?;
    let phone_dir = options
        .data
        .join(format!("venue-user-{}-phone", user.index));
    session
        .save(&phone_dir)
        .with_context(|| format!("cannot save {}", phone_dir.display()))?;
    let rec_path = options
        .data
        .join(format!("venue-user-{}.sitarsim", user.index));
    std::fs::write(&rec_path, user.recording.to_bytes())
        .with_context(|| format!("cannot write {}", rec_path.display()))?;
    let request = NewSession {
        trials: options.trials,
        setting: sitar_core::DEFAULT_SETTING.into(),
        playback: "sim".into(),
        window_frames: None,
        pose_relation: None,
    };
    let id = http
        .create_session(&request, venue_id)
        .context("cannot create a venue session (POST /v1/sessions)")?;
    for file in ["trajectory.txt", "anchors.csv", "subtrajectories.csv"] {
        let body = std::fs::read(phone_dir.join(file))
            .with_context(|| format!("cannot read {}", phone_dir.join(file).display()))?;
        http.put(&format!("/v1/sessions/{id}/{file}"), &body)
            .with_context(|| format!("cannot upload {file} of session {id}"))?;
    }
    client.upload_recording(&id, &rec_path, &mut |_, _| {})?;
    client.upload_evidence(&id, &phone_dir)?;
    let full = session
        .anchors()
        .iter()
        .filter(|o| o.tracking == sitar_core::Tracking::Full)
        .count();
    println!(
        "user {}      session {id}: {:.1} s walk, {} anchor sightings ({full} full), phone log and recording sent",
        user.index,
        user.recording.duration_s(),
        session.anchors().len()
    );
    Ok(id)
}

/// Waits until the session is done; fails otherwise.
fn wait(client: &Client, id: &str) -> Result<()> {
    let status = client.wait(
        id,
        Duration::from_millis(100),
        Duration::from_secs(600),
        &mut |_| {},
    )?;
    if status.state != SessionState::Done {
        bail!(
            "session {id} {}: {}",
            status.state,
            status.error.unwrap_or_default()
        );
    }
    Ok(())
}

/// The backend's alignment of one session (its spread) and ours from the same anchors.csv
/// against the simulator's truth.
fn print_alignment(http: &Http<'_>, venue: &Venue, u: &Uploaded<'_>) -> Result<()> {
    let status: serde_json::Value = serde_json::from_str(
        &http
            .get_text(&format!("/v1/sessions/{}", u.id))
            .with_context(|| format!("cannot read session {}", u.id))?,
    )
    .with_context(|| format!("session {}'s status", u.id))?;
    let backend = &status["alignment"];
    match align(&u.user.observations, &venue.anchor.id) {
        Ok(a) => {
            let (position_m, heading_deg) = u.user.truth.error_of(&a);
            println!(
                "alignment   {}: {} observations, spread {:.1} mm / {:.2}° (backend: {}); against the truth {:.1} mm, {:.2}°",
                u.id,
                a.observations,
                a.position_spread_m * 1000.0,
                a.heading_spread_deg,
                backend_summary(backend),
                position_m * 1000.0,
                heading_deg
            );
        }
        Err(e) => println!("alignment   {}: {e}", u.id),
    }
    Ok(())
}

/// The session status's `alignment` in a few words.
fn backend_summary(alignment: &serde_json::Value) -> String {
    if let Some(e) = alignment.get("error").and_then(|e| e.as_str()) {
        return format!("not aligned: {e}");
    }
    match (
        alignment["position_spread_m"].as_f64(),
        alignment["heading_spread_deg"].as_f64(),
    ) {
        (Some(p), Some(h)) => format!("{:.1} mm / {h:.2}°", p * 1000.0),
        _ => "no alignment reported".into(),
    }
}

/// The map's worst surface cells with what they truly are.
fn print_worst_cells(venue: &Venue, map: &VenueMap) {
    let mut surface: Vec<_> = map
        .cells
        .iter()
        .filter(|c| c.kind == CellKind::Surface)
        .collect();
    surface.sort_by(|a, b| b.error_m.total_cmp(&a.error_m));
    println!(
        "map         {} cells ({} surface) from {} sessions; worst surface cells:",
        map.cells.len(),
        surface.len(),
        map.sessions.len()
    );
    for (i, cell) in surface.iter().take(WORST_CELLS).enumerate() {
        let c = DVec3::from_array(cell.center);
        let truth = venue
            .truth_at(c)
            .map_or_else(|| "nothing".to_owned(), |t| t.label());
        println!(
            "  {}. ({:5.2}, {:5.2}, {:5.2}) m: {:5.1} cm ({:6}), {} session(s), {} sub-trajectories → {truth}",
            i + 1,
            c.x,
            c.y,
            c.z,
            cell.error_m * 100.0,
            class_name(cell.class),
            cell.sessions,
            cell.subtrajectories
        );
    }
}

/// The report's problem regions (surface cells classed high, seen by at least 2 sessions)
/// and what they truly are.
fn print_regions(venue: &Venue, map: &VenueMap) {
    let regions: Vec<String> = map
        .cells
        .iter()
        .filter(|c| c.kind == CellKind::Surface && c.class == ErrorClass::High && c.sessions >= 2)
        .map(|c| {
            venue
                .truth_at(DVec3::from_array(c.center))
                .map_or_else(|| "nothing".to_owned(), |t| t.label())
        })
        .collect();
    let mut labels: Vec<(String, usize)> = Vec::new();
    for label in regions.iter() {
        match labels.iter_mut().find(|(l, _)| l == label) {
            Some((_, n)) => *n += 1,
            None => labels.push((label.clone(), 1)),
        }
    }
    let on: Vec<String> = labels
        .iter()
        .map(|(label, n)| format!("{n} on {label}"))
        .collect();
    println!(
        "regions     {} problem regions (high surface cells seen by ≥ 2 sessions){}",
        regions.len(),
        if on.is_empty() {
            String::new()
        } else {
            format!(": {}", on.join(", "))
        }
    );
}

/// The match line: problem cells (high or medium surface cells) against the hard surfaces.
fn print_match(venue: &Venue, map: &VenueMap) {
    let s = venue.score_problem_cells(map);
    let missed: Vec<&str> = s
        .hard_surfaces
        .iter()
        .filter(|h| !s.hard_surfaces_found.contains(h))
        .map(String::as_str)
        .collect();
    println!(
        "match       {}/{} problem cells on truly hard surfaces; {}/{} hard-surface cells flagged; hard surfaces found: {}/{}{}",
        s.problem_on_hard,
        s.problem_cells,
        s.problem_on_hard,
        s.hard_cells,
        s.hard_surfaces_found.len(),
        s.hard_surfaces.len(),
        if missed.is_empty() {
            String::new()
        } else {
            format!(" (missed: {})", missed.join(", "))
        }
    );
}

fn class_name(class: ErrorClass) -> &'static str {
    match class {
        ErrorClass::High => "high",
        ErrorClass::Medium => "medium",
        ErrorClass::Low => "low",
        _ => "none",
    }
}

/// The venue routes, which `sitar-client` does not speak: plain requests with the token.
struct Http<'a> {
    url: &'a str,
    token: &'a str,
}

impl Http<'_> {
    fn auth(&self) -> String {
        format!("Bearer {}", self.token)
    }

    fn get_text(&self, path: &str) -> Result<String> {
        let mut response = ureq::get(&format!("{}{path}", self.url))
            .header("authorization", &self.auth())
            .call()?;
        Ok(response
            .body_mut()
            .with_config()
            .limit(MAX_RESPONSE_BYTES)
            .read_to_string()?)
    }

    fn post_json(&self, path: &str, body: &serde_json::Value) -> Result<serde_json::Value> {
        let mut response = ureq::post(&format!("{}{path}", self.url))
            .header("authorization", &self.auth())
            .header("content-type", "application/json")
            .send(body.to_string())?;
        let text = response
            .body_mut()
            .with_config()
            .limit(MAX_RESPONSE_BYTES)
            .read_to_string()?;
        serde_json::from_str(&text).with_context(|| format!("POST {path} answered {text}"))
    }

    fn put(&self, path: &str, body: &[u8]) -> Result<()> {
        ureq::put(&format!("{}{path}", self.url))
            .header("authorization", &self.auth())
            .send(body)?;
        Ok(())
    }

    fn create_venue(&self, venue: &Venue) -> Result<String> {
        let answer = self.post_json(
            "/v1/venues",
            &serde_json::json!({"name": "demo room", "anchor": venue.anchor.id, "cell_m": 0.25}),
        )?;
        id_of(&answer)
    }

    fn create_session(&self, request: &NewSession, venue_id: &str) -> Result<String> {
        let answer = self.post_json(
            "/v1/sessions",
            &serde_json::json!({
                "trials": request.trials,
                "setting": request.setting,
                "playback": request.playback,
                "venue": venue_id,
                "convention": "arcore",
            }),
        )?;
        id_of(&answer)
    }
}

fn id_of(answer: &serde_json::Value) -> Result<String> {
    answer["id"]
        .as_str()
        .map(str::to_owned)
        .with_context(|| format!("no id in {answer}"))
}

/// The data directory's default name (in the system temp dir).
pub const DEMO_DIR: &str = "sitar-demo-venue";
