//! The venue map document (`map.json`) and its cells in a session's world frame.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::{Alignment, check_anchor_id};
use crate::{Convention, Error, ErrorClass};

/// A map cell's kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[repr(i32)]
pub enum CellKind {
    /// Where cameras were: the midpoint positions of sub-trajectories.
    Path = 0,
    /// What cameras looked at: the surface points of valid depth samples.
    Surface = 1,
}

/// One cell of a venue map, in the venue frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VenueCell {
    /// The cell's centre `[x, y, z]` in the venue frame (m).
    pub center: [f64; 3],
    /// `path` or `surface`.
    pub kind: CellKind,
    /// Sessions with a sub-trajectory in it.
    pub sessions: u32,
    /// Sub-trajectories in it.
    pub subtrajectories: u32,
    /// The 30 % trimmed mean of their errors (m).
    pub error_m: f64,
    /// The class of `error_m` by the default thresholds.
    pub class: ErrorClass,
    /// Sub-trajectories by the camera's heading in 8 sectors of 45° (sector 0 centred on
    /// venue +X, counter-clockwise seen from above).
    pub directions: [u32; 8],
}

/// One session of a venue map: aligned (with its spread) or not (with the reason).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum VenueSession {
    /// In the map. (Listed first: an untagged enum tries its variants in order.)
    Aligned {
        /// The server session id.
        id: String,
        /// Always true here.
        aligned: bool,
        /// `full` observations used.
        observations: u32,
        /// RMS position deviation (m).
        position_spread_m: f64,
        /// RMS heading deviation (degrees).
        heading_spread_deg: f64,
        /// Sub-trajectories it brought into the cells.
        subtrajectories: u32,
    },
    /// Out of the map.
    NotAligned {
        /// The server session id.
        id: String,
        /// Always false here.
        aligned: bool,
        /// Why (e.g. the anchor was never fully tracked).
        reason: String,
    },
}

/// The backend's `GET /v1/venues/{id}/map.json`: coordinates in the venue frame, errors in
/// metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VenueMap {
    /// The venue id (`v` and 16 hex digits).
    pub id: String,
    /// Its name.
    pub name: String,
    /// The anchor id its sessions observe.
    pub anchor: String,
    /// Cell edge (m, 0.05…2).
    pub cell_m: f64,
    /// The convention its sessions share.
    pub convention: Convention,
    /// Always `"m"`.
    pub unit: String,
    /// Its sessions.
    pub sessions: Vec<VenueSession>,
    /// Its cells.
    pub cells: Vec<VenueCell>,
}

impl VenueMap {
    /// Parses and checks `map.json`: unknown keys, wrong types, a `unit` other than `"m"`, a
    /// `cell_m` outside 0.05…2, a non-finite centre or a negative error, or a session whose
    /// `aligned` does not fit its fields are [`Error::Parse`] naming the key (its JSON path)
    /// and the line.
    pub fn from_json(text: &str) -> Result<Self, Error> {
        const SRC: &str = "map.json";
        let de = &mut serde_json::Deserializer::from_str(text);
        let map: VenueMap = serde_path_to_error::deserialize(de).map_err(|e| {
            let line = e.inner().line();
            Error::parse(SRC, line, e.path().to_string(), e.into_inner().to_string())
        })?;
        let bad =
            |field: String, message: String| Err::<Self, _>(Error::parse(SRC, 0, field, message));
        if map.unit != "m" {
            return bad("unit".into(), format!("`{}` is not \"m\"", map.unit));
        }
        if !(0.05..=2.0).contains(&map.cell_m) {
            return bad(
                "cell_m".into(),
                format!("{} is not within 0.05…2", map.cell_m),
            );
        }
        if let Err(e) = check_anchor_id(&map.anchor) {
            return bad("anchor".into(), e.to_string());
        }
        for (i, s) in map.sessions.iter().enumerate() {
            let (aligned, expected) = match s {
                VenueSession::Aligned { aligned, .. } => (*aligned, true),
                VenueSession::NotAligned { aligned, .. } => (*aligned, false),
            };
            if aligned != expected {
                return bad(
                    format!("sessions[{i}].aligned"),
                    format!("is {aligned} but the session has the fields of aligned={expected}"),
                );
            }
        }
        for (i, c) in map.cells.iter().enumerate() {
            if !c.center.iter().all(|v| v.is_finite()) {
                return bad(format!("cells[{i}].center"), "is not finite".into());
            }
            if !(c.error_m.is_finite() && c.error_m >= 0.0) {
                return bad(
                    format!("cells[{i}].error_m"),
                    format!("{} is not a finite number ≥ 0", c.error_m),
                );
            }
        }
        Ok(map)
    }

    /// The map as JSON (what the backend serves).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }
}

/// A venue cell in a session's world frame ([`crate::Session::venue_cells`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldCell {
    /// Its centre in the session's world frame.
    pub position: DVec3,
    /// `path` or `surface`.
    pub kind: CellKind,
    /// Its class.
    pub class: ErrorClass,
    /// Sessions with a sub-trajectory in it.
    pub sessions: u32,
    /// Its error (m).
    pub error_m: f64,
}

/// The map's cells in the world frame of a session with `alignment`, in the map's order.
pub fn world_cells(map: &VenueMap, alignment: &Alignment) -> Vec<WorldCell> {
    map.cells
        .iter()
        .map(|c| WorldCell {
            position: alignment.to_world(DVec3::from_array(c.center)),
            kind: c.kind,
            class: c.class,
            sessions: c.sessions,
            error_m: c.error_m,
        })
        .collect()
}
