//! What one session brings to a venue map: its alignment and, in the venue frame, each
//! sub-trajectory's midpoint, camera heading, surface point and error.

use std::f64::consts::{FRAC_PI_4, FRAC_PI_8};

use glam::DVec3;

use super::{Alignment, parse_anchors_csv};
use crate::{Convention, Error, ErrorUnit, Pose, PoseRelation, Results};

/// A session's files as text, as the backend stores them (a file not uploaded is `None`).
#[derive(Debug, Clone, Copy)]
pub struct SessionFiles<'a> {
    /// The session's id (listed in the map).
    pub session: &'a str,
    /// The convention of its poses (the session config's `convention`).
    pub convention: Convention,
    /// The phone's `anchors.csv`.
    pub anchors_csv: Option<&'a str>,
    /// The phone's TUM log `trajectory.txt` (start, midpoints, endpoints; integer ns).
    pub trajectory_txt: Option<&'a str>,
    /// The phone's `subtrajectories.csv`.
    pub subtrajectories_csv: Option<&'a str>,
    /// The session's final results (JSON or legacy CSV).
    pub results_json: Option<&'a str>,
}

/// One sub-trajectory with an error, in the venue frame (coordinates in the session's
/// convention: the `convention` of [`Contribution::InMap`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Its index in the session.
    pub subtrajectory: u32,
    /// The camera position at its midpoint.
    pub position: DVec3,
    /// The camera's heading at its midpoint: the angle of its forward axis levelled onto the
    /// horizontal plane, from venue +X, counter-clockwise seen from above (radians in
    /// (−π, π]); `None` when the camera looks straight up or down.
    pub heading_rad: Option<f64>,
    /// The surface point of its depth sample, when the sample is valid.
    pub surface: Option<DVec3>,
    /// Its estimated error (m), looked up by its start as the phone does.
    pub error_m: f64,
}

impl Sample {
    /// The direction sector (0…7) of [`Sample::heading_rad`]: 45° sectors, sector 0 centred on
    /// venue +X ([−22.5°, 22.5°)), counter-clockwise seen from above.
    pub fn sector(&self) -> Option<u8> {
        self.heading_rad.map(sector_of)
    }
}

/// The 45° sector (0…7) of a heading (radians, counter-clockwise from +X seen from above):
/// `floor((θ + π/8) / (π/4)) mod 8`, so sector `k` is `[k·45° − 22.5°, k·45° + 22.5°)`.
pub fn sector_of(heading_rad: f64) -> u8 {
    ((heading_rad + FRAC_PI_8) / FRAC_PI_4)
        .floor()
        .rem_euclid(8.0) as u8
}

/// What one session brings to a venue map.
#[derive(Debug, Clone, PartialEq)]
pub enum Contribution {
    /// Aligned, with results in metres: its samples enter the cells.
    InMap {
        /// The session's id.
        session: String,
        /// The convention of its poses and of [`Sample`]'s coordinates.
        convention: Convention,
        /// Its place in the venue frame.
        alignment: Alignment,
        /// Its sub-trajectories with an error, in order.
        samples: Vec<Sample>,
    },
    /// Aligned, but it brings no cells (no results yet, results in degrees, no trajectory).
    Excluded {
        /// The session's id.
        session: String,
        /// Its place in the venue frame.
        alignment: Alignment,
        /// Why it brings no cells.
        reason: String,
    },
    /// Not in the venue frame: no usable observation of the anchor.
    NotAligned {
        /// The session's id.
        session: String,
        /// Why, in words.
        reason: String,
    },
}

impl Contribution {
    /// The session's id.
    pub fn session(&self) -> &str {
        match self {
            Self::InMap { session, .. }
            | Self::Excluded { session, .. }
            | Self::NotAligned { session, .. } => session,
        }
    }

    /// Its alignment, when it has one.
    pub fn alignment(&self) -> Option<&Alignment> {
        match self {
            Self::InMap { alignment, .. } | Self::Excluded { alignment, .. } => Some(alignment),
            Self::NotAligned { .. } => None,
        }
    }

    /// Its samples (empty unless [`Contribution::InMap`]).
    pub fn samples(&self) -> &[Sample] {
        match self {
            Self::InMap { samples, .. } => samples,
            _ => &[],
        }
    }

    /// The contribution of one session to the venue whose anchor is `anchor`.
    ///
    /// Every file given is parsed whole first: a malformed one is an [`Error::Parse`] naming
    /// the file, the line and the column, whatever else is missing. Then: without
    /// `anchors.csv` or a usable `full` observation ([`super::align`]) the session is
    /// [`Contribution::NotAligned`]; without results, with results not in metres
    /// (`trans_part`), or without `trajectory.txt` / `subtrajectories.csv` it is
    /// [`Contribution::Excluded`]. Otherwise each sub-trajectory whose start has a result
    /// window within the tolerance (the nearest window start, as [`Results::lookup`] and the
    /// phone do) becomes a [`Sample`]: its midpoint pose is the `trajectory.txt` pose stamped
    /// `mid_ns`, its surface point the `x,y,z` of a `valid` depth sample. The tolerance is
    /// half the median frame interval, the frame interval being the median gap between
    /// `trajectory.txt` stamps divided by the frames between logged poses (half the results'
    /// `window_frames`, default 10).
    pub fn from_files(files: &SessionFiles<'_>, anchor: &str) -> Result<Contribution, Error> {
        let anchors = files
            .anchors_csv
            .map(|t| parse_anchors_csv(t, "anchors.csv"))
            .transpose()?;
        let trajectory = files
            .trajectory_txt
            .map(|t| crate::tum::parse_tum_ns(t, "trajectory.txt"))
            .transpose()?;
        let rows = files
            .subtrajectories_csv
            .map(parse_subtrajectories)
            .transpose()?;
        let results = files.results_json.map(Results::parse).transpose()?;

        let session = files.session.to_owned();
        let Some(anchors) = anchors else {
            return Ok(Self::NotAligned {
                session,
                reason: "no anchors.csv was uploaded".into(),
            });
        };
        let alignment = match super::align(&anchors, anchor) {
            Ok(a) => a,
            Err(e) => {
                return Ok(Self::NotAligned {
                    session,
                    reason: e.reason,
                });
            }
        };
        let excluded = |reason: String| {
            Ok(Self::Excluded {
                session: files.session.to_owned(),
                alignment,
                reason,
            })
        };
        let Some(results) = results else {
            return excluded("it has no results yet".into());
        };
        if results.relation != PoseRelation::TransPart {
            return excluded(format!(
                "its results are {} (errors in {}); the map's cells are in metres (trans_part)",
                results.relation,
                results.unit().name()
            ));
        }
        let (Some(trajectory), Some(rows)) = (trajectory, rows) else {
            let missing = if files.trajectory_txt.is_none() {
                "trajectory.txt"
            } else {
                "subtrajectories.csv"
            };
            return excluded(format!("no {missing} was uploaded"));
        };
        let half = i128::from(results.window_frames.unwrap_or(10) / 2).max(1);
        let tolerance_ns = tolerance_ns(&trajectory, half);
        let mut by_time = trajectory;
        by_time.sort_by_key(|(t, _)| *t);
        let rotation_inverse = alignment.rotation().inverse();
        let mut samples = Vec::new();
        for row in rows {
            let Some(window) = results.lookup(row.start_ns, tolerance_ns) else {
                continue;
            };
            let pose = pose_at(&by_time, row.mid_ns).ok_or_else(|| {
                Error::parse(
                    "subtrajectories.csv",
                    row.line,
                    "mid_ns",
                    format!("{} is not a timestamp of trajectory.txt", row.mid_ns),
                )
            })?;
            let forward = rotation_inverse * (pose.rotation * files.convention.camera_forward());
            samples.push(Sample {
                subtrajectory: row.index,
                position: alignment.to_venue(pose.position),
                heading_rad: heading_seen_from_above(forward, files.convention),
                surface: row.surface.map(|p| alignment.to_venue(p)),
                error_m: window.error,
            });
        }
        Ok(Self::InMap {
            session,
            convention: files.convention,
            alignment,
            samples,
        })
    }
}

/// The heading of a venue-frame direction, counter-clockwise from +X seen from above: the
/// third axis points north of +X-east in Unity's left-handed frame and south in ARCore's
/// right-handed one, so the angle is `atan2(z, x)` or `atan2(−z, x)`. `None` when the
/// direction is (within 1e-9) vertical.
pub fn heading_seen_from_above(direction: DVec3, convention: Convention) -> Option<f64> {
    let north = match convention {
        Convention::Unity => direction.z,
        Convention::Arcore => -direction.z,
    };
    (direction.x.hypot(direction.z) > 1e-9).then(|| north.atan2(direction.x))
}

/// Half the median frame interval, from the gaps between logged poses (`half` frames apart).
fn tolerance_ns(trajectory: &[(i64, Pose)], half: i128) -> i64 {
    let mut gaps: Vec<i128> = trajectory
        .windows(2)
        .map(|w| i128::from(w[1].0) - i128::from(w[0].0))
        .collect();
    if gaps.is_empty() {
        return 0;
    }
    gaps.sort_unstable();
    let m = gaps.len() / 2;
    let median2 = if gaps.len() % 2 == 1 {
        2 * gaps[m]
    } else {
        gaps[m - 1] + gaps[m]
    };
    // median2 / 2 is the median gap; / half a frame; / 2 the tolerance.
    (median2 / (4 * half)).clamp(0, i128::from(i64::MAX)) as i64
}

/// The pose stamped exactly `t_ns` (poses sorted by time).
fn pose_at(by_time: &[(i64, Pose)], t_ns: i64) -> Option<Pose> {
    by_time
        .binary_search_by_key(&t_ns, |(t, _)| *t)
        .ok()
        .map(|i| by_time[i].1)
}

/// The columns of `subtrajectories.csv` a map needs.
struct Row {
    line: usize,
    index: u32,
    start_ns: i64,
    mid_ns: i64,
    surface: Option<DVec3>,
}

/// Parses `subtrajectories.csv` (either header of [`crate::Session::save`]); errors name the
/// file, the line and the column.
fn parse_subtrajectories(text: &str) -> Result<Vec<Row>, Error> {
    const SRC: &str = "subtrajectories.csv";
    let header = crate::subtrajectory_columns::HEADER;
    let degrees = crate::subtrajectory_columns::header(ErrorUnit::Degrees);
    let columns: Vec<&str> = header.split(',').collect();
    let at = |name: &str| columns.iter().position(|c| *c == name).unwrap_or(0);
    let mut out = Vec::new();
    for (line, cells) in crate::csv_rows::rows(text, SRC, &[header, &degrees])? {
        let int = |name: &str| -> Result<i64, Error> {
            let s = cells[at(name)];
            s.parse::<i64>()
                .map_err(|_| Error::parse(SRC, line, name, format!("`{s}` is not an integer")))
        };
        let number = |name: &str| -> Result<f64, Error> {
            let s = cells[at(name)];
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    Error::parse(SRC, line, name, format!("`{s}` is not a finite number"))
                })
        };
        let index = int("index")?;
        if index != out.len() as i64 {
            return Err(Error::parse(
                SRC,
                line,
                "index",
                format!("expected {}, found {index}", out.len()),
            ));
        }
        let surface = match cells[at("depth")] {
            "valid" => Some(DVec3::new(number("x")?, number("y")?, number("z")?)),
            "missing" | "no_depth" | "out_of_bounds" | "no_valid_neighbours" => None,
            other => {
                return Err(Error::parse(
                    SRC,
                    line,
                    "depth",
                    format!("unknown depth status `{other}`"),
                ));
            }
        };
        out.push(Row {
            line,
            index: index as u32,
            start_ns: int("start_ns")?,
            mid_ns: int("mid_ns")?,
            surface,
        });
    }
    Ok(out)
}
