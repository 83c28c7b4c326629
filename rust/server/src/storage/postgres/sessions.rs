//! The `sessions` table in Postgres: as `storage::sqlite::sessions`, with `seq` for SQLite's
//! rowid and row locks (`FOR UPDATE`) where SQLite relied on one writer at a time.

use postgres::Row;
use postgres::types::ToSql;

use super::{PgStore, u32_column};
use crate::error::Error;
use crate::model::{
    NewSession, PlaybackKind, Session, SessionState, Step,
    estimate_settings::{self, EstimateSettings},
};
use crate::storage::deletes::Claim;
use crate::storage::metadata::{Rows, SessionStore, StepRecord, Unreadable};
use crate::storage::now_ms;

pub(super) const COLUMNS: &str = "id, trials_total, setting, playback, state, error, stop_reason, \
     adaptive_min, adaptive_k, recording_bytes, results_trials, legacy, window_frames, pose_relation, \
     owner, venue, convention, calibration";

/// What makes two session requests the same, as one text; must match
/// [`NewSession::request_summary`].
const REQUEST: &str = "trials_total || '/' || playback || '/' || setting || '/' || window_frames \
     || '/' || pose_relation || '/' || COALESCE(adaptive_min::text, '-') || '/' || adaptive_k \
     || '/' || (CASE WHEN legacy THEN '1' ELSE '0' END) || '/' || COALESCE(venue, '-') \
     || '/' || convention || '/' || COALESCE(calibration, '-')";

/// A text column parsed into its type; a value no version writes is an error naming it.
fn typed<T>(
    r: &Row,
    index: usize,
    column: &str,
    parse: impl FnOnce(&str) -> Option<T>,
) -> Result<T, String> {
    let text: String = r
        .try_get(index)
        .map_err(|e| format!("sessions.{column}: {e}"))?;
    parse(&text).ok_or_else(|| format!("sessions.{column}: unknown value {text:?}"))
}

fn optional_u32(r: &Row, index: usize, column: &str) -> Result<Option<u32>, String> {
    let value: Option<i64> = r
        .try_get(index)
        .map_err(|e| format!("sessions.{column}: {e}"))?;
    value
        .map(|v| u32::try_from(v).map_err(|_| format!("sessions.{column}: {v} is out of range")))
        .transpose()
}

fn session_from_row(r: &Row) -> Result<Session, String> {
    let get = |e: postgres::Error| e.to_string();
    Ok(Session {
        id: r.try_get(0).map_err(get)?,
        trials_total: u32_column(r, 1, "sessions.trials_total")?,
        settings: EstimateSettings {
            setting: typed(r, 2, "setting", |s| {
                estimate_settings::parse_setting(s).ok()
            })?,
            window_frames: u32_column(r, 12, "sessions.window_frames")?,
            pose_relation: typed(r, 13, "pose_relation", |s| {
                estimate_settings::parse_pose_relation(s).ok()
            })?,
        },
        playback: typed(r, 3, "playback", |s| s.parse::<PlaybackKind>().ok())?,
        state: typed(r, 4, "state", SessionState::from_wire)?,
        error: r.try_get(5).map_err(get)?,
        stop_reason: r.try_get(6).map_err(get)?,
        adaptive_min: optional_u32(r, 7, "adaptive_min")?,
        adaptive_k: u32_column(r, 8, "sessions.adaptive_k")?,
        recording_bytes: r
            .try_get::<_, Option<i64>>(9)
            .map_err(get)?
            .map(|b| b.max(0) as u64),
        results_trials: u32_column(r, 10, "sessions.results_trials")?,
        legacy: r.try_get(11).map_err(get)?,
        owner: r.try_get(14).map_err(get)?,
        venue: r.try_get(15).map_err(get)?,
        convention: typed(r, 16, "convention", super::joining::parse_convention)?,
        calibration: r.try_get(17).map_err(get)?,
    })
}

/// Sorts rows into the readable and the rest.
pub(super) fn read_rows(rows: Vec<Row>) -> Rows {
    let mut out = Rows::default();
    for row in rows {
        match session_from_row(&row) {
            Ok(session) => out.sessions.push(session),
            Err(why) => out.unreadable.push(Unreadable {
                id: row.try_get::<_, String>(0).unwrap_or_default(),
                why,
            }),
        }
    }
    out
}

/// Owned copies of a new session's values, for a connection thread.
struct NewRow {
    key: Option<String>,
    summary: String,
    venue: Option<String>,
    convention: sitar_core::Convention,
    calibration: Option<String>,
    values: (
        i64,
        String,
        String,
        Option<i64>,
        i64,
        bool,
        i64,
        String,
        Option<i64>,
    ),
}

impl SessionStore for PgStore {
    fn insert_session(&self, id: &str, new: &NewSession<'_>) -> Result<(String, bool), Error> {
        let id = id.to_string();
        let row = NewRow {
            key: new.idempotency_key.map(str::to_string),
            summary: new.request_summary(),
            venue: new.venue.map(str::to_string),
            convention: new.convention,
            calibration: new.calibration.map(str::to_string),
            values: (
                i64::from(new.trials_total),
                new.settings.setting.to_string(),
                new.playback.as_str().to_string(),
                new.adaptive_min.map(i64::from),
                i64::from(new.adaptive_k),
                new.legacy,
                i64::from(new.settings.window_frames),
                new.settings.pose_relation.to_string(),
                new.owner,
            ),
        };
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            let (total, setting, playback, min, k, legacy, frames, relation, owner) = &row.values;
            // The session made earlier with this key, if any, checked against this request.
            let earlier = |tx: &mut postgres::Transaction<'_>| -> Result<Option<String>, Error> {
                let Some(existing) = tx.query_opt(
                    &format!("SELECT id, {REQUEST} FROM sessions WHERE idempotency_key = $1"),
                    &[&row.key],
                )?
                else {
                    return Ok(None);
                };
                let (existing, request): (String, String) = (existing.get(0), existing.get(1));
                // The IETF Idempotency-Key draft: a key reused for another request is refused.
                if request != row.summary {
                    return Err(Error::Conflict(format!(
                        "this Idempotency-Key was used for a different request (session \
                         {existing}): a new request needs a new key"
                    )));
                }
                Ok(Some(existing))
            };
            if row.key.is_some()
                && let Some(existing) = earlier(&mut tx)?
            {
                return Ok((existing, false));
            }
            if let Some(venue) = &row.venue {
                super::joining::check_joining(&mut tx, venue, row.convention)?;
            }
            // ON CONFLICT: two instances given the same key at once make one session.
            let inserted = tx.query_opt(
                "INSERT INTO sessions (id, idempotency_key, created_ms, trials_total, setting, \
                 playback, state, adaptive_min, adaptive_k, legacy, window_frames, pose_relation, \
                 owner, venue, convention, calibration) \
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16) \
                 ON CONFLICT (idempotency_key) DO NOTHING RETURNING id",
                &[
                    &id,
                    &row.key,
                    &now_ms(),
                    total,
                    setting,
                    playback,
                    &SessionState::Created.as_str(),
                    min,
                    k,
                    legacy,
                    frames,
                    relation,
                    owner,
                    &row.venue,
                    &row.convention.name(),
                    &row.calibration,
                ],
            )?;
            if inserted.is_some() {
                tx.commit()?;
                return Ok((id.clone(), true));
            }
            // Another instance made it with this key meanwhile.
            match earlier(&mut tx)? {
                Some(existing) => Ok((existing, false)),
                None => Err(Error::Conflict(
                    "this Idempotency-Key's session was deleted as it was made; retry".into(),
                )),
            }
        })
    }

    fn session(&self, id: &str) -> Result<Option<Session>, Error> {
        let id = id.to_string();
        self.pool.run(move |c| {
            let row = c.query_opt(
                &format!("SELECT {COLUMNS} FROM sessions WHERE id = $1"),
                &[&id],
            )?;
            row.map(|r| session_from_row(&r).map_err(Error::Database))
                .transpose()
        })
    }

    fn recent_sessions(&self, owner: Option<i64>, limit: u32) -> Result<Vec<Session>, Error> {
        let rows = self.recent_rows(owner, limit)?;
        for bad in &rows.unreadable {
            log::warn!("session {}: unreadable row, left out: {}", bad.id, bad.why);
        }
        Ok(rows.sessions)
    }

    fn recent_rows(&self, owner: Option<i64>, limit: u32) -> Result<Rows, Error> {
        self.pool.run(move |c| {
            let rows = c.query(
                &format!(
                    "SELECT {COLUMNS} FROM sessions WHERE $1::BIGINT IS NULL OR owner = $1 \
                     ORDER BY seq DESC LIMIT $2"
                ),
                &[&owner, &i64::from(limit)],
            )?;
            Ok(read_rows(rows))
        })
    }

    fn sessions_in(&self, states: &[SessionState]) -> Result<Rows, Error> {
        let names: Vec<String> = states.iter().map(|s| s.as_str().to_string()).collect();
        self.pool.run(move |c| {
            let rows = c.query(
                &format!(
                    "SELECT {COLUMNS} FROM sessions WHERE state = ANY($1) ORDER BY created_ms, seq"
                ),
                &[&names],
            )?;
            Ok(read_rows(rows))
        })
    }

    fn expired(&self, cutoff_ms: i64) -> Result<Vec<String>, Error> {
        self.pool.run(move |c| {
            let rows = c.query(
                "SELECT id FROM sessions WHERE \
                 (state IN ($2, $3) AND finished_ms < $1) \
                 OR (created_ms < $1 AND (state = $4 OR (state = $5 AND playback = $6))) \
                 ORDER BY created_ms",
                &[
                    &cutoff_ms,
                    &SessionState::Done.as_str(),
                    &SessionState::Failed.as_str(),
                    &SessionState::Created.as_str(),
                    &SessionState::Uploaded.as_str(),
                    &PlaybackKind::Upload.as_str(),
                ],
            )?;
            Ok(rows.iter().map(|r| r.get(0)).collect())
        })
    }

    fn latest_session(
        &self,
        done_only: bool,
        legacy_only: bool,
        owner: Option<i64>,
    ) -> Result<Option<String>, Error> {
        let legacy = if legacy_only { " AND legacy" } else { "" };
        self.pool.run(move |c| {
            let row = if done_only {
                c.query_opt(
                    &format!(
                        "SELECT id FROM sessions WHERE state = $1{legacy} \
                         AND ($2::BIGINT IS NULL OR owner = $2) \
                         ORDER BY finished_ms DESC NULLS LAST, seq DESC LIMIT 1"
                    ),
                    &[&SessionState::Done.as_str(), &owner],
                )?
            } else {
                c.query_opt(
                    &format!(
                        "SELECT id FROM sessions WHERE ($1::BIGINT IS NULL OR owner = $1){legacy} \
                         ORDER BY seq DESC LIMIT 1"
                    ),
                    &[&owner],
                )?
            };
            Ok(row.map(|r| r.get(0)))
        })
    }

    fn session_created_ms(&self, session: &str) -> Result<Option<i64>, Error> {
        let id = session.to_string();
        self.pool.run(move |c| {
            Ok(
                c.query_opt("SELECT created_ms FROM sessions WHERE id = $1", &[&id])?
                    .map(|r| r.get(0)),
            )
        })
    }

    fn delete_session(&self, id: &str, claim: Claim<'_>) -> Result<bool, Error> {
        let id = id.to_string();
        let (instance, until_ms) = (claim.instance.to_string(), claim.until_ms);
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            tx.execute("DELETE FROM trials WHERE session_id = $1", &[&id])?;
            tx.execute("DELETE FROM jobs WHERE session_id = $1", &[&id])?;
            tx.execute("DELETE FROM share_links WHERE session_id = $1", &[&id])?;
            tx.execute(
                "DELETE FROM venue_contributions WHERE session_id = $1",
                &[&id],
            )?;
            tx.execute(
                "UPDATE devices SET session_id = NULL WHERE session_id = $1",
                &[&id],
            )?;
            let deleted = tx.execute("DELETE FROM sessions WHERE id = $1", &[&id])? == 1;
            if deleted {
                tx.execute(
                    "INSERT INTO unfinished_deletes (session_id, deleted_ms, claimed_by, \
                     claimed_until_ms) VALUES ($1, $2, $3, $4) ON CONFLICT (session_id) DO NOTHING",
                    &[&id, &now_ms(), &instance, &until_ms],
                )?;
            }
            tx.commit()?;
            Ok(deleted)
        })
    }

    fn transition(
        &self,
        id: &str,
        step: Step,
        also: StepRecord<'_>,
    ) -> Result<SessionState, Error> {
        let id = id.to_string();
        // The record's value as an owned column and value, for the connection thread.
        let (column, value): (Option<&'static str>, Option<Box<dyn ToSql + Send + Sync>>) =
            match also {
                StepRecord::Nothing => (None, None),
                StepRecord::RecordingBytes(b) => (
                    Some("recording_bytes"),
                    Some(Box::new(i64::try_from(b).unwrap_or(i64::MAX))),
                ),
                StepRecord::ResultsTrials(t) => {
                    (Some("results_trials"), Some(Box::new(i64::from(t))))
                }
                StepRecord::StopReason(r) => (Some("stop_reason"), Some(Box::new(r.to_string()))),
                StepRecord::Error(e) => (Some("error"), Some(Box::new(e.to_string()))),
            };
        self.pool.run(move |c| {
            let mut tx = c.transaction()?;
            // The row lock makes the check and the write one step: racing instances queue.
            let row = tx.query_opt(
                "SELECT state, playback FROM sessions WHERE id = $1 FOR UPDATE",
                &[&id],
            )?;
            let row = row.ok_or_else(|| Error::NotFound(format!("no session {id:?}")))?;
            let (state, playback): (String, String) = (row.get(0), row.get(1));
            let unknown = |column: &str, value: &str| {
                Error::Internal(format!("session {id}: unknown {column} {value:?}"))
            };
            let before = SessionState::from_wire(&state).ok_or_else(|| unknown("state", &state))?;
            let playback = playback
                .parse::<PlaybackKind>()
                .map_err(|_| unknown("playback", &playback))?;
            let after = step.next(before, playback).ok_or(Error::Transition {
                session: id.clone(),
                state: before.as_str(),
                action: step.describe(),
            })?;
            let finished = after.is_finished().then(now_ms);
            tx.execute(
                "UPDATE sessions SET state = $2, finished_ms = COALESCE($3, finished_ms) WHERE id = $1",
                &[&id, &after.as_str(), &finished],
            )?;
            if let (Some(column), Some(value)) = (column, &value) {
                let value: &(dyn ToSql + Sync) = &**value;
                tx.execute(&format!("UPDATE sessions SET {column} = $2 WHERE id = $1"), &[&id, value])?;
            }
            if after == SessionState::Done {
                // Its final results now enter its venue's map.
                tx.execute(super::joining::FORGET_CONTRIBUTION, &[&id])?;
            }
            tx.commit()?;
            Ok(before)
        })
    }

    fn fail_unreadable(&self, id: &str, why: &str) -> Result<(), Error> {
        let (id, why) = (id.to_string(), why.to_string());
        self.pool.run(move |c| {
            c.execute(
                "UPDATE sessions SET state = $2, error = $3, finished_ms = $4 WHERE id = $1",
                &[&id, &SessionState::Failed.as_str(), &why, &now_ms()],
            )?;
            Ok(())
        })
    }
}
