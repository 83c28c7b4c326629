//! SiTAR's `drift`: the KITTI odometry benchmark's drift (translational error in %,
//! rotational error in deg/m over segments of the reference's path), computed by
//! `sitar_estimator::drift` after pairing (stamps or index) and the alignment asked for.

use serde_json::{Value, json};
use sitar_estimator::{
    Alignment, Drift, DriftBin, DriftOptions, GravityAxis, KITTI_FRAME_INTERVAL_S, KITTI_LENGTHS_M,
    KITTI_SPEED_STEP_M_S, KITTI_STEP, SegmentDuration, drift,
};

use crate::SEP;
use crate::align::align_estimate;
use crate::document::{VERSION, across_trials, alignment_name, json_number};
use crate::error::{Error, Result, invalid};
use crate::messages::Messages;
use crate::options::AlgorithmOptions;
use crate::read::Loaded;
use crate::sync::synchronise;

/// `drift`'s options, with the CLI's names and the devkit's defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct DriftSettings {
    /// Segment lengths along the reference's path (m).
    pub lengths: Vec<f64>,
    /// A segment starts at every `step`-th (associated) pose.
    pub step: usize,
    /// Spacing of the speed bins (m/s).
    pub speed_step: f64,
    /// Umeyama alignment (no scale).
    pub align: bool,
    /// Scale correction (alone: scale only; with `align`: Sim(3)).
    pub correct_scale: bool,
    /// Poses used for the alignment (-1: all).
    pub n_to_align: i64,
    /// With `align`: 4-DoF alignment (translation and yaw about `yaw_axis`).
    pub yaw_only: bool,
    /// The gravity axis of `yaw_only`.
    pub yaw_axis: GravityAxis,
}

impl Default for DriftSettings {
    fn default() -> Self {
        Self {
            lengths: KITTI_LENGTHS_M.to_vec(),
            step: KITTI_STEP,
            speed_step: KITTI_SPEED_STEP_M_S,
            align: false,
            correct_scale: false,
            n_to_align: -1,
            yaw_only: false,
            yaw_axis: GravityAxis::Z,
        }
    }
}

impl DriftSettings {
    /// The library's segment options (checks the speed step).
    pub fn options(&self) -> Result<DriftOptions> {
        if !(self.speed_step.is_finite() && self.speed_step > 0.0) {
            invalid!(
                "--speed_step must be a positive number of m/s, got {}",
                self.speed_step
            );
        }
        Ok(DriftOptions {
            lengths_m: self.lengths.clone(),
            step: self.step,
            ..DriftOptions::default()
        }
        .with_speed_step(self.speed_step))
    }

    /// The title: the metric, its segments, the alignment (as evo names it).
    pub fn title(&self) -> String {
        let mut title = format!(
            "KITTI drift over segments of {} (a start every {} poses)",
            lengths_text(&self.lengths),
            self.step
        );
        title += match (self.align, self.correct_scale) {
            (true, _) if self.yaw_only => match self.yaw_axis {
                GravityAxis::Z => "\n(with 4-DoF position and yaw alignment about z)",
                GravityAxis::Y => "\n(with 4-DoF position and yaw alignment about y)",
            },
            (true, false) => "\n(with SE(3) Umeyama alignment)",
            (true, true) => "\n(with Sim(3) Umeyama alignment)",
            (false, true) => "\n(scale corrected)",
            (false, false) => "\n(not aligned)",
        };
        if (self.align || self.correct_scale) && self.n_to_align != -1 {
            title += &format!(" (aligned poses: {})", self.n_to_align);
        }
        title
    }
}

/// One run's drift and what it was computed on.
#[derive(Debug, Clone)]
pub struct DriftOutcome {
    /// The reference's name.
    pub ref_name: String,
    /// The estimate's name.
    pub est_name: String,
    /// The drift.
    pub drift: Drift,
    /// The alignment applied.
    pub alignment: Alignment,
    /// Its scale, when aligned.
    pub scale: Option<f64>,
    /// Associated poses.
    pub poses: usize,
    /// The reference's path length (m).
    pub path_m: f64,
    /// Speeds from stamps (else from KITTI's frame interval).
    pub stamps: bool,
}

/// Pairs (stamps or index), aligns as asked and computes one run's drift.
pub fn compute_drift(
    loaded: Loaded,
    settings: &DriftSettings,
    mut options: DriftOptions,
    messages: &dyn Messages,
) -> Result<DriftOutcome> {
    let Loaded {
        reference,
        estimate,
        sync,
    } = loaded;
    let (ref_name, est_name) = (reference.name, estimate.name);
    let (mut reference, mut estimate) = (reference.trajectory, estimate.trajectory);
    if let Some(sync) = &sync {
        (reference, estimate, _) =
            synchronise(reference, estimate, sync, (&ref_name, &est_name), messages)?;
        options.duration = SegmentDuration::Stamps;
    } else {
        if reference.len() != estimate.len() {
            invalid!(
                "trajectories must have same number of poses ({ref_name}: {}, {est_name}: {})",
                reference.len(),
                estimate.len()
            );
        }
        options.duration = SegmentDuration::Frames {
            interval_s: KITTI_FRAME_INTERVAL_S,
        };
    }
    let algorithm = AlgorithmOptions {
        align: settings.align,
        correct_scale: settings.correct_scale,
        n_to_align: settings.n_to_align,
        yaw_only: settings.yaw_only,
        yaw_axis: settings.yaw_axis,
        ..AlgorithmOptions::default()
    };
    let (alignment, transform, _) =
        align_estimate(&algorithm, &mut estimate, &reference, messages)?;
    messages.debug(SEP)?;
    let result = drift(&reference, &estimate, &options).map_err(|e| match e {
        sitar_estimator::Error::NoPairs(_) => Error::Invalid(format!(
            "{est_name}: {e} (--lengths sets shorter segments, e.g. 1,2,3,4,5,6,7,8 indoors)"
        )),
        e => Error::Invalid(format!("{est_name}: {e}")),
    })?;
    messages.debug(&format!(
        "{} segments of {} over {} poses of {est_name}",
        result.segments.len(),
        lengths_text(&options.lengths_m),
        reference.len()
    ))?;
    Ok(DriftOutcome {
        ref_name,
        est_name,
        drift: result,
        alignment,
        scale: transform.map(|t| t.scale),
        poses: reference.len(),
        path_m: reference.distances().last().copied().unwrap_or(0.0),
        stamps: sync.is_some(),
    })
}

/// `1, 2, 3 m`.
pub fn lengths_text(lengths: &[f64]) -> String {
    let list: Vec<String> = lengths.iter().map(f64::to_string).collect();
    format!("{} m", list.join(", "))
}

/// A bin as JSON, its centre under `key`.
fn bin_json(key: &str, bin: &DriftBin) -> Value {
    json!({
        key: bin.centre,
        "segments": bin.segments,
        "t_err_percent": json_number(bin.t_err_percent),
        "r_err_deg_per_m": json_number(bin.r_err_deg_per_m),
    })
}

/// The drift statistics summarised over runs.
pub const DRIFT_STATS: [&str; 2] = ["t_err_percent", "r_err_deg_per_m"];

impl DriftOutcome {
    /// A statistic of [`DRIFT_STATS`] by name.
    pub fn stat(&self, name: &str) -> f64 {
        match name {
            "t_err_percent" => self.drift.t_err_percent,
            "r_err_deg_per_m" => self.drift.r_err_deg_per_m,
            _ => f64::NAN,
        }
    }

    /// One run's JSON document (what `sitar drift --format json` prints).
    pub fn json(&self, title: &str, options: &DriftOptions) -> Value {
        let d = &self.drift;
        json!({
            "version": VERSION,
            "metric": "drift",
            "title": title,
            "reference": self.ref_name,
            "estimate": self.est_name,
            "lengths_m": options.lengths_m,
            "step": options.step,
            "speed_from": if self.stamps { "stamps" } else { "frames" },
            "alignment": alignment_name(self.alignment),
            "scale": self.scale,
            "associated_poses": self.poses,
            "path_length_m": json_number(self.path_m),
            "t_err_percent": json_number(d.t_err_percent),
            "r_err_deg_per_m": json_number(d.r_err_deg_per_m),
            "segments": d.segments.len(),
            "by_length": d.by_length.iter().map(|b| bin_json("length_m", b)).collect::<Vec<_>>(),
            "by_speed": d.by_speed.iter().map(|b| bin_json("speed_m_s", b)).collect::<Vec<_>>(),
        })
    }
}

/// Several runs' drift document: each run's under `trials`, the summaries under
/// `across_trials`. `outcomes` must not be empty.
pub fn drift_runs_json(outcomes: &[DriftOutcome], title: &str, options: &DriftOptions) -> Value {
    let n = outcomes.len();
    json!({
        "version": VERSION,
        "metric": "drift",
        "title": title,
        "reference": outcomes[0].ref_name,
        "runs": n,
        "trials": outcomes.iter().map(|o| o.json(title, options)).collect::<Vec<_>>(),
        "across_trials": across_trials(&DRIFT_STATS, |k, name| outcomes[k].stat(name), n),
    })
}
