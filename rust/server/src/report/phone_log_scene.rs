//! A session's scene from the phone's own log (`PUT …/trajectory.txt`, and the depth of
//! `PUT …/subtrajectories.csv` when it was sent whole): the poses the phone logged (start,
//! midpoints, endpoints) replayed through sitar-core's phone logic with the frames between
//! them on straight lines, so the sub-trajectories keep the phone's own start timestamps
//! and frame interval; each valid depth
//! sample is put back as a sample of its measured depth straight ahead, so the scene has
//! the surface points and markers the phone had (their normals face the camera: the flat
//! sample cannot carry the measured one).

use sitar_core::{Pose, Session, SessionConfig};

use crate::error::Error;
use crate::ingest::phone_log::SUBTRAJECTORIES_HEADER;
use crate::model::Session as Row;

/// The phone session replayed from `trajectory` (the stored `trajectory.txt`) with the depth
/// of `subtrajectories` (the stored `subtrajectories.csv`, if any).
pub(crate) fn from_phone_log(
    row: &Row,
    trajectory: &str,
    subtrajectories: Option<&str>,
) -> Result<Session, Error> {
    let poses = sitar_core::parse_tum_ns(trajectory, "trajectory.txt")
        .map_err(|e| Error::InvalidContent(format!("the phone's log of {}: {e}", row.id)))?;
    if poses.len() < 3 {
        return Err(Error::Conflict(format!(
            "the phone's log of {} has {} poses; a scene needs 3",
            row.id,
            poses.len()
        )));
    }
    let depths = subtrajectories.map(depth_by_index).unwrap_or_default();
    let fail = |e: sitar_core::Error| Error::InvalidContent(format!("the phone's log: {e}"));
    let frames = row.settings.window_frames.max(2);
    let config = SessionConfig::from_json(
        &serde_json::json!({
            "convention": row.convention.name(),
            "subtrajectory_frames": frames,
            "pose_relation": row.settings.pose_relation.to_string(),
            "images": false,
        })
        .to_string(),
    )
    .map_err(|e| Error::Internal(format!("phone log config: {e}")))?;
    let mut session = Session::try_new(config).map_err(fail)?;
    let (t0, p0) = poses[0];
    session.start(t0, p0).map_err(fail)?;
    // The phone logged every `frames / 2`-th frame: the frames between two logged poses are
    // put back on the straight line between them, evenly in time, so the phone logic logs
    // exactly the phone's poses at their own timestamps and its frame interval (the results'
    // lookup tolerance) is the phone's.
    let step = i64::from(frames / 2);
    for pair in poses.windows(2) {
        let ((ta, a), (tb, b)) = (pair[0], pair[1]);
        if tb - ta < step {
            return Err(Error::InvalidContent(format!(
                "the phone's log of {}: poses {ta} and {tb} are closer than {step} ns, the \
                 {step} frames between them",
                row.id
            )));
        }
        for j in 1..=step {
            let share = j as f64 / step as f64;
            let t = ta + ((i128::from(tb - ta) * i128::from(j)) / i128::from(step)) as i64;
            let pose = if j == step {
                b
            } else {
                Pose::new(
                    a.position.lerp(b.position, share),
                    a.rotation.slerp(b.rotation, share),
                )
            };
            let flags = session.frame(t, pose).map_err(fail)?;
            if flags.is_midpoint()
                && let Some(k) = session.subtrajectories().last().map(|s| s.index as usize)
                && let Some(Some(depth_m)) = depths.get(k)
            {
                super::flat_depth::flat_depth_sample(&mut session, *depth_m);
            }
        }
    }
    let (t, pose) = poses[poses.len() - 1];
    session.stop(t, pose).map_err(fail)?;
    Ok(session)
}

/// Each row's valid depth (m) by sub-trajectory index, from a whole `subtrajectories.csv`
/// (checked on arrival); a table of spans only has none.
fn depth_by_index(text: &str) -> Vec<Option<f64>> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").trim_end().split(',').collect();
    let whole: Vec<&str> = SUBTRAJECTORIES_HEADER.split(',').collect();
    if header.len() != whole.len() || header[..21] != whole[..21] {
        return Vec::new();
    }
    let mut out = Vec::new();
    for line in lines {
        let cells: Vec<&str> = line.trim_end().split(',').collect();
        let Some(index) = cells.first().and_then(|c| c.parse::<usize>().ok()) else {
            continue;
        };
        let depth = (cells.get(4) == Some(&"valid"))
            .then(|| cells.get(7).and_then(|c| c.parse::<f64>().ok()))
            .flatten();
        if index >= out.len() {
            out.resize(index + 1, None);
        }
        out[index] = depth;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depths_are_read_by_index_from_a_whole_table_only() {
        let valid = "valid,128,96,1.5,1.52,0.1,0.2,-1.5,0,0,1,0.3,1.4,-2.1,0,0,1";
        let missing = format!("missing{}", ",".repeat(16));
        let text = format!(
            "{SUBTRAJECTORIES_HEADER}\n0,100,150,200,{valid},0.03,low\n2,300,350,,{missing},,\n1,200,250,300,{valid},,\n"
        );
        assert_eq!(depth_by_index(&text), vec![Some(1.5), Some(1.5), None]);
        assert!(depth_by_index("index,start_ns,end_ns\n0,1,2\n").is_empty());
    }
}
