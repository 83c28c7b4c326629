//! A trial's way in, for trials from the API and from playback phones alike: parsed once from
//! the bytes received, checked, written once as its file, and kept parsed in the session's
//! live session (`estimate/live_sessions.rs`) for every estimate after.

use sitar_estimator::Trajectory;

use crate::error::Error;
use crate::estimate::live_sessions::LiveSession;
use crate::storage::keys::SessionObject;
use crate::storage::{BlobStore, StoreRefs};

/// Parses one trial's TUM text from the bytes received; the error names `source`, the line
/// and the column.
pub(crate) fn parse_trial(bytes: &[u8], source: &str) -> Result<Trajectory, Error> {
    parse_run(bytes, source, 2)
}

/// Parses a run's TUM text as [`parse_trial`] does, with at least `min_poses` poses (a
/// trial needs 2; the phone's walk may be its start pose alone).
pub(crate) fn parse_run(bytes: &[u8], source: &str, min_poses: usize) -> Result<Trajectory, Error> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| Error::InvalidContent(format!("trajectory is not UTF-8 text: {e}")))?;
    let mut trial = sitar_estimator::parse_tum(text, source)
        .map_err(|e| Error::InvalidContent(e.to_string()))?;
    if trial.len() < min_poses {
        return Err(Error::InvalidContent(format!(
            "{source}: a trial needs at least {min_poses} poses, found {}",
            trial.len()
        )));
    }
    if trial
        .positions
        .iter()
        .any(|p| p.to_array().into_iter().any(out_of_bounds))
    {
        return Err(Error::InvalidContent(absurd_position(text, source)));
    }
    // Held in memory for the session's life: no spare capacity (64 bytes a pose).
    trial.stamps.shrink_to_fit();
    trial.positions.shrink_to_fit();
    trial.orientations.shrink_to_fit();
    Ok(trial)
}

/// The largest position coordinate a trial may have, in metres: a room-scale AR session is
/// metres across; beyond this a value is a unit or encoding error whose errors would overflow.
pub(crate) const MAX_POSITION_M: f64 = 1e6;

fn out_of_bounds(v: f64) -> bool {
    !v.is_finite() || v.abs() > MAX_POSITION_M
}

/// Names the first line of `text` whose position is out of bounds (the parser has checked
/// every line's form already).
fn absurd_position(text: &str, source: &str) -> String {
    let line = text.split('\n').enumerate().find(|(_, line)| {
        let data = line.split('#').next().unwrap_or("");
        data.split_whitespace()
            .skip(1)
            .take(3)
            .filter_map(|t| t.parse::<f64>().ok())
            .any(out_of_bounds)
    });
    match line {
        Some((i, _)) => format!(
            "{source}:{}: a position coordinate is beyond ±{MAX_POSITION_M:e} m",
            i + 1
        ),
        None => format!("{source}: a position coordinate is beyond ±{MAX_POSITION_M:e} m"),
    }
}

/// Where a trial comes from.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Arrival<'a> {
    /// The request's `Idempotency-Key` (API uploads).
    pub key: Option<&'a str>,
    /// Its playback index (phones; API uploads take their storage index).
    pub play_index: Option<u32>,
    /// Which device made it (`upload`, `sim:0`, `adb:SERIAL`).
    pub source: &'a str,
    /// An earlier attempt to store it failed at the metadata store. Had that attempt
    /// committed before its answer was lost, the row is there now but the trial never
    /// joined `live`: it joins it then.
    pub retried: bool,
}

/// Stores a parsed trial under the next index: its memory is counted in `live` first (a
/// refusal stores nothing), then `bytes` are written once as the trial's file, its row
/// commits, and the parsed trial joins `live`. With an idempotency key seen before, returns
/// the earlier index and stores nothing (the bool is false).
pub(crate) fn store_trial(
    stores: StoreRefs<'_>,
    live: &LiveSession,
    id: &str,
    arrival: Arrival<'_>,
    bytes: &[u8],
    trial: Trajectory,
) -> Result<(u32, bool), Error> {
    let Arrival {
        key,
        play_index,
        source,
        retried,
    } = arrival;
    let reservation = live.reserve(crate::estimate::held_trials::trial_bytes(&trial))?;
    let (index, created) =
        stores
            .db
            .add_trial(id, key, play_index, trial.len(), source, &mut |index| {
                stores.blobs.put(id, SessionObject::Trial(index), bytes)
            })?;
    if created || retried {
        live.add(play_index.unwrap_or(index), index, trial, reservation);
    }
    Ok((index, created))
}

/// Trial `index` of session `id` as stored; a trial its row names but the store lacks is an
/// internal error naming it.
pub(crate) fn read_trial(blobs: &dyn BlobStore, id: &str, index: u32) -> Result<Vec<u8>, Error> {
    blobs
        .get(id, SessionObject::Trial(index))?
        .ok_or_else(|| Error::Internal(format!("session {id}: trial {index} is missing")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_absurd_position_is_refused_naming_its_line() {
        let text = "# t x y z qx qy qz qw\n0 0 0 0 0 0 0 1\n1 0 1e308 0 0 0 0 1\n";
        let e = parse_trial(text.as_bytes(), "t.tum").unwrap_err();
        assert!(matches!(e, Error::InvalidContent(_)), "{e}");
        assert!(e.to_string().starts_with("t.tum:3: "), "{e}");
        let text = "0 0 0 0 0 0 0 1\n1 -1000001 0 0 0 0 0 1\n";
        assert!(
            parse_trial(text.as_bytes(), "t")
                .unwrap_err()
                .to_string()
                .starts_with("t:2: ")
        );
        let text = "0 0 0 0 0 0 0 1\n1 -999999 0 0 0 0 0 1\n";
        assert_eq!(parse_trial(text.as_bytes(), "t").unwrap().len(), 2);
        let text = "0 0 0 0 0 0 0 1\n1 inf 0 0 0 0 0 1\n";
        assert!(matches!(
            parse_trial(text.as_bytes(), "t"),
            Err(Error::InvalidContent(_))
        ));
    }
}
