//! `sitar.calibrate`'s core: fits a calibration of the estimate on sequences with ground
//! truth, as `sitar calibrate` does (`CalibrationSequence::new` per sequence, then
//! `fit_calibration`); the sequences' files are found by `sitar/__init__.py`.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rayon::prelude::*;
use sitar_estimator::{
    CalibrationSequence, EstimateOptions, FitOptions, PoseRelation, Thresholds, fit_calibration,
};

use crate::SitarError;
use crate::estimate::{Run, parse_setting, read_runs};

/// One sequence: its name (in the calibration's `fitted_on`), a description of where its
/// runs come from (for errors), its ground truth, set A (the truth's runs) and set B (the
/// estimate's runs).
#[derive(FromPyObject)]
pub struct Sequence(String, String, Run, Vec<Run>, Vec<Run>);

/// The calibration's JSON text (as `sitar calibrate -o` writes it) and the warnings of
/// reading the runs.
#[allow(clippy::too_many_arguments)]
#[pyfunction]
#[pyo3(signature = (sequences, setting, delta, t_max_diff, pose_relation, coverage, spread_match, smoothing, medium, high))]
pub fn calibrate(
    py: Python<'_>,
    sequences: Vec<Sequence>,
    setting: &str,
    delta: usize,
    t_max_diff: f64,
    pose_relation: &str,
    coverage: f64,
    spread_match: f64,
    smoothing: usize,
    medium: f64,
    high: f64,
) -> PyResult<(String, Vec<String>)> {
    let setting = parse_setting(setting)?;
    let pose_relation = match pose_relation.parse() {
        Ok(r @ (PoseRelation::TranslationPart | PoseRelation::RotationAngleDeg)) => r,
        Ok(_) => {
            return Err(PyValueError::new_err(format!(
                "pose_relation: a calibration is fitted for trans_part or angle_deg, not {pose_relation}"
            )));
        }
        Err(e) => {
            return Err(PyValueError::new_err(format!("pose_relation: {e}")));
        }
    };
    if !(coverage > 0.0 && coverage < 1.0) {
        return Err(PyValueError::new_err(format!(
            "coverage must be between 0 and 1, got {coverage}"
        )));
    }
    if delta == 0 {
        return Err(PyValueError::new_err("delta must be at least 1 frame"));
    }
    if smoothing > 1000 {
        return Err(PyValueError::new_err(format!(
            "smoothing must be at most 1000 windows, got {smoothing}"
        )));
    }
    if !(medium.is_finite() && high.is_finite() && medium <= high) {
        return Err(PyValueError::new_err(format!(
            "thresholds: medium ({medium}) must not exceed high ({high})"
        )));
    }
    if sequences.is_empty() {
        return Err(PyValueError::new_err(
            "sequences: a calibration needs at least one sequence with ground truth",
        ));
    }
    let estimate = EstimateOptions {
        setting,
        delta,
        t_max_diff_s: t_max_diff,
        pose_relation,
    };
    py.allow_threads(|| {
        let read: Vec<PyResult<(CalibrationSequence, Vec<String>)>> = sequences
            .par_iter()
            .map(|Sequence(name, origin, gt, set_a, set_b)| {
                let mut warnings = Vec::new();
                let gt = read_runs(std::slice::from_ref(gt), &mut warnings)?;
                let set_a = read_runs(set_a, &mut warnings)?;
                let set_b = read_runs(set_b, &mut warnings)?;
                let sequence =
                    CalibrationSequence::new(name, &gt[0], &set_a, &set_b, &estimate, smoothing)
                        .map_err(|e| SitarError::new_err(format!("{origin}: {e}")))?;
                Ok((sequence, warnings))
            })
            .collect();
        let mut fitted = Vec::with_capacity(read.len());
        let mut warnings = Vec::new();
        for sequence in read {
            let (sequence, notes) = sequence?;
            fitted.push(sequence);
            warnings.extend(notes);
        }
        let options = FitOptions {
            coverage,
            spread_match,
            smoothing_windows: smoothing,
            estimate,
            thresholds: Thresholds::new(medium, high),
        };
        let calibration = fit_calibration(&fitted, &options)
            .map_err(|e| SitarError::new_err(format!("fitting the calibration: {e}")))?;
        Ok((calibration.to_json(), warnings))
    })
}
