//! The `sessions` table: rows read typed, created (idempotently), listed, deleted, and moved
//! through their states by [`SessionStore::transition`], which only `session::lifecycle`
//! calls.

use rusqlite::types::Type;
use rusqlite::{OptionalExtension, params};

use super::{CachedSql, SqliteStore};
use crate::error::Error;
use crate::model::{
    NewSession, PlaybackKind, Session, SessionState, Step,
    estimate_settings::{self, EstimateSettings},
};
use crate::storage::deletes::Claim;
use crate::storage::metadata::{Rows, SessionStore, StepRecord, Unreadable};
use crate::storage::now_ms;

pub(super) const COLUMNS: &str = "id, trials_total, setting, playback, state, error, stop_reason, adaptive_min, \
     adaptive_k, recording_bytes, results_trials, legacy, window_frames, pose_relation, owner, venue, \
     convention, calibration";

/// What makes two session requests the same, as one text (compared for an idempotency key
/// used again); must match [`NewSession::request_summary`].
const REQUEST: &str = "trials_total || '/' || playback || '/' || setting || '/' || window_frames \
     || '/' || pose_relation || '/' || COALESCE(adaptive_min, '-') || '/' || adaptive_k \
     || '/' || legacy || '/' || COALESCE(venue, '-') || '/' || convention \
     || '/' || COALESCE(calibration, '-')";

impl NewSession<'_> {
    /// The request as [`REQUEST`] reads it back from a row.
    pub(crate) fn request_summary(&self) -> String {
        format!(
            "{}/{}/{}/{}/{}/{}/{}/{}/{}/{}/{}",
            self.trials_total,
            self.playback.as_str(),
            self.settings.setting,
            self.settings.window_frames,
            self.settings.pose_relation,
            self.adaptive_min
                .map_or_else(|| "-".to_string(), |m| m.to_string()),
            self.adaptive_k,
            self.legacy as i64,
            self.venue.unwrap_or("-"),
            self.convention.name(),
            // A calibration name holds no `/` (`estimate::calibrations`).
            self.calibration.unwrap_or("-"),
        )
    }
}

/// A text column parsed into its type; a value no version of the server writes is an error
/// that names the column.
fn typed<T>(
    r: &rusqlite::Row<'_>,
    index: usize,
    column: &str,
    parse: impl FnOnce(&str) -> Option<T>,
) -> rusqlite::Result<T> {
    let text: String = r.get(index)?;
    parse(&text).ok_or_else(|| {
        rusqlite::Error::FromSqlConversionFailure(
            index,
            Type::Text,
            format!("sessions.{column}: unknown value {text:?}").into(),
        )
    })
}

fn session_from_row(r: &rusqlite::Row<'_>) -> rusqlite::Result<Session> {
    Ok(Session {
        id: r.get(0)?,
        trials_total: r.get(1)?,
        settings: EstimateSettings {
            setting: typed(r, 2, "setting", |s| {
                estimate_settings::parse_setting(s).ok()
            })?,
            window_frames: r.get(12)?,
            pose_relation: typed(r, 13, "pose_relation", |s| {
                estimate_settings::parse_pose_relation(s).ok()
            })?,
        },
        playback: typed(r, 3, "playback", |s| s.parse::<PlaybackKind>().ok())?,
        state: typed(r, 4, "state", SessionState::from_wire)?,
        error: r.get(5)?,
        stop_reason: r.get(6)?,
        adaptive_min: r.get(7)?,
        adaptive_k: r.get(8)?,
        recording_bytes: r.get::<_, Option<i64>>(9)?.map(|b| b as u64),
        results_trials: r.get(10)?,
        legacy: r.get::<_, i64>(11)? != 0,
        owner: r.get(14)?,
        venue: r.get(15)?,
        convention: typed(r, 16, "convention", super::joining::parse_convention)?,
        calibration: r.get(17)?,
    })
}

/// Reads every row of `stmt` (a `SELECT {COLUMNS}`), sorting the readable from the rest.
pub(super) fn read_rows(
    stmt: &mut rusqlite::Statement<'_>,
    params: impl rusqlite::Params,
) -> rusqlite::Result<Rows> {
    let mut rows = stmt.query(params)?;
    let mut out = Rows::default();
    while let Some(row) = rows.next()? {
        match session_from_row(row) {
            Ok(session) => out.sessions.push(session),
            Err(e) => out.unreadable.push(Unreadable {
                id: row.get::<_, String>(0).unwrap_or_default(),
                why: e.to_string(),
            }),
        }
    }
    Ok(out)
}

impl SessionStore for SqliteStore {
    /// Inserts a session (state `created`), or returns the one created earlier with the same
    /// idempotency key. The bool is true when a new row was made.
    fn insert_session(&self, id: &str, new: &NewSession<'_>) -> Result<(String, bool), Error> {
        self.transaction(|tx| {
            if let Some(key) = new.idempotency_key {
                let existing: Option<(String, String)> = tx
                    .query_row_cached(
                        &format!(
                            "SELECT id, {REQUEST} FROM sessions WHERE idempotency_key = ?1"
                        ),
                        [key],
                        |r| Ok((r.get(0)?, r.get(1)?)),
                    )
                    .optional()?;
                if let Some((existing, request)) = existing {
                    // The IETF Idempotency-Key draft: a key reused for another request is refused.
                    if request != new.request_summary() {
                        return Err(Error::Conflict(format!(
                            "this Idempotency-Key was used for a different request (session \
                             {existing}): a new request needs a new key"
                        )));
                    }
                    return Ok((existing, false));
                }
            }
            if let Some(venue) = new.venue {
                super::joining::check_joining(tx, venue, new.convention)?;
            }
            tx.execute_cached(
                "INSERT INTO sessions (id, idempotency_key, created_ms, trials_total, setting, playback, \
                 state, adaptive_min, adaptive_k, legacy, window_frames, pose_relation, owner, venue, \
                 convention, calibration) \
                 VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16)",
                params![
                    id,
                    new.idempotency_key,
                    now_ms(),
                    new.trials_total,
                    new.settings.setting.to_string(),
                    new.playback.as_str(),
                    SessionState::Created.as_str(),
                    new.adaptive_min,
                    new.adaptive_k,
                    new.legacy as i64,
                    new.settings.window_frames,
                    new.settings.pose_relation.to_string(),
                    new.owner,
                    new.venue,
                    new.convention.name(),
                    new.calibration,
                ],
            )?;
            Ok((id.to_string(), true))
        })
    }

    fn session(&self, id: &str) -> Result<Option<Session>, Error> {
        self.with(|c| {
            c.query_row_cached(
                &format!("SELECT {COLUMNS} FROM sessions WHERE id = ?1"),
                [id],
                session_from_row,
            )
            .optional()
        })
    }

    /// The newest `limit` sessions, newest first; of token `owner` only when given. Rows
    /// that cannot be read are logged and left out.
    fn recent_sessions(&self, owner: Option<i64>, limit: u32) -> Result<Vec<Session>, Error> {
        let rows = self.recent_rows(owner, limit)?;
        for bad in &rows.unreadable {
            log::warn!("session {}: unreadable row, left out: {}", bad.id, bad.why);
        }
        Ok(rows.sessions)
    }

    /// As [`SessionStore::recent_sessions`], with the unreadable rows named.
    fn recent_rows(&self, owner: Option<i64>, limit: u32) -> Result<Rows, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(&format!(
                "SELECT {COLUMNS} FROM sessions WHERE ?1 IS NULL OR owner = ?1 \
                 ORDER BY rowid DESC LIMIT ?2"
            ))?;
            read_rows(&mut stmt, params![owner, limit])
        })
    }

    /// Sessions in any of `states`, oldest first (in the order they were created).
    fn sessions_in(&self, states: &[SessionState]) -> Result<Rows, Error> {
        let names: Vec<&str> = states.iter().map(|s| s.as_str()).collect();
        let list = serde_json::to_string(&names).unwrap_or_default();
        self.with(|c| {
            let mut stmt = c.prepare_cached(&format!(
                "SELECT {COLUMNS} FROM sessions WHERE state IN (SELECT value FROM json_each(?1)) \
                 ORDER BY created_ms, rowid"
            ))?;
            read_rows(&mut stmt, [list])
        })
    }

    /// Sessions past a retention that ends at `cutoff_ms` (ms since the epoch): finished
    /// before it, or created before it and idle since (never uploaded, or an `upload` session
    /// still waiting for trials).
    fn expired(&self, cutoff_ms: i64) -> Result<Vec<String>, Error> {
        self.with(|c| {
            let mut stmt = c.prepare_cached(
                "SELECT id FROM sessions WHERE \
                 (state IN (?2, ?3) AND finished_ms < ?1) \
                 OR (created_ms < ?1 AND (state = ?4 OR (state = ?5 AND playback = ?6))) \
                 ORDER BY created_ms",
            )?;
            let rows = stmt.query_map(
                params![
                    cutoff_ms,
                    SessionState::Done.as_str(),
                    SessionState::Failed.as_str(),
                    SessionState::Created.as_str(),
                    SessionState::Uploaded.as_str(),
                    PlaybackKind::Upload.as_str(),
                ],
                |r| r.get(0),
            )?;
            rows.collect()
        })
    }

    /// The newest session (by finish time when `done_only`), of the legacy routes when
    /// `legacy_only`, of token `owner` when given.
    fn latest_session(
        &self,
        done_only: bool,
        legacy_only: bool,
        owner: Option<i64>,
    ) -> Result<Option<String>, Error> {
        let legacy = if legacy_only { " AND legacy = 1" } else { "" };
        self.with(|c| {
            if done_only {
                let sql = format!(
                    "SELECT id FROM sessions WHERE state = ?1{legacy} AND (?2 IS NULL OR owner = ?2) \
                     ORDER BY finished_ms DESC, rowid DESC LIMIT 1"
                );
                c.query_row_cached(&sql, params![SessionState::Done.as_str(), owner], |r| {
                    r.get(0)
                })
                    .optional()
            } else {
                let sql = format!(
                    "SELECT id FROM sessions WHERE (?1 IS NULL OR owner = ?1){legacy} \
                     ORDER BY rowid DESC LIMIT 1"
                );
                c.query_row_cached(&sql, [owner], |r| r.get(0)).optional()
            }
        })
    }

    /// Removes a session with its trials and jobs (devices forget it) in one transaction.
    /// Returns whether it existed.
    fn delete_session(&self, id: &str, claim: Claim<'_>) -> Result<bool, Error> {
        self.transaction(|tx| {
            tx.execute_cached("DELETE FROM trials WHERE session_id = ?1", [id])?;
            tx.execute_cached("DELETE FROM jobs WHERE session_id = ?1", [id])?;
            tx.execute_cached("DELETE FROM share_links WHERE session_id = ?1", [id])?;
            tx.execute_cached(
                "DELETE FROM venue_contributions WHERE session_id = ?1",
                [id],
            )?;
            tx.execute_cached(
                "UPDATE devices SET session_id = NULL WHERE session_id = ?1",
                [id],
            )?;
            let deleted = tx.execute_cached("DELETE FROM sessions WHERE id = ?1", [id])? == 1;
            if deleted {
                super::deletes::record(tx, id, claim)?;
            }
            Ok(deleted)
        })
    }

    fn session_created_ms(&self, session: &str) -> Result<Option<i64>, Error> {
        self.with(|c| {
            use rusqlite::OptionalExtension;
            c.query_row_cached(
                "SELECT created_ms FROM sessions WHERE id = ?1",
                [session],
                |r| r.get(0),
            )
            .optional()
        })
    }

    fn transition(
        &self,
        id: &str,
        step: Step,
        also: StepRecord<'_>,
    ) -> Result<SessionState, Error> {
        self.transaction(|tx| {
            let row: Option<(String, String)> = tx
                .query_row_cached(
                    "SELECT state, playback FROM sessions WHERE id = ?1",
                    [id],
                    |r| Ok((r.get(0)?, r.get(1)?)),
                )
                .optional()?;
            let (state, playback) =
                row.ok_or_else(|| Error::NotFound(format!("no session {id:?}")))?;
            let unknown = |column: &str, value: &str| {
                Error::Internal(format!("session {id}: unknown {column} {value:?}"))
            };
            let before = SessionState::from_wire(&state).ok_or_else(|| unknown("state", &state))?;
            let playback = playback
                .parse::<PlaybackKind>()
                .map_err(|_| unknown("playback", &playback))?;
            let after = step.next(before, playback).ok_or(Error::Transition {
                session: id.to_string(),
                state: before.as_str(),
                action: step.describe(),
            })?;
            let finished = after.is_finished().then(now_ms);
            tx.execute_cached(
                "UPDATE sessions SET state = ?2, finished_ms = COALESCE(?3, finished_ms) WHERE id = ?1",
                params![id, after.as_str(), finished],
            )?;
            if after == SessionState::Done {
                // Its final results now enter its venue's map.
                tx.execute_cached(super::joining::FORGET_CONTRIBUTION, [id])?;
            }
            match also {
                StepRecord::Nothing => 0,
                StepRecord::RecordingBytes(bytes) => tx.execute_cached(
                    "UPDATE sessions SET recording_bytes = ?2 WHERE id = ?1",
                    params![id, bytes as i64],
                )?,
                StepRecord::ResultsTrials(trials) => tx.execute_cached(
                    "UPDATE sessions SET results_trials = ?2 WHERE id = ?1",
                    params![id, trials],
                )?,
                StepRecord::StopReason(reason) => tx.execute_cached(
                    "UPDATE sessions SET stop_reason = ?2 WHERE id = ?1",
                    params![id, reason],
                )?,
                StepRecord::Error(why) => tx.execute_cached(
                    "UPDATE sessions SET error = ?2 WHERE id = ?1",
                    params![id, why],
                )?,
            };
            Ok(before)
        })
    }

    fn fail_unreadable(&self, id: &str, why: &str) -> Result<(), Error> {
        self.with(|c| {
            c.execute_cached(
                "UPDATE sessions SET state = ?2, error = ?3, finished_ms = ?4 WHERE id = ?1",
                params![id, SessionState::Failed.as_str(), why, now_ms()],
            )
        })?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::deletes::DeleteStore;
    use sitar_estimator::{PoseRelation, Setting};

    pub(crate) fn new_session(key: Option<&str>) -> NewSession<'_> {
        NewSession {
            idempotency_key: key,
            trials_total: 5,
            playback: PlaybackKind::Upload,
            settings: EstimateSettings {
                setting: Setting::Median,
                window_frames: 20,
                pose_relation: PoseRelation::RotationAngleDeg,
            },
            adaptive_min: None,
            adaptive_k: 3,
            legacy: false,
            owner: None,
            venue: None,
            convention: sitar_core::Convention::Unity,
            calibration: None,
        }
    }

    #[test]
    fn sessions_come_back_typed_and_idempotent_after_a_reopen() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sitar.db");
        {
            let db = SqliteStore::open(&path).unwrap();
            let new = new_session(Some("k1"));
            assert_eq!(db.insert_session("a", &new).unwrap(), ("a".into(), true));
            assert_eq!(db.insert_session("b", &new).unwrap(), ("a".into(), false));
            // The same key with another request is refused, naming the key's session.
            for other in [
                NewSession {
                    trials_total: 6,
                    ..new.clone()
                },
                NewSession {
                    adaptive_min: Some(4),
                    ..new.clone()
                },
            ] {
                let err = db.insert_session("c", &other).unwrap_err();
                assert_eq!(err.status_and_code().0.as_u16(), 409, "{err}");
                assert!(err.to_string().contains("Idempotency-Key"), "{err}");
            }
            assert!(db.session("c").unwrap().is_none());
        }
        let db = SqliteStore::open(&path).unwrap();
        let session = db.session("a").unwrap().unwrap();
        assert_eq!(session.state, SessionState::Created);
        assert_eq!(session.playback, PlaybackKind::Upload);
        assert_eq!(session.settings, new_session(None).settings);
        assert_eq!((session.trials_total, session.adaptive_k), (5, 3));
        assert!(db.session("b").unwrap().is_none());
        assert_eq!(
            db.sessions_in(&[SessionState::Created])
                .unwrap()
                .sessions
                .len(),
            1
        );
        assert!(
            db.sessions_in(&[SessionState::Done])
                .unwrap()
                .sessions
                .is_empty()
        );
        assert_eq!(
            db.latest_session(false, false, None).unwrap().as_deref(),
            Some("a")
        );
        assert_eq!(db.latest_session(true, false, None).unwrap(), None);
        let claim = crate::storage::Claim {
            instance: "test",
            until_ms: i64::MAX,
        };
        assert!(db.delete_session("a", claim).unwrap());
        assert!(!db.delete_session("a", claim).unwrap());
        assert_eq!(db.unfinished_deletes().unwrap(), ["a"]);
    }

    #[test]
    fn unreadable_rows_are_named_and_left_out_of_listings() {
        let dir = tempfile::tempdir().unwrap();
        let db = SqliteStore::open(&dir.path().join("sitar.db")).unwrap();
        for id in ["a", "b", "c"] {
            db.insert_session(id, &new_session(None)).unwrap();
        }
        db.with(|c| {
            c.execute("UPDATE sessions SET trials_total = -5 WHERE id = 'a'", [])?;
            c.execute("UPDATE sessions SET playback = 'vhs' WHERE id = 'c'", [])
        })
        .unwrap();
        let rows = db.recent_rows(None, 10).unwrap();
        let ids: Vec<_> = rows.sessions.iter().map(|s| s.id.as_str()).collect();
        assert_eq!(ids, vec!["b"]);
        let bad: Vec<_> = rows.unreadable.iter().map(|u| u.id.as_str()).collect();
        assert_eq!(bad, vec!["c", "a"]);
        assert!(
            rows.unreadable[0].why.contains("vhs"),
            "{:?}",
            rows.unreadable
        );
        assert_eq!(db.recent_sessions(None, 10).unwrap().len(), 1);
        let in_flight = db.sessions_in(&[SessionState::Created]).unwrap();
        assert_eq!(
            (in_flight.sessions.len(), in_flight.unreadable.len()),
            (1, 2)
        );
        // Failing an unreadable row needs no typed row.
        db.fail_unreadable("a", "bad row").unwrap();
        let failed = db.sessions_in(&[SessionState::Failed]).unwrap();
        assert_eq!(failed.unreadable[0].id, "a");
    }

    #[test]
    fn a_value_no_server_writes_is_an_error_naming_the_column() {
        let dir = tempfile::tempdir().unwrap();
        let db = SqliteStore::open(&dir.path().join("sitar.db")).unwrap();
        db.insert_session("a", &new_session(None)).unwrap();
        db.with(|c| c.execute("UPDATE sessions SET pose_relation = 'sideways'", []))
            .unwrap();
        let err = db.session("a").unwrap_err().to_string();
        assert!(
            err.contains("sessions.pose_relation") && err.contains("sideways"),
            "{err}"
        );
    }
}
