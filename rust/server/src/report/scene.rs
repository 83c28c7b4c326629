//! A session as the user's phone saw it — render plan, depth-sampled surfaces, markers — for
//! the report's 3-D view and `GET /v1/sessions/{id}/scene.glb`.
//!
//! A simulated recording (`sitar-sim`) holds the walk and the room, so the phone session is
//! rebuilt exactly as the phone logic recorded it (depth images included). A real recording
//! holds no depth: the reference trial's poses give the render plan; when the phone sent its
//! camera evidence (`crate::ingest::evidence`), each midpoint's measured distance to the surface it
//! faced is put back as a depth sample straight ahead, so the page has surface points and
//! markers (placed by sitar-core's own rule; their normals face the camera, as the true
//! ones are unknown). Either is built once and kept as a `sitar_core` session folder
//! (`sessions/ID/phone/`, rebuilt when evidence arrives later), right after the session
//! finishes ([`prepare`]) or else on the first request; the latest results are loaded into
//! it on every request.

use std::io::Read as _;
use std::sync::{Arc, Mutex};

use serde_json::json;
use sitar_core::{DisplayRotation, Session, SessionConfig};

use super::flat_depth::flat_depth_sample;
use crate::error::Error;
use crate::estimate::results_files::{self, Form};
use crate::ingest::evidence::{EvidenceFiles, EvidenceRow};
use crate::ingest::mp4_check;
use crate::model::Session as Row;
use crate::storage::keys::SessionObject;
use crate::storage::{BlobStore, MetadataStore, StoreRefs};

/// Where the scene's poses came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Source {
    /// The simulated walk, recorded by the phone logic with depth.
    SimulatedWalk,
    /// The reference trial's poses (no depth on the backend).
    ReferenceTrial,
    /// The reference trial's poses with the surface distances of the phone's evidence.
    ReferenceTrialWithEvidence,
    /// The phone's own log (`trajectory.txt`, with the depth of its `subtrajectories.csv`).
    PhoneLog,
}

impl Source {
    /// What the page says about where the 3-D scene came from.
    pub(crate) fn describe(self) -> &'static str {
        match self {
            Self::SimulatedWalk => "the recorded walk with its depth samples",
            Self::ReferenceTrial => {
                "the reference trial: a real recording brings no depth to the backend, and the phone sent no camera evidence, so there are no surface points or markers"
            }
            Self::ReferenceTrialWithEvidence => {
                "the reference trial, with the surface distances the phone measured (surface points straight ahead of each midpoint; marker normals face the camera)"
            }
            Self::PhoneLog => {
                "the phone's own log (trajectory.txt), with the depth it measured at each midpoint from its subtrajectories.csv (surface points straight ahead; marker normals face the camera)"
            }
        }
    }

    /// Its name in the phone folder's `source.txt`.
    fn tag(self) -> &'static str {
        match self {
            Self::SimulatedWalk => "sim",
            Self::ReferenceTrial => "trial",
            Self::ReferenceTrialWithEvidence => "trial+evidence",
            Self::PhoneLog => "phone",
        }
    }

    fn from_tag(tag: &str) -> Self {
        match tag {
            "sim" => Self::SimulatedWalk,
            "trial+evidence" => Self::ReferenceTrialWithEvidence,
            "phone" => Self::PhoneLog,
            _ => Self::ReferenceTrial,
        }
    }
}

fn config(row: &Row) -> Result<SessionConfig, Error> {
    let text = json!({
        "convention": "arcore",
        "subtrajectory_frames": row.settings.window_frames,
        "pose_relation": row.settings.pose_relation.to_string(),
        // The scene needs poses and depth; camera images would cost a render and a JPEG per
        // midpoint on every rebuild.
        "images": false,
    })
    .to_string();
    SessionConfig::from_json(&text).map_err(|e| Error::Internal(format!("phone config: {e}")))
}

/// The reference trial (the first stored) replayed through the phone logic, with each
/// midpoint's surface distance from `evidence` (rows by sub-trajectory index) when given.
fn from_reference_trial(
    stores: StoreRefs<'_>,
    row: &Row,
    evidence: Option<&[EvidenceRow]>,
) -> Result<Session, Error> {
    let first = stores
        .db
        .trials_in_order(&row.id)?
        .first()
        .map(|(index, _)| *index)
        .ok_or_else(|| Error::Conflict(format!("session {} has no trials yet", row.id)))?;
    let bytes = crate::ingest::trials::read_trial(stores.blobs, &row.id, first)?;
    let text = String::from_utf8_lossy(&bytes);
    let trajectory = sitar_estimator::parse_tum(&text, "reference trial")
        .map_err(|e| Error::InvalidContent(format!("reference trial of {}: {e}", row.id)))?;
    let poses: Vec<(i64, sitar_core::Pose)> = (0..trajectory.len())
        .map(|i| {
            (
                trajectory.stamps[i],
                sitar_core::Pose::new(trajectory.positions[i], trajectory.orientations[i]),
            )
        })
        .collect();
    if poses.len() < 3 {
        return Err(Error::Conflict(format!(
            "the reference trial of {} has {} poses; a scene needs 3",
            row.id,
            poses.len()
        )));
    }
    let fail = |e: sitar_core::Error| Error::InvalidContent(format!("reference trial: {e}"));
    let mut session = Session::try_new(config(row)?).map_err(fail)?;
    let last = poses.len() - 1;
    session.start(poses[0].0, poses[0].1).map_err(fail)?;
    for (t, pose) in &poses[1..last] {
        let flags = session.frame(*t, *pose).map_err(fail)?;
        if let Some(rows) = evidence
            && flags.is_midpoint()
            && let Some(k) = session.subtrajectories().last().map(|s| s.index as usize)
            && let Some(measured) = rows.get(k).filter(|r| r.index == k && r.depth_valid)
        {
            flat_depth_sample(&mut session, measured.distance_m);
        }
    }
    session.stop(poses[last].0, poses[last].1).map_err(fail)?;
    Ok(session)
}

/// Builds the phone session of `row` (no results loaded): from the phone's own log when it
/// sent one, else from the simulated walk, else from the reference trial. Blocking and
/// CPU-heavy for simulated walks (one depth image per midpoint).
fn build(stores: StoreRefs<'_>, row: &Row) -> Result<(Session, Source), Error> {
    if let Some(log) = stores.blobs.get(&row.id, SessionObject::PhoneTrajectory)? {
        let table = stores.blobs.get(&row.id, SessionObject::Subtrajectories)?;
        let session = super::phone_log_scene::from_phone_log(
            row,
            &String::from_utf8_lossy(&log),
            table.as_deref().map(String::from_utf8_lossy).as_deref(),
        )?;
        return Ok((session, Source::PhoneLog));
    }
    if let Some(recording) = simulated_walk(stores, &row.id) {
        let session = recording
            .phone_session(config(row)?, DisplayRotation::Deg90)
            .map_err(|e| Error::InvalidContent(format!("simulated walk: {e}")))?;
        return Ok((session, Source::SimulatedWalk));
    }
    let evidence = stored_evidence(stores, row);
    let source = if evidence.is_some() {
        Source::ReferenceTrialWithEvidence
    } else {
        Source::ReferenceTrial
    };
    Ok((
        from_reference_trial(stores, row, evidence.as_deref())?,
        source,
    ))
}

/// Session `id`'s recording when it is a `sitar-sim` one. Only its header is read to tell
/// (a phone's recording is gigabytes of video that the scene never needs); a sim recording
/// is read whole, within its bound ([`mp4_check::MAX_SIM_RECORDING_BYTES`]).
fn simulated_walk(stores: StoreRefs<'_>, id: &str) -> Option<sitar_sim::Recording> {
    let head = stores
        .blobs
        .peek(id, SessionObject::Recording, mp4_check::SIM_HEADER_BYTES)
        .ok()??;
    if !mp4_check::is_sim_header(&head) {
        return None;
    }
    let found = stores.blobs.open(id, SessionObject::Recording).ok()??;
    if found.len > mp4_check::MAX_SIM_RECORDING_BYTES {
        log::info!(
            "session {id}: a sitar-sim recording of {} bytes is not read for its scene",
            found.len
        );
        return None;
    }
    // Read no further than the bound, even if the recording was replaced meanwhile.
    let mut bytes = Vec::with_capacity(found.len as usize);
    std::io::Read::take(found.bytes, mp4_check::MAX_SIM_RECORDING_BYTES)
        .read_to_end(&mut bytes)
        .ok()?;
    sitar_sim::Recording::from_bytes(&bytes).ok()
}

/// The phone's evidence rows of `row`, if it sent any (an unreadable table counts as none:
/// the scene is drawn without it).
fn stored_evidence(stores: StoreRefs<'_>, row: &Row) -> Option<Vec<EvidenceRow>> {
    EvidenceFiles {
        blobs: stores.blobs,
        id: &row.id,
    }
    .evidence_rows()
    .ok()
    .flatten()
}

/// Phone sessions with results loaded, most recent last: a report and its `scene.json` (and a
/// reload) reuse the work. Keyed by folder (data dir + id) and the results' trial count.
type Cached = (std::path::PathBuf, u32, Arc<(Session, Source)>);
static CACHE: Mutex<Vec<Cached>> = Mutex::new(Vec::new());
/// Sessions kept in memory (a 10-minute walk's is a few MB).
const CACHED_SESSIONS: usize = 4;

/// The session whose scene is being built ahead, if any (at most one at a time).
static PREPARING: Mutex<Option<String>> = Mutex::new(None);

/// `mutex` locked; a panic elsewhere while it was held leaves its data usable (a cache and a
/// flag: nothing half-written to guard against).
fn locked<T>(mutex: &'static Mutex<T>) -> std::sync::MutexGuard<'static, T> {
    mutex
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Builds a just-finished session's scene — the phone session folder, its results loaded,
/// the in-memory cache — on a thread of its own, so the first load of its report does not pay
/// for it (a simulated 10-minute walk takes seconds to rebuild). One at a time: a session that
/// finishes while another's is built gets its scene on the first request instead, as before.
pub(crate) fn prepare(db: Arc<dyn MetadataStore>, blobs: Arc<dyn BlobStore>, id: String) {
    {
        let mut slot = locked(&PREPARING);
        if slot.is_some() {
            return;
        }
        *slot = Some(id.clone());
    }
    let spawned = std::thread::Builder::new()
        .name("sitar-scene".into())
        .spawn(move || {
            let stores = StoreRefs {
                db: &*db,
                blobs: &*blobs,
            };
            let built = stores
                .db
                .session(&id)
                .and_then(|row| row.ok_or_else(|| Error::NotFound(format!("no session {id:?}"))))
                .and_then(|row| load(stores, &row));
            if let Err(e) = built {
                log::debug!("session {id}: scene not built ahead: {e}");
            }
            *locked(&PREPARING) = None;
        });
    if spawned.is_err() {
        *locked(&PREPARING) = None;
    }
}

/// Whether session `id`'s scene is being built ahead right now (its scratch folder under
/// `tmp/` may exist until the build ends).
pub(crate) fn preparing(id: &str) -> bool {
    locked(&PREPARING).as_deref() == Some(id)
}

/// The phone's log of session `id` changed (`trajectory.txt` or `subtrajectories.csv`): its
/// kept scene and cached copy are dropped, so the next request builds it from the new log.
pub(crate) fn phone_log_changed(blobs: &dyn BlobStore, id: &str) {
    blobs.discard_scene(id);
    forget(blobs, id);
}

/// Drops session `id`'s scene from the in-memory cache (a deleted session's data must not
/// stay readable, even in memory).
pub(crate) fn forget(blobs: &dyn BlobStore, id: &str) {
    let key = blobs.scene_folder(id);
    locked(&CACHE).retain(|(k, _, _)| *k != key);
}

/// One gate per scene being loaded (keyed as [`CACHE`]): requests for the same session at
/// once wait for one load and share it, instead of each building its own copy.
static LOADING: Mutex<Vec<(std::path::PathBuf, Arc<Mutex<()>>)>> = Mutex::new(Vec::new());

fn cached(key: &std::path::Path, trials: u32) -> Option<Arc<(Session, Source)>> {
    locked(&CACHE)
        .iter()
        .find(|(k, t, _)| k == key && *t == trials)
        .map(|(_, _, hit)| hit.clone())
}

/// The phone session of `row` with its latest results loaded. Blocking. Loaded once however
/// many requests ask at the same time: the first loads, the others wait for it.
pub(crate) fn load(stores: StoreRefs<'_>, row: &Row) -> Result<Arc<(Session, Source)>, Error> {
    let key = stores.blobs.scene_folder(&row.id);
    if let Some(hit) = cached(&key, row.results_trials) {
        return Ok(hit);
    }
    let gate = {
        let mut loading = locked(&LOADING);
        match loading.iter().find(|(k, _)| *k == key) {
            Some((_, gate)) => gate.clone(),
            None => {
                let gate = Arc::new(Mutex::new(()));
                loading.push((key.clone(), gate.clone()));
                gate
            }
        }
    };
    let loaded = {
        let _turn = gate.lock().unwrap_or_else(|p| p.into_inner());
        match cached(&key, row.results_trials) {
            Some(hit) => Ok(hit),
            None => load_uncached(stores, row).map(|loaded| {
                let loaded = Arc::new(loaded);
                let mut cache = locked(&CACHE);
                cache.retain(|(k, _, _)| *k != key);
                if cache.len() >= CACHED_SESSIONS {
                    cache.remove(0);
                }
                cache.push((key.clone(), row.results_trials, loaded.clone()));
                loaded
            }),
        }
    };
    drop(gate);
    // The last one through removes the gate.
    locked(&LOADING).retain(|(_, gate)| Arc::strong_count(gate) > 1);
    loaded
}

fn load_uncached(stores: StoreRefs<'_>, row: &Row) -> Result<(Session, Source), Error> {
    let cached = stores
        .blobs
        .kept_scene(&row.id)
        .and_then(|(dir, tag)| Some((Session::load(&dir).ok()?, Source::from_tag(&tag))))
        // Built before the phone's evidence arrived: built again with it.
        .filter(|(_, source)| {
            *source != Source::ReferenceTrial || stored_evidence(stores, row).is_none()
        })
        // Built before the phone's log arrived: built again from it.
        .filter(|(_, source)| {
            *source == Source::PhoneLog
                || !stores.blobs.exists(&row.id, SessionObject::PhoneTrajectory)
        });
    if cached.is_none() {
        stores.blobs.discard_scene(&row.id);
    }
    let (mut session, source) = match cached {
        Some(found) => found,
        None => {
            let (session, source) = build(stores, row)?;
            stores
                .blobs
                .keep_scene(&row.id, source.tag(), &mut |scratch| {
                    session.save(scratch).is_ok()
                });
            (session, source)
        }
    };
    if row.results_trials > 0 {
        let json = results_files::read(stores.blobs, row, Form::Json)?;
        session
            .load_results(&json)
            .map_err(|e| Error::Internal(format!("results of {} do not fit: {e}", row.id)))?;
    }
    Ok((session, source))
}
