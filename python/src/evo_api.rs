//! The fast parts of `sitar.evo` (evo's Python API) besides reading text matrices
//! (`matrix`, `matrix_rows`): APE/RPE error arrays of two associated pose sequences, and pose
//! topics of ROS bags. Arrays cross as raw float64 bytes (numpy's `tobytes`/`frombuffer`): no
//! numpy crate, no copies per pose.

use std::path::PathBuf;

use glam::{DQuat, DVec3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use sitar_estimator::{DeltaUnit, PoseRelation, RpeOptions, TimeUnit, Trajectory};

use crate::SitarError;
use crate::matrix::py_bytes;

/// float64 values from native-endian bytes, checking the count is a multiple of `width`.
fn floats(bytes: &[u8], width: usize, what: &str) -> PyResult<Vec<f64>> {
    if !bytes.len().is_multiple_of(8 * width) {
        return Err(PyValueError::new_err(format!(
            "{what}: {} bytes are not rows of {width} float64",
            bytes.len()
        )));
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|c| f64::from_ne_bytes(c.try_into().expect("8 bytes")))
        .collect())
}

/// A pose sequence from positions (n×3) and quaternions (n×4, w x y z; normalised here, as
/// evo's `quaternion_matrix` does when it builds `poses_se3`). Stamps are indices: the
/// metrics pair poses by index.
fn poses(xyz: &[u8], wxyz: &[u8], what: &str) -> PyResult<Trajectory> {
    let p = floats(xyz, 3, what)?;
    let q = floats(wxyz, 4, what)?;
    if p.len() / 3 != q.len() / 4 {
        return Err(PyValueError::new_err(format!(
            "{what}: {} positions but {} orientations",
            p.len() / 3,
            q.len() / 4
        )));
    }
    let positions = p.chunks_exact(3).map(DVec3::from_slice).collect();
    let orientations = q
        .chunks_exact(4)
        .map(|q| {
            let quat = DQuat::from_xyzw(q[1], q[2], q[3], q[0]);
            let norm = quat.length();
            if norm > 0.0 { quat / norm } else { quat }
        })
        .collect();
    Ok(Trajectory {
        stamps: (0..p.len() as i64 / 3).collect(),
        positions,
        orientations,
        time_unit: TimeUnit::Seconds,
    })
}

fn relation(name: &str) -> PyResult<PoseRelation> {
    name.parse()
        .map_err(|e: sitar_estimator::Error| PyValueError::new_err(e.to_string()))
}

fn estimator_error(e: sitar_estimator::Error) -> PyErr {
    SitarError::new_err(e.to_string())
}

/// evo's `APE.process_data` error array: `relation` (`trans_part`, `rot_part`, `full`,
/// `angle_deg`, `angle_rad`, `point_distance`) of `E_i = P_i⁻¹·Q_i` for every pose.
#[pyfunction]
pub fn ape_errors(
    py: Python<'_>,
    ref_xyz: &[u8],
    ref_wxyz: &[u8],
    est_xyz: &[u8],
    est_wxyz: &[u8],
    pose_relation: &str,
) -> PyResult<Py<PyBytes>> {
    let relation = relation(pose_relation)?;
    let reference = poses(ref_xyz, ref_wxyz, "reference")?;
    let estimate = poses(est_xyz, est_wxyz, "estimate")?;
    let errors = py
        .allow_threads(|| sitar_estimator::ape(&reference, &estimate, relation))
        .map_err(estimator_error)?;
    Ok(py_bytes(py, &errors.errors)?.unbind())
}

/// evo's `RPE.process_data`: the error array and the index pairs `(i, j)` (int64, flat) of
/// `delta` in `delta_unit` (`f`, `m`, `d`, `r`), chosen on the estimate or the reference.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
pub fn rpe_errors(
    py: Python<'_>,
    ref_xyz: &[u8],
    ref_wxyz: &[u8],
    est_xyz: &[u8],
    est_wxyz: &[u8],
    pose_relation: &str,
    delta: f64,
    delta_unit: &str,
    rel_delta_tol: f64,
    all_pairs: bool,
    pairs_from_reference: bool,
) -> PyResult<(Py<PyBytes>, Py<PyBytes>)> {
    let delta_unit = match delta_unit {
        "f" => DeltaUnit::Frames,
        "m" => DeltaUnit::Meters,
        "d" => DeltaUnit::Degrees,
        "r" => DeltaUnit::Radians,
        other => {
            return Err(PyValueError::new_err(format!(
                "unsupported delta unit: {other}"
            )));
        }
    };
    let options = RpeOptions {
        pose_relation: relation(pose_relation)?,
        delta,
        delta_unit,
        all_pairs,
        rel_delta_tol,
        pairs_from_reference,
    };
    let reference = poses(ref_xyz, ref_wxyz, "reference")?;
    let estimate = poses(est_xyz, est_wxyz, "estimate")?;
    let errors = py
        .allow_threads(|| sitar_estimator::rpe(&reference, &estimate, &options))
        .map_err(estimator_error)?;
    let pairs: Vec<u8> = errors
        .pairs
        .iter()
        .flat_map(|&(i, j)| [i as i64, j as i64])
        .flat_map(i64::to_ne_bytes)
        .collect();
    Ok((
        py_bytes(py, &errors.errors)?.unbind(),
        PyBytes::new(py, &pairs).unbind(),
    ))
}

/// The messages of `topic` in a ROS 1 bag (`.bag`) or a ROS 2 MCAP bag (an `.mcap` file or
/// a bag directory holding one), as evo's `read_bag_trajectory` reads them: stamps (header,
/// `sec + nanosec·1e-9`), positions, quaternions (w x y z) as float64 bytes, and the first
/// message's `frame_id`. ROS 2 `.db3` bags need SQLite: the sitar command reads them.
#[allow(clippy::type_complexity)]
#[pyfunction]
pub fn read_bag_topic(
    py: Python<'_>,
    path: PathBuf,
    topic: &str,
) -> PyResult<(Py<PyBytes>, Py<PyBytes>, Py<PyBytes>, String)> {
    let (stamps, xyz, wxyz, frame_id) = py
        .allow_threads(|| -> Result<_, String> {
            let shown = path.display().to_string();
            let wanted = |t: &str| t == topic;
            let file = if path.is_dir() {
                let mut found: Vec<PathBuf> = std::fs::read_dir(&path)
                    .map_err(|e| format!("{shown}: {e}"))?
                    .filter_map(|e| e.ok().map(|e| e.path()))
                    .filter(|p| p.extension().is_some_and(|x| x == "mcap" || x == "db3"))
                    .collect();
                found.sort();
                found
                    .into_iter()
                    .next()
                    .ok_or_else(|| format!("{shown}: a bag directory without an .mcap file"))?
            } else {
                path.clone()
            };
            let name = file.to_string_lossy().into_owned();
            let topics = if name.ends_with(".bag") {
                sitar_estimator::read_ros1_bag_topics(&file, &wanted).map_err(|e| e.to_string())?
            } else if name.ends_with(".mcap") {
                let bytes = std::fs::read(&file).map_err(|e| format!("{name}: {e}"))?;
                sitar_estimator::read_mcap_topics(&bytes, &wanted)
                    .map_err(|e| format!("{name}: {e}"))?
            } else {
                return Err(format!(
                    "{name}: sitar.evo reads ROS 1 .bag files and ROS 2 .mcap bags; for .db3 \
                     bags use `sitar traj bag2 {shown} {topic} --save_as_tum`"
                ));
            };
            let messages = topics
                .get(topic)
                .ok_or_else(|| format!("no messages for topic '{topic}' in bag"))?;
            // The checks and their errors (type, no messages, bad values), then the poses as
            // written: evo keeps the quaternions' norms, the trajectory normalises them.
            let bag =
                sitar_estimator::topic_trajectory(topic, messages).map_err(|e| e.to_string())?;
            let kind = sitar_estimator::PoseMessage::from_type_name(&messages.type_name)
                .expect("topic_trajectory accepted the type");
            let unit = bag.trajectory.time_unit;
            let (mut stamps, mut xyz, mut wxyz) = (Vec::new(), Vec::new(), Vec::new());
            for data in &messages.messages {
                let pose = sitar_estimator::decode_pose_as(kind, messages.encoding, data)
                    .map_err(|e| format!("topic {topic}: {e}"))?;
                stamps.push(unit.seconds(pose.stamp_ns));
                xyz.extend(pose.position.to_array());
                let q = pose.orientation;
                wxyz.extend([q.w, q.x, q.y, q.z]);
            }
            Ok((stamps, xyz, wxyz, bag.frame_id))
        })
        .map_err(SitarError::new_err)?;
    Ok((
        py_bytes(py, &stamps)?.unbind(),
        py_bytes(py, &xyz)?.unbind(),
        py_bytes(py, &wxyz)?.unbind(),
        frame_id,
    ))
}
