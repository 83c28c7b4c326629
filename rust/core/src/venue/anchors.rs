//! The anchor image's observations and the session folder's `anchors.csv`.

use std::fmt::Write as _;

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::{Error, Pose};

/// The longest anchor id, in bytes.
pub const MAX_ANCHOR_ID_BYTES: usize = 64;

/// The header of a session folder's `anchors.csv`.
pub const ANCHORS_HEADER: &str = "t_ns,anchor,px,py,pz,qx,qy,qz,qw,tracking";

/// How well the platform tracked the anchor image in one observation (numbers as in the
/// C ABI).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[repr(i32)]
pub enum Tracking {
    /// Not tracked (the pose is the last known one).
    None = 0,
    /// Tracked with limited quality (AR Foundation `Limited`, ARCore `LAST_KNOWN_POSE`).
    Limited = 1,
    /// Fully tracked: the only observations alignment uses.
    Full = 2,
}

impl Tracking {
    /// `"none"`, `"limited"` or `"full"`.
    pub fn name(&self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Limited => "limited",
            Self::Full => "full",
        }
    }

    /// The inverse of [`Tracking::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "none" => Some(Self::None),
            "limited" => Some(Self::Limited),
            "full" => Some(Self::Full),
            _ => None,
        }
    }

    /// 0 none, 1 limited, 2 full; another number is an [`Error::InvalidArgument`] naming
    /// `tracking`.
    pub fn from_code(code: i32) -> Result<Self, Error> {
        match code {
            0 => Ok(Self::None),
            1 => Ok(Self::Limited),
            2 => Ok(Self::Full),
            _ => Err(Error::arg(
                "tracking",
                format!("{code} is not a tracking state (0 none, 1 limited, 2 full)"),
            )),
        }
    }
}

/// One observation of an anchor image: the pose the platform reports for it
/// (world-from-image, in the session's convention and world frame; image +X to its right).
#[derive(Debug, Clone, PartialEq)]
pub struct AnchorObservation {
    /// When it was observed (ns, the session's clock).
    pub t_ns: i64,
    /// The anchor's id (1…64 bytes, no comma, quote or control character).
    pub anchor: String,
    /// World-from-image pose.
    pub pose: Pose,
    /// Tracking state.
    pub tracking: Tracking,
}

/// Checks an anchor id: 1…[`MAX_ANCHOR_ID_BYTES`] bytes, and (so that `anchors.csv` holds it
/// as one cell) no comma, double quote or control character. The error names `anchor_id`.
pub fn check_anchor_id(id: &str) -> Result<(), Error> {
    if id.is_empty() {
        return Err(Error::arg("anchor_id", "is empty"));
    }
    if id.len() > MAX_ANCHOR_ID_BYTES {
        return Err(Error::arg(
            "anchor_id",
            format!(
                "is {} bytes long; at most {MAX_ANCHOR_ID_BYTES} are allowed",
                id.len()
            ),
        ));
    }
    if let Some(c) = id
        .chars()
        .find(|c| *c == ',' || *c == '"' || c.is_control())
    {
        return Err(Error::arg(
            "anchor_id",
            format!(
                "`{}` contains {c:?}, which anchors.csv cannot hold",
                id.escape_debug()
            ),
        ));
    }
    Ok(())
}

/// The observations as `anchors.csv` text ([`ANCHORS_HEADER`], one row per observation;
/// numbers in Rust's shortest round-trip form).
pub fn anchors_csv(observations: &[AnchorObservation]) -> String {
    let mut csv = String::from(ANCHORS_HEADER);
    csv.push('\n');
    for o in observations {
        let (p, q) = (o.pose.position, o.pose.rotation);
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{}",
            o.t_ns,
            o.anchor,
            p.x,
            p.y,
            p.z,
            q.x,
            q.y,
            q.z,
            q.w,
            o.tracking.name()
        );
    }
    csv
}

/// Parses `anchors.csv` text; errors name `source`, the line and the column.
pub fn parse_anchors_csv(text: &str, source: &str) -> Result<Vec<AnchorObservation>, Error> {
    let columns: Vec<&str> = ANCHORS_HEADER.split(',').collect();
    let mut out = Vec::new();
    for (line_no, cells) in crate::csv_rows::rows(text, source, &[ANCHORS_HEADER])? {
        let number = |j: usize| -> Result<f64, Error> {
            match cells[j].parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(Error::parse(
                    source,
                    line_no,
                    columns[j],
                    format!("`{}` is not a finite number", cells[j]),
                )),
            }
        };
        let t_ns: i64 = cells[0].parse().map_err(|_| {
            Error::parse(
                source,
                line_no,
                columns[0],
                format!("`{}` is not integer nanoseconds", cells[0]),
            )
        })?;
        check_anchor_id(cells[1])
            .map_err(|e| Error::parse(source, line_no, columns[1], e.to_string()))?;
        let pose = Pose::new(
            DVec3::new(number(2)?, number(3)?, number(4)?),
            DQuat::from_xyzw(number(5)?, number(6)?, number(7)?, number(8)?),
        )
        .validated("pose")
        .map_err(|e| Error::parse(source, line_no, "qx", e.to_string()))?;
        let tracking = Tracking::from_name(cells[9]).ok_or_else(|| {
            Error::parse(
                source,
                line_no,
                columns[9],
                format!("`{}` is not none, limited or full", cells[9]),
            )
        })?;
        out.push(AnchorObservation {
            t_ns,
            anchor: cells[1].to_owned(),
            pose,
            tracking,
        });
    }
    Ok(out)
}
