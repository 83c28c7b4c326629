//! A venue's map (`GET /v1/venues/{id}/map.json`), built on every request from its sessions'
//! stored files with sitar-core's [`sitar_core::venue::build_map`]: so it follows its
//! sessions at once (one that finishes, joins, leaves or is deleted changes the next answer)
//! and no cache can be stale.

use sitar_core::Convention;
use sitar_core::venue::{Contribution, SessionFiles, VenueMap, VenueSpec, build_map};

use crate::Error;
use crate::session::{Session, SessionState};
use crate::storage::keys::SessionObject;
use crate::storage::{BlobStore, MetadataStore};
use crate::venue::Venue;

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
/// order the sessions joined.
pub(crate) fn contributions(
    db: &dyn MetadataStore,
    blobs: &dyn BlobStore,
    venue: &Venue,
) -> Result<(VenueSpec, Vec<(Session, Contribution)>), Error> {
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
        let contribution =
            StoredFiles::read(blobs, &session)?.contribution(&session, &venue.anchor);
        out.push((session, contribution));
    }
    Ok((spec, out))
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
