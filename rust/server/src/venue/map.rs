//! A venue's map (`GET /v1/venues/{id}/map.json`, `map.glb`, the venue report) from its
//! sessions' kept contributions: each session's contribution (sitar-core's
//! [`Contribution::from_files`] of its stored files) is computed once and kept beside its row
//! in the metadata store (`venue_contributions`, encoded by [`super::kept`]), and a request
//! merges the kept ones with [`sitar_core::venue::build_map`]. A contribution is forgotten
//! (its generation raised) when what it comes from changes — a phone file uploaded again,
//! the session becoming `done` — and removed when the session is deleted or its venue is;
//! the next request (or the finishing job, at once) computes it again. One without a kept
//! contribution (e.g. from before the table existed) gets one computed on first use. So the
//! map follows its sessions at once: one that finishes, joins, leaves or is deleted changes
//! the next answer.

use std::collections::HashMap;

use sitar_core::Convention;
use sitar_core::venue::{Contribution, SessionFiles, VenueMap, VenueSpec, build_map};

use crate::error::Error;
use crate::model::{Session, SessionState, Venue};
use crate::storage::keys::SessionObject;
use crate::storage::metadata::KeptContribution;
use crate::storage::{BlobStore, MetadataStore};
use crate::venue::kept;

/// One session's stored files as text (`None` when not uploaded; only a finished session's
/// results count, so a progressive estimate never enters the map).
struct StoredFiles {
    anchors: Option<String>,
    trajectory: Option<String>,
    subtrajectories: Option<String>,
    results: Option<String>,
}

impl StoredFiles {
    fn read(blobs: &dyn BlobStore, session: &Session) -> Result<StoredFiles, Error> {
        let text = |object| -> Result<Option<String>, Error> {
            Ok(blobs
                .get(&session.id, object)?
                .map(|bytes| String::from_utf8_lossy(&bytes).into_owned()))
        };
        let finished = session.state == SessionState::Done && session.results_trials > 0;
        Ok(StoredFiles {
            anchors: text(SessionObject::Anchors)?,
            trajectory: text(SessionObject::PhoneTrajectory)?,
            subtrajectories: text(SessionObject::Subtrajectories)?,
            results: if finished {
                text(SessionObject::ResultsJson)?
            } else {
                None
            },
        })
    }

    fn contribution(&self, session: &Session, anchor: &str) -> Contribution {
        let files = SessionFiles {
            session: &session.id,
            convention: session.convention,
            anchors_csv: self.anchors.as_deref(),
            trajectory_txt: self.trajectory.as_deref(),
            subtrajectories_csv: self.subtrajectories.as_deref(),
            results_json: self.results.as_deref(),
        };
        // Every file was checked on arrival, so this is a log and a reason, never a 500 for
        // the whole venue.
        Contribution::from_files(&files, anchor).unwrap_or_else(|e| {
            log::warn!("session {}: left out of its venue's map: {e}", session.id);
            Contribution::NotAligned {
                session: session.id.clone(),
                reason: format!("its files do not fit together: {e}"),
            }
        })
    }
}

/// What the map of `venue` is built from: its spec and each session's contribution, in the
/// order the sessions joined. Kept contributions are used as they are; the others are
/// computed from the session's files and kept (unless forgotten meanwhile).
pub(crate) fn contributions(
    db: &dyn MetadataStore,
    blobs: &dyn BlobStore,
    venue: &Venue,
) -> Result<(VenueSpec, Vec<(Session, Contribution)>), Error> {
    // The generations first, then the rows and files: a contribution forgotten after this
    // read is not kept over (see `keep`).
    let mut by_session: HashMap<String, KeptContribution> = db
        .kept_contributions(&venue.id)?
        .into_iter()
        .map(|k| (k.session.clone(), k))
        .collect();
    let sessions = db.venue_sessions(&venue.id)?;
    let spec = VenueSpec {
        id: venue.id.clone(),
        name: venue.name.clone(),
        anchor: venue.anchor.clone(),
        cell_m: venue.cell_m,
        // A venue's sessions share one; an empty venue's map has no coordinates to mean.
        convention: sessions.first().map_or(Convention::Unity, |s| s.convention),
    };
    let mut out = Vec::with_capacity(sessions.len());
    for session in sessions {
        let row = by_session.remove(&session.id);
        let decoded = row
            .as_ref()
            .and_then(|k| k.body.as_deref())
            .and_then(kept::decode)
            .filter(|c| c.session() == session.id);
        let contribution = match decoded {
            Some(c) => c,
            None => {
                let generation = row.map_or(0, |k| k.generation);
                compute_and_keep(db, blobs, &session, &venue.anchor, generation)?
            }
        };
        out.push((session, contribution));
    }
    Ok((spec, out))
}

/// Session `session`'s contribution from its files now, kept at `generation` (read before
/// the files).
fn compute_and_keep(
    db: &dyn MetadataStore,
    blobs: &dyn BlobStore,
    session: &Session,
    anchor: &str,
    generation: i64,
) -> Result<Contribution, Error> {
    let contribution = StoredFiles::read(blobs, session)?.contribution(session, anchor);
    db.keep_contribution(&session.id, generation, &kept::encode(&contribution))?;
    Ok(contribution)
}

/// Computes and keeps session `id`'s contribution to its venue now (when it is in one):
/// after it finished, so the first map request after it does not pay for it. Errors are
/// logged: the next request computes it anyway.
pub(crate) fn keep_now(db: &dyn MetadataStore, blobs: &dyn BlobStore, id: &str) {
    let run = || -> Result<(), Error> {
        let Some(session) = db.session(id)? else {
            return Ok(());
        };
        let Some(venue) = session.venue.as_deref() else {
            return Ok(());
        };
        let Some(venue) = db.venue(venue)? else {
            return Ok(());
        };
        let Some(generation) = db
            .kept_contributions(&venue.id)?
            .into_iter()
            .find(|k| k.session == id)
            .map(|k| k.generation)
        else {
            return Ok(());
        };
        // The row again, after the generation: its state is at least as new.
        let Some(session) = db.session(id)? else {
            return Ok(());
        };
        compute_and_keep(db, blobs, &session, &venue.anchor, generation).map(drop)
    };
    if let Err(e) = run() {
        log::warn!("session {id}: its venue contribution is left to the next map request: {e}");
    }
}

/// The map of `venue` with the cells seen by at least `min_sessions` sessions.
pub(crate) fn venue_map(
    db: &dyn MetadataStore,
    blobs: &dyn BlobStore,
    venue: &Venue,
    min_sessions: u32,
) -> Result<VenueMap, Error> {
    let (spec, contributions) = contributions(db, blobs, venue)?;
    let contributions: Vec<Contribution> = contributions.into_iter().map(|(_, c)| c).collect();
    Ok(build_map(&spec, &contributions, min_sessions))
}
