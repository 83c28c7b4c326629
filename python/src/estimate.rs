//! `sitar.estimate`'s core: SiTAR's estimate of repeated runs (the paper's section 3,
//! `sitar-estimator`), optionally calibrated, as flat columns; as `sitar estimate` computes
//! it: several runs give the expected error, one run with a calibration (or a live run with
//! replays) the error of that run.

use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sitar_estimator::{
    ApplyCalibration, Calibration, EstimateOptions, PoseRelation, ReadOptions, Setting, Thresholds,
    TimeUnit, TimeUnitRule, Trajectory, estimate_live, live_spread, read_tum_with, seconds_to_ns,
};

use crate::SitarError;

/// One run as Python gives it: a TUM file, or (stamps in s, positions n×3, quaternions n×4
/// w x y z) as float64 bytes with a name for errors.
#[derive(FromPyObject)]
pub enum Run {
    /// A TUM file (integer stamps above 10^11: nanoseconds; anything else: seconds).
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

/// An error as Python's exception: a missing file as FileNotFoundError, another reading
/// failure as OSError, anything else as SitarError (a ValueError); the text is `context`
/// (when not empty), then the error.
pub fn python_error(context: &str, error: &(dyn std::error::Error + 'static)) -> PyErr {
    let text = if context.is_empty() {
        error.to_string()
    } else {
        format!("{context}: {error}")
    };
    let mut cause: Option<&(dyn std::error::Error + 'static)> = Some(error);
    while let Some(e) = cause {
        if let Some(io) = e.downcast_ref::<std::io::Error>() {
            return match io.kind() {
                std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(text),
                _ => PyOSError::new_err(text),
            };
        }
        cause = e.source();
    }
    SitarError::new_err(text)
}

/// Reads a TUM file as the CLI does (`sitar estimate`, `sitar calibrate`): evo's reading
/// with SiTAR's stamp unit rule; no poses or a decreasing stamp is an error, a repeated
/// stamp a warning (pushed to `warnings`).
fn read_tum_file(path: &Path, warnings: &mut Vec<String>) -> PyResult<Trajectory> {
    let options = ReadOptions {
        time_unit: TimeUnitRule::Auto,
        ..ReadOptions::EVO
    };
    let (trajectory, report) = read_tum_with(path, &options).map_err(|e| python_error("", &e))?;
    let name = path.display();
    if trajectory.is_empty() {
        return Err(SitarError::new_err(format!("{name}: no poses")));
    }
    if let Some(line) = report.first_decreasing_line {
        return Err(SitarError::new_err(format!(
            "{name}: line {line}: the timestamp is below the previous one ({} such); windows follow time, so the poses must be in time order",
            report.decreasing_stamps
        )));
    }
    if let Some(line) = report.first_repeated_line {
        warnings.push(format!(
            "{name}: {} repeated timestamp(s), the first on line {line}; both poses are kept, as evo keeps them",
            report.repeated_stamps
        ));
    }
    Ok(trajectory)
}

impl Run {
    /// The trajectory, warnings about it pushed to `warnings`.
    pub fn trajectory(&self, warnings: &mut Vec<String>) -> PyResult<Trajectory> {
        match self {
            Run::Path(path) => read_tum_file(path, warnings),
            Run::Arrays(name, stamps, xyz, wxyz) => {
                let stamps: Vec<i64> = floats(stamps).into_iter().map(seconds_to_ns).collect();
                if stamps.is_empty() {
                    return Err(SitarError::new_err(format!("{name}: no poses")));
                }
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

    /// The name of the run in messages: its path, or the name given with its arrays.
    pub fn name(&self) -> String {
        match self {
            Run::Path(path) => path.display().to_string(),
            Run::Arrays(name, ..) => name.clone(),
        }
    }
}

/// Reads every run, in parallel when there are several; their warnings in order.
pub fn read_runs(runs: &[Run], warnings: &mut Vec<String>) -> PyResult<Vec<Trajectory>> {
    use rayon::prelude::*;
    let read: Vec<(PyResult<Trajectory>, Vec<String>)> = runs
        .par_iter()
        .map(|run| {
            let mut notes = Vec::new();
            (run.trajectory(&mut notes), notes)
        })
        .collect();
    let mut out = Vec::with_capacity(read.len());
    for (trajectory, notes) in read {
        warnings.extend(notes);
        out.push(trajectory?);
    }
    Ok(out)
}

/// Parses a setting (`trim_mean_30`, ...) naming the argument on error.
pub fn parse_setting(setting: &str) -> PyResult<Setting> {
    setting
        .parse()
        .map_err(|e: sitar_estimator::Error| PyValueError::new_err(format!("setting: {e}")))
}

/// A calibration: a file (named by its file name without `.json`, as the CLI names it) or
/// the JSON text of one (named `calibration`).
fn read_calibration(
    path: Option<PathBuf>,
    json: Option<String>,
) -> PyResult<Option<(Calibration, String)>> {
    if let Some(path) = path {
        let calibration = Calibration::read(&path).map_err(|e| python_error("", &e))?;
        let name = path.file_name().map_or_else(
            || "calibration".into(),
            |n| n.to_string_lossy().into_owned(),
        );
        let name = name.strip_suffix(".json").unwrap_or(&name).to_owned();
        return Ok(Some((calibration, name)));
    }
    match json {
        Some(text) => Calibration::from_json(&text, "calibration")
            .map(|c| Some((c, "calibration".to_owned())))
            .map_err(|e| SitarError::new_err(format!("calibration: {e}"))),
        None => Ok(None),
    }
}

/// The estimate of `runs` as a dict of equal-length lists: `start`, `end` (stamps in
/// seconds, evo's float), `error`, `raw`, `lower`, `upper` (NaN without a calibration),
/// `spread`, `pairs`, `class`; and `setting`, `trials`, `runs`, `calibration`, `target`,
/// `informative` (None without a calibration), `warnings`.
///
/// With `live`, the error of that run with `runs` as its replays; one run alone (with a
/// calibration) is the live run; otherwise the expected error of the runs.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (runs, live, calibration, calibration_json, setting, delta, t_max_diff, pose_relation, medium, high))]
pub fn estimate<'py>(
    py: Python<'py>,
    runs: Vec<Run>,
    live: Option<Run>,
    calibration: Option<PathBuf>,
    calibration_json: Option<String>,
    setting: &str,
    delta: usize,
    t_max_diff: f64,
    pose_relation: &str,
    medium: f64,
    high: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let setting = parse_setting(setting)?;
    let pose_relation: PoseRelation = match pose_relation.parse() {
        Ok(
            r @ (PoseRelation::TranslationPart
            | PoseRelation::RotationAngleDeg
            | PoseRelation::RotationAngleRad),
        ) => r,
        Ok(_) => {
            return Err(PyValueError::new_err(format!(
                "pose_relation: the estimate supports trans_part, angle_deg and angle_rad, not {pose_relation}"
            )));
        }
        Err(e) => return Err(PyValueError::new_err(format!("pose_relation: {e}"))),
    };
    if !(medium.is_finite() && high.is_finite() && medium <= high) {
        return Err(PyValueError::new_err(format!(
            "thresholds: medium ({medium}) must not exceed high ({high})"
        )));
    }
    let count = runs.len() + usize::from(live.is_some());
    // Read and checked before the runs, so a wrong file fails at once (the setting matters
    // only with two or more runs).
    let calibration = read_calibration(calibration, calibration_json)?;
    if let Some((fitted, name)) = &calibration {
        let setting = setting.to_string();
        fitted
            .check(
                (count > 1).then_some(setting.as_str()),
                delta,
                &pose_relation.to_string(),
            )
            .map_err(|e| SitarError::new_err(format!("{name}: {e}")))?;
    }
    if count < 2 && calibration.is_none() {
        return Err(PyValueError::new_err(format!(
            "trajectories: {count} run; the estimate measures how runs differ, and one run has no spread to measure: give at least 2 runs, or a calibration (calibration=, from sitar.calibrate or `sitar calibrate`) to estimate the error of one run from its own motion"
        )));
    }
    let options = EstimateOptions {
        setting,
        delta,
        t_max_diff_s: t_max_diff,
        pose_relation,
    };
    let mut warnings = Vec::new();
    let estimate = py.allow_threads(|| {
        let trials = read_runs(&runs, &mut warnings)?;
        let live_run = match &live {
            Some(run) => Some((run.name(), run.trajectory(&mut warnings)?)),
            None if trials.len() == 1 => Some((runs[0].name(), trials[0].clone())),
            None => None,
        };
        let replays: &[Trajectory] = if live.is_some() { &trials } else { &[] };
        let fail =
            |what: &str, e: sitar_estimator::Error| SitarError::new_err(format!("{what}: {e}"));
        match (&live_run, &calibration) {
            (Some((name, run)), Some((fitted, calibration_name))) => {
                estimate_live(fitted, run, replays, &options, calibration_name)
                    .map_err(|e| fail(&format!("estimating the error of {name}"), e))
            }
            (Some((name, run)), None) => live_spread(run, replays, &options)
                .map_err(|e| fail(&format!("the spread of {name} against its replays"), e)),
            (None, calibration) => {
                let mut result = sitar_estimator::estimate(&trials, &options)
                    .map_err(|e| fail("estimating", e))?;
                if let Some((fitted, name)) = calibration {
                    fitted
                        .apply(&mut result, &trials, name)
                        .map_err(|e| fail(name, e))?;
                }
                Ok(result)
            }
        }
    })?;
    let unit = estimate.time_unit;
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
            .map(|x| thresholds.classify(x.error_m).name())
            .collect::<Vec<_>>(),
    )?;
    out.set_item("setting", estimate.setting.to_string())?;
    out.set_item("trials", estimate.trials)?;
    out.set_item("runs", estimate.trials)?;
    out.set_item("calibration", estimate.calibration.clone())?;
    out.set_item("target", estimate.calibrated_as.map(|c| c.target.name()))?;
    out.set_item("informative", estimate.calibrated_as.map(|c| c.informative))?;
    out.set_item("warnings", warnings)?;
    Ok(out)
}
