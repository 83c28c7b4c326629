//! `sitar.estimate`'s core: SiTAR's pairwise estimate of repeated runs (the paper's
//! section 3, `sitar-estimator`'s `estimate`), optionally calibrated, as flat columns.

use std::path::PathBuf;

use glam::{DQuat, DVec3};
use pyo3::exceptions::{PyFileNotFoundError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sitar_estimator::{
    Calibration, EstimateOptions, PoseRelation, Setting, Thresholds, TimeUnit, Trajectory,
    seconds_to_ns,
};

use crate::SitarError;

/// One run as Python gives it: a TUM file, or (stamps in s, positions n×3, quaternions n×4
/// w x y z) as float64 bytes with a name for errors.
#[derive(FromPyObject)]
pub enum Run {
    /// A TUM file (integer stamps: nanoseconds; decimal: seconds).
    Path(PathBuf),
    /// `(name, stamps, xyz, wxyz)`.
    Arrays(String, Vec<u8>, Vec<u8>, Vec<u8>),
}

fn floats(bytes: &[u8]) -> Vec<f64> {
    bytes
        .chunks_exact(8)
        .map(|c| f64::from_ne_bytes(c.try_into().expect("8 bytes")))
        .collect()
}

impl Run {
    fn trajectory(&self) -> PyResult<Trajectory> {
        match self {
            Run::Path(path) => sitar_estimator::read_tum(path).map_err(|e| match &e {
                sitar_estimator::Error::Io { source, .. }
                    if source.kind() == std::io::ErrorKind::NotFound =>
                {
                    PyFileNotFoundError::new_err(e.to_string())
                }
                _ => SitarError::new_err(e.to_string()),
            }),
            Run::Arrays(name, stamps, xyz, wxyz) => {
                let stamps: Vec<i64> = floats(stamps).into_iter().map(seconds_to_ns).collect();
                let positions = floats(xyz).chunks_exact(3).map(DVec3::from_slice).collect();
                let orientations = floats(wxyz)
                    .chunks_exact(4)
                    .map(|q| DQuat::from_xyzw(q[1], q[2], q[3], q[0]))
                    .collect();
                Trajectory::from_poses(stamps, positions, orientations, TimeUnit::Seconds)
                    .map_err(|e| SitarError::new_err(format!("{name}: {e}")))
            }
        }
    }
}

/// The estimate of `runs` (at least two) as a dict of equal-length lists: `start`, `end`
/// (stamps in seconds, evo's float), `error`, `raw`, `lower`, `upper` (NaN without a
/// calibration), `spread`, `pairs`, `class`; and `setting`, `trials`, `calibration`.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (runs, calibration, setting, delta, t_max_diff, pose_relation, medium, high))]
pub fn estimate<'py>(
    py: Python<'py>,
    runs: Vec<Run>,
    calibration: Option<PathBuf>,
    setting: &str,
    delta: usize,
    t_max_diff: f64,
    pose_relation: &str,
    medium: f64,
    high: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let setting: Setting = setting
        .parse()
        .map_err(|e: sitar_estimator::Error| PyValueError::new_err(format!("setting: {e}")))?;
    let pose_relation: PoseRelation =
        pose_relation.parse().map_err(|e: sitar_estimator::Error| {
            PyValueError::new_err(format!("pose_relation: {e}"))
        })?;
    if runs.len() < 2 {
        return Err(PyValueError::new_err(format!(
            "trajectories: the estimate compares repeated runs, at least 2 (got {})",
            runs.len()
        )));
    }
    let options = EstimateOptions {
        setting,
        delta,
        t_max_diff_s: t_max_diff,
        pose_relation,
    };
    let (estimate, unit) = py.allow_threads(|| {
        let trials = runs
            .iter()
            .map(Run::trajectory)
            .collect::<Result<Vec<_>, _>>()?;
        let fail = |e: sitar_estimator::Error| SitarError::new_err(e.to_string());
        let mut estimate = sitar_estimator::estimate(&trials, &options).map_err(fail)?;
        if let Some(path) = &calibration {
            let fitted = Calibration::read(path).map_err(fail)?;
            fitted
                .apply(&mut estimate, &trials, &path.display().to_string())
                .map_err(|e| SitarError::new_err(format!("{}: {e}", path.display())))?;
        }
        Ok::<_, PyErr>((estimate, trials[0].time_unit))
    })?;
    let thresholds = Thresholds { medium, high };
    let w = &estimate.windows;
    let out = PyDict::new(py);
    let column = |f: &dyn Fn(&sitar_estimator::WindowEstimate) -> f64| -> Vec<f64> {
        w.iter().map(f).collect()
    };
    out.set_item("start", column(&|x| unit.seconds(x.start)))?;
    out.set_item("end", column(&|x| unit.seconds(x.end)))?;
    out.set_item("error", column(&|x| x.error_m))?;
    out.set_item(
        "raw",
        column(&|x| x.interval.map_or(x.error_m, |i| i.raw_m)),
    )?;
    out.set_item(
        "lower",
        column(&|x| x.interval.map_or(f64::NAN, |i| i.lower_m)),
    )?;
    out.set_item(
        "upper",
        column(&|x| x.interval.map_or(f64::NAN, |i| i.upper_m)),
    )?;
    out.set_item("spread", column(&|x| x.spread_m))?;
    out.set_item("pairs", w.iter().map(|x| x.pairs).collect::<Vec<_>>())?;
    out.set_item(
        "class",
        w.iter()
            .map(|x| {
                let class = thresholds.classify(x.error_m);
                format!("{class:?}").to_lowercase()
            })
            .collect::<Vec<_>>(),
    )?;
    out.set_item("setting", estimate.setting.to_string())?;
    out.set_item("trials", estimate.trials)?;
    out.set_item("calibration", estimate.calibration.clone())?;
    Ok(out)
}
