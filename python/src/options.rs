//! Keyword options by evo's names (those of `evo_ape`/`evo_rpe`'s command line and of
//! evo's Python API), onto sitar-evo's option structs. An unknown name is a TypeError
//! naming it; a bad value a ValueError naming the option.

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sitar_estimator::{DeltaUnit, DirectionRelation, GravityAxis, Plane, PoseRelation};
use sitar_evo::{
    AlgorithmOptions, ApeRelation, ChangeUnit, DriftSettings, Metric, StampUnit, SyncMethod,
    SyncOptions,
};

/// The sync options every format with stamps takes.
const SYNC: [&str; 6] = [
    "t_max_diff",
    "t_offset",
    "sync_method",
    "t_start",
    "t_end",
    "time_unit",
];
/// `ape`'s and `rpe`'s algorithm options.
const ALGORITHM: [&str; 13] = [
    "align",
    "correct_scale",
    "n_to_align",
    "yaw_only",
    "yaw_axis",
    "estimate_t_offset",
    "t_offset_range",
    "show_pairing",
    "align_origin",
    "change_unit",
    "project_to_plane",
    "downsample",
    "motion_filter",
];
/// `rpe`'s pair options.
const RPE: [&str; 5] = [
    "delta",
    "delta_tol",
    "delta_unit",
    "all_pairs",
    "pairs_from_reference",
];
/// `drift`'s own options.
const DRIFT: [&str; 8] = [
    "lengths",
    "step",
    "speed_step",
    "align",
    "correct_scale",
    "n_to_align",
    "yaw_only",
    "yaw_axis",
];

/// A call's options, parsed.
pub struct Options {
    kind: &'static str,
    /// The sync options.
    pub sync: SyncOptions,
    /// The algorithm options (ape, rpe; drift's alignment).
    pub algorithm: AlgorithmOptions,
    pose_relation: String,
    delta: f64,
    delta_tol: f64,
    delta_unit: String,
    all_pairs: bool,
    pairs_from_reference: bool,
    lengths: Option<Vec<f64>>,
    step: Option<usize>,
    speed_step: Option<f64>,
}

/// `value` as `T`, or a ValueError naming the option and what it wants.
fn take<'py, T: FromPyObject<'py>>(
    name: &str,
    value: &Bound<'py, PyAny>,
    wants: &str,
) -> PyResult<T> {
    value.extract().map_err(|_| {
        PyValueError::new_err(format!(
            "{name}: expected {wants}, got {}",
            value.repr().map_or_else(|_| "?".into(), |r| r.to_string())
        ))
    })
}

fn bad(name: &str, value: &str, choices: &str) -> PyErr {
    PyValueError::new_err(format!(
        "{name}: invalid choice '{value}' (choose from {choices})"
    ))
}

impl Options {
    /// The options of `kind` (`ape`, `rpe`, `drift`) from the keyword dict.
    pub fn parse(kind: &'static str, dict: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let mut o = Options {
            kind,
            sync: SyncOptions::default(),
            algorithm: AlgorithmOptions::default(),
            pose_relation: "trans_part".into(),
            delta: 1.0,
            delta_tol: 0.1,
            delta_unit: "f".into(),
            all_pairs: false,
            pairs_from_reference: false,
            lengths: None,
            step: None,
            speed_step: None,
        };
        let Some(dict) = dict else { return Ok(o) };
        for (key, value) in dict.iter() {
            let name: String = key.extract()?;
            let known = SYNC.contains(&name.as_str())
                || match kind {
                    "ape" => ALGORITHM.contains(&name.as_str()) || name == "pose_relation",
                    "rpe" => {
                        ALGORITHM.contains(&name.as_str())
                            || RPE.contains(&name.as_str())
                            || name == "pose_relation"
                    }
                    _ => DRIFT.contains(&name.as_str()),
                };
            if !known {
                return Err(PyTypeError::new_err(format!(
                    "{kind}() got an unexpected keyword argument '{name}'"
                )));
            }
            if value.is_none()
                && !matches!(
                    name.as_str(),
                    "t_start"
                        | "t_end"
                        | "change_unit"
                        | "project_to_plane"
                        | "downsample"
                        | "motion_filter"
                        | "lengths"
                )
            {
                return Err(PyValueError::new_err(format!(
                    "{name}: None is not a value of this option"
                )));
            }
            o.set(&name, &value)?;
        }
        Ok(o)
    }

    fn set(&mut self, name: &str, v: &Bound<'_, PyAny>) -> PyResult<()> {
        let (a, s) = (&mut self.algorithm, &mut self.sync);
        match name {
            "t_max_diff" => s.t_max_diff = take(name, v, "a number of seconds")?,
            "t_offset" => s.t_offset = take(name, v, "a number of seconds")?,
            "t_start" => s.t_start = take(name, v, "a number of seconds or None")?,
            "t_end" => s.t_end = take(name, v, "a number of seconds or None")?,
            "sync_method" => {
                let text: String = take(name, v, "a string")?;
                s.sync_method = match text.as_str() {
                    "nearest_time" => SyncMethod::NearestTime,
                    "interpolation" => SyncMethod::Interpolation,
                    _ => return Err(bad(name, &text, "'nearest_time', 'interpolation'")),
                }
            }
            "time_unit" => {
                let text: String = take(name, v, "a string")?;
                s.time_unit = match text.as_str() {
                    "s" => StampUnit::S,
                    "ns" => StampUnit::Ns,
                    "auto" => StampUnit::Auto,
                    _ => return Err(bad(name, &text, "'s', 'ns', 'auto'")),
                }
            }
            "align" => a.align = take(name, v, "True or False")?,
            "correct_scale" => a.correct_scale = take(name, v, "True or False")?,
            "n_to_align" => a.n_to_align = take(name, v, "an integer (-1: all poses)")?,
            "yaw_only" => a.yaw_only = take(name, v, "True or False")?,
            "yaw_axis" => {
                let text: String = take(name, v, "'z' or 'y'")?;
                a.yaw_axis = match text.as_str() {
                    "z" => GravityAxis::Z,
                    "y" => GravityAxis::Y,
                    _ => return Err(bad(name, &text, "'z', 'y'")),
                }
            }
            "estimate_t_offset" => a.estimate_t_offset = take(name, v, "True or False")?,
            "t_offset_range" => a.t_offset_range = take(name, v, "a number of seconds")?,
            "show_pairing" => a.show_pairing = take(name, v, "True or False")?,
            "align_origin" => a.align_origin = take(name, v, "True or False")?,
            "change_unit" => {
                let text: Option<String> = take(name, v, "a unit name or None")?;
                a.change_unit = match text {
                    None => None,
                    Some(t) => Some(
                        ChangeUnit::from_name(&t)
                            .ok_or_else(|| bad(name, &t, "'deg', 'rad', 'mm', 'cm', 'm', 'km'"))?,
                    ),
                }
            }
            "project_to_plane" => {
                let text: Option<String> = take(name, v, "'xy', 'xz', 'yz' or None")?;
                a.project_to_plane = match text.as_deref() {
                    None => None,
                    Some("xy") => Some(Plane::Xy),
                    Some("xz") => Some(Plane::Xz),
                    Some("yz") => Some(Plane::Yz),
                    Some(t) => return Err(bad(name, t, "'xy', 'xz', 'yz'")),
                }
            }
            "downsample" => a.downsample = take(name, v, "a number of poses or None")?,
            "motion_filter" => {
                a.motion_filter =
                    take::<Option<(f64, f64)>>(name, v, "(distance_m, angle_deg) or None")?
                        .map(|(d, g)| [d, g])
            }
            "pose_relation" => self.pose_relation = take(name, v, "a pose relation name")?,
            "delta" => self.delta = take(name, v, "a number")?,
            "delta_tol" => self.delta_tol = take(name, v, "a number")?,
            "delta_unit" => self.delta_unit = take(name, v, "'f', 'd', 'r' or 'm'")?,
            "all_pairs" => self.all_pairs = take(name, v, "True or False")?,
            "pairs_from_reference" => self.pairs_from_reference = take(name, v, "True or False")?,
            "lengths" => self.lengths = take(name, v, "a list of metres or None")?,
            "step" => self.step = Some(take(name, v, "a number of poses")?),
            "speed_step" => self.speed_step = Some(take(name, v, "a number of m/s")?),
            _ => {}
        }
        Ok(())
    }

    /// The metric of an `ape` or `rpe` call.
    pub fn metric(&self) -> PyResult<Metric> {
        let r = self.pose_relation.as_str();
        if self.kind == "ape" {
            if let Ok(d) = r.parse::<DirectionRelation>() {
                return Ok(Metric::Ape(ApeRelation::Direction(d)));
            }
            return match r.parse::<PoseRelation>() {
                Ok(PoseRelation::PointDistanceErrorRatio) | Err(_) => Err(bad(
                    "pose_relation",
                    r,
                    "'full', 'trans_part', 'rot_part', 'angle_deg', 'angle_rad', 'point_distance', or SiTAR's 'along_track', 'cross_track', 'vertical', 'yaw_deg', 'roll_pitch_deg'",
                )),
                Ok(p) => Ok(Metric::Ape(ApeRelation::Evo(p))),
            };
        }
        let relation = r.parse::<PoseRelation>().map_err(|_| {
            bad(
                "pose_relation",
                r,
                "'full', 'trans_part', 'rot_part', 'angle_deg', 'angle_rad', 'point_distance', 'point_distance_error_ratio'",
            )
        })?;
        let unit = match self.delta_unit.as_str() {
            "f" => DeltaUnit::Frames,
            "d" => DeltaUnit::Degrees,
            "r" => DeltaUnit::Radians,
            "m" => DeltaUnit::Meters,
            u => return Err(bad("delta_unit", u, "'f', 'd', 'r', 'm'")),
        };
        sitar_evo::rpe_options(
            relation,
            self.delta,
            unit,
            self.delta_tol,
            self.all_pairs,
            self.pairs_from_reference,
        )
        .map(Metric::Rpe)
        .map_err(|e| PyValueError::new_err(e.chain_text()))
    }

    /// The settings of a `drift` call.
    pub fn drift(&self) -> PyResult<DriftSettings> {
        let defaults = DriftSettings::default();
        Ok(DriftSettings {
            lengths: self.lengths.clone().unwrap_or(defaults.lengths),
            step: self.step.unwrap_or(defaults.step),
            speed_step: self.speed_step.unwrap_or(defaults.speed_step),
            align: self.algorithm.align,
            correct_scale: self.algorithm.correct_scale,
            n_to_align: self.algorithm.n_to_align,
            yaw_only: self.algorithm.yaw_only,
            yaw_axis: self.algorithm.yaw_axis,
        })
    }
}
