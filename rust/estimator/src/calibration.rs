//! Applying a calibration (the file `sitar calibrate` writes; its types live in
//! `sitar_core::calibration`, so the phone reads the same file) to the runs at hand.
//!
//! Two targets ([`Target`]):
//! - the **expected error** at each place, from several runs: per window of their pairwise
//!   estimate the statistic over all pairs (the spread) and the median motion of the runs;
//! - the **error of a live run**, from that run alone ([`estimate_live`] with no replay: its
//!   own motion) or with replays (its own motion and the statistic of the RPE between it and
//!   each replay).
//!
//! Per window, each feature is averaged with `smoothing_windows` neighbouring windows on
//! either side (windows overlap by all but one frame, so the truth is smooth while a single
//! window's values are noisy), then the model of that target and run count gives the value
//! and the interval.

use sitar_core::calibration::{
    Calibration, CalibrationModel, Target, WindowFeatures, WindowMotion, smooth_features,
    window_motion,
};

use crate::{
    CalibratedAs, Error, Estimate, EstimateOptions, PoseRelation, Setting, Trajectory,
    WindowEstimate, WindowInterval, estimate,
};

/// The largest number of runs whose motion is looked at per window (they replay one
/// recording: their motion differs by the error alone), which bounds the cost of applying.
const MOTION_TRIALS: usize = 15;

/// The unit of an estimate's values for a pose relation, as [`Estimate::to_json`] names it.
pub(crate) fn unit_of(relation: PoseRelation) -> &'static str {
    match relation {
        PoseRelation::TranslationPart => "m",
        PoseRelation::RotationAngleDeg => "deg",
        PoseRelation::RotationAngleRad => "rad",
        _ => "unit-less",
    }
}

/// What the estimator adds to a [`Calibration`]: checks and application with its types.
pub trait ApplyCalibration {
    /// Refuses an estimate of another setting, window or pose relation than the one the
    /// calibration was fitted for, naming both.
    fn check_estimate(
        &self,
        setting: Setting,
        window_frames: usize,
        pose_relation: PoseRelation,
    ) -> Result<(), Error>;

    /// Calibrates a pairwise `estimate` of `trials` in place as the expected error: each
    /// window's `error_m` becomes the calibrated value, its `interval` holds the raw value
    /// and the bounds, and the estimate is named `name`.
    fn apply(
        &self,
        estimate: &mut Estimate,
        trials: &[Trajectory],
        name: &str,
    ) -> Result<(), Error>;
}

impl ApplyCalibration for Calibration {
    fn check_estimate(
        &self,
        setting: Setting,
        window_frames: usize,
        pose_relation: PoseRelation,
    ) -> Result<(), Error> {
        self.check(
            Some(&setting.to_string()),
            window_frames,
            &pose_relation.to_string(),
        )
        .map_err(core_error)
    }

    fn apply(
        &self,
        estimate: &mut Estimate,
        trials: &[Trajectory],
        name: &str,
    ) -> Result<(), Error> {
        self.check_estimate(estimate.setting, estimate.delta, estimate.pose_relation)?;
        let model = self
            .model(Target::Expected, trials.len().max(2))
            .map_err(core_error)?;
        let features = expected_features(estimate, trials);
        apply_model(model, &mut estimate.windows, &features);
        estimate.calibration = Some(name.to_owned());
        estimate.calibrated_as = Some(CalibratedAs {
            target: Target::Expected,
            informative: model.informative,
        });
        Ok(())
    }
}

/// A core error (a calibration file's) as the estimator's.
pub(crate) fn core_error(e: sitar_core::Error) -> Error {
    Error::InvalidArgument(e.to_string())
}

/// Calibrates `windows` with `model` on their unsmoothed `features`.
fn apply_model(
    model: &CalibrationModel,
    windows: &mut [WindowEstimate],
    features: &[WindowFeatures],
) {
    let smoothed = smooth_features(features, model.smoothing_windows);
    for (window, f) in windows.iter_mut().zip(&smoothed) {
        let p = model.predict(f);
        window.interval = Some(WindowInterval {
            raw_m: window.error_m,
            lower_m: p.lower,
            upper_m: p.upper,
        });
        window.error_m = p.value;
    }
}

/// The motion of `trajectory` over the window that starts at stamp `start`, if it has that
/// stamp and `delta` frames after it.
pub fn motion_at(trajectory: &Trajectory, start: i64, delta: usize) -> Option<WindowMotion> {
    let k = trajectory.stamps.binary_search(&start).ok()?;
    window_motion(
        &trajectory.stamps,
        &trajectory.positions,
        &trajectory.orientations,
        k,
        delta,
    )
}

/// The unsmoothed features of every window of a pairwise `estimate`, in its window order: the
/// statistic as the spread, and the motion as the median over the first 15 trials that have
/// the window's start stamp. A window no trial starts at takes the motion of the nearest
/// window that has one.
pub fn expected_features(estimate: &Estimate, trials: &[Trajectory]) -> Vec<WindowFeatures> {
    let delta = estimate.delta;
    let mut found: Vec<Option<WindowMotion>> = Vec::with_capacity(estimate.windows.len());
    let mut columns: [Vec<f64>; 4] = Default::default();
    for window in &estimate.windows {
        columns.iter_mut().for_each(Vec::clear);
        for m in trials
            .iter()
            .filter_map(|t| motion_at(t, window.start, delta))
            .take(MOTION_TRIALS)
        {
            columns[0].push(m.path_m);
            columns[1].push(m.rotation_deg);
            columns[2].push(m.displacement_m);
            columns[3].push(m.jitter_mps2);
        }
        found.push((!columns[0].is_empty()).then(|| {
            let [p, r, d, j] = &mut columns;
            WindowMotion {
                path_m: crate::median(p),
                rotation_deg: crate::median(r),
                displacement_m: crate::median(d),
                jitter_mps2: crate::median(j),
            }
        }));
    }
    fill_from_nearest(&found)
        .into_iter()
        .zip(&estimate.windows)
        .map(|(motion, w)| WindowFeatures {
            spread: w.error_m,
            motion,
        })
        .collect()
}

/// Each `None` replaced by the nearest `Some` (the earlier one on a tie); all default when
/// there is none.
pub(crate) fn fill_from_nearest<T: Copy + Default>(found: &[Option<T>]) -> Vec<T> {
    let known: Vec<usize> = (0..found.len()).filter(|&i| found[i].is_some()).collect();
    (0..found.len())
        .map(|i| {
            found[i].unwrap_or_else(|| {
                let at = known.partition_point(|&k| k < i);
                [at.checked_sub(1), (at < known.len()).then_some(at)]
                    .into_iter()
                    .flatten()
                    .map(|j| known[j])
                    .min_by_key(|&k| k.abs_diff(i))
                    .and_then(|k| found[k])
                    .unwrap_or_default()
            })
        })
        .collect()
}

/// The windows of a live run with what the runs show for each: one window per start frame of
/// the live run, its own motion, and with replays the spread between it and them.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveWindows {
    /// One per start frame of the live run: `error_m` the spread (the statistic over the
    /// replays of the RPE between the live run and each; NaN without replays), `pairs` the
    /// replays that have the window, `spread_m` the population standard deviation of those
    /// values.
    pub windows: Vec<WindowEstimate>,
    /// The unsmoothed features of the same windows.
    pub features: Vec<WindowFeatures>,
}

/// The windows of `live` and their features, with `replays` (any number, none included) of
/// the same recording. The RPE between the live run (the reference) and each replay is
/// computed as a pairwise estimate of the two, keyed by the live run's stamps; a window no
/// replay has takes the spread of the nearest window that has one.
pub fn live_windows(
    live: &Trajectory,
    replays: &[Trajectory],
    opts: &EstimateOptions,
) -> Result<LiveWindows, Error> {
    live.validate()
        .map_err(|e| Error::InvalidArgument(format!("the live run: {e}")))?;
    let delta = opts.delta;
    if delta == 0 {
        return Err(Error::InvalidArgument(
            "delta must be at least 1 frame".into(),
        ));
    }
    let motion = sitar_core::calibration::run_motion(
        &live.stamps,
        &live.positions,
        &live.orientations,
        delta,
    );
    if motion.is_empty() {
        return Err(Error::InvalidArgument(format!(
            "the live run has {} poses: a window needs {}",
            live.len(),
            delta + 1
        )));
    }
    let pairs: Vec<Estimate> = replays
        .iter()
        .map(|replay| estimate(&[live.clone(), replay.clone()], opts))
        .collect::<Result<_, _>>()?;
    let mut values = Vec::with_capacity(pairs.len());
    let mut own: Vec<Option<Spread>> = Vec::with_capacity(motion.len());
    for k in 0..motion.len() {
        values.clear();
        let start = live.stamps[k];
        for pair in &pairs {
            if let Ok(i) = pair.windows.binary_search_by_key(&start, |w| w.start)
                && pair.windows[i].error_m.is_finite()
            {
                values.push(pair.windows[i].error_m);
            }
        }
        own.push((!values.is_empty()).then(|| {
            let mean = crate::mean(&values);
            let variance =
                values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / values.len() as f64;
            Spread {
                pairs: values.len(),
                sd: variance.sqrt(),
                value: opts.setting.apply(&mut values),
            }
        }));
    }
    if !replays.is_empty() && own.iter().all(Option::is_none) {
        return Err(Error::NoPairs(
            "no replay has a window of the live run (do their stamps associate?)".into(),
        ));
    }
    // A filled window takes its neighbour's spread but counts no pair of its own.
    let filled: Vec<Spread> = fill_from_nearest(&own)
        .into_iter()
        .zip(&own)
        .map(|(s, own)| {
            if own.is_some() {
                s
            } else {
                Spread { pairs: 0, ..s }
            }
        })
        .collect();
    let windows = (0..motion.len())
        .map(|k| WindowEstimate {
            start: live.stamps[k],
            end: live.stamps[k + delta],
            error_m: filled[k].value,
            pairs: filled[k].pairs,
            spread_m: filled[k].sd,
            interval: None,
        })
        .collect();
    let features = motion
        .into_iter()
        .zip(&filled)
        .map(|(motion, s)| WindowFeatures {
            spread: s.value,
            motion,
        })
        .collect();
    Ok(LiveWindows { windows, features })
}

/// The spread of a live run's window: the statistic over the replays, how many had the
/// window, and their population standard deviation (NaN without replays).
#[derive(Debug, Clone, Copy)]
struct Spread {
    value: f64,
    pairs: usize,
    sd: f64,
}

impl Default for Spread {
    fn default() -> Self {
        Self {
            value: f64::NAN,
            pairs: 0,
            sd: f64::NAN,
        }
    }
}

/// The live run's windows with, as the (uncalibrated) estimate, the spread between it and
/// its replays (at least one).
pub fn live_spread(
    live: &Trajectory,
    replays: &[Trajectory],
    opts: &EstimateOptions,
) -> Result<Estimate, Error> {
    if replays.is_empty() {
        return Err(Error::InvalidArgument(
            "a live run's spread needs at least one replay (or a calibration, for one run alone)"
                .into(),
        ));
    }
    Ok(Estimate {
        setting: opts.setting,
        trials: 1 + replays.len(),
        time_unit: live.time_unit,
        pose_relation: opts.pose_relation,
        delta: opts.delta,
        windows: live_windows(live, replays, opts)?.windows,
        calibration: None,
        calibrated_as: None,
        source: None,
    })
}

/// The calibrated error of the live run `live`, alone or with `replays` of the same
/// recording: one window per start frame of the live run, `error_m` the calibrated value and
/// `interval` its raw spread (NaN alone) and bounds; the estimate is named `name` and says
/// `"target": "live"` with `1 + replays.len()` runs.
pub fn estimate_live(
    calibration: &Calibration,
    live: &Trajectory,
    replays: &[Trajectory],
    opts: &EstimateOptions,
    name: &str,
) -> Result<Estimate, Error> {
    let runs = 1 + replays.len();
    let setting = (runs > 1).then(|| opts.setting.to_string());
    calibration
        .check(
            setting.as_deref(),
            opts.delta,
            &opts.pose_relation.to_string(),
        )
        .map_err(core_error)?;
    let model = calibration.model(Target::Live, runs).map_err(core_error)?;
    let LiveWindows {
        mut windows,
        features,
    } = live_windows(live, replays, opts)?;
    apply_model(model, &mut windows, &features);
    Ok(Estimate {
        setting: opts.setting,
        trials: runs,
        time_unit: live.time_unit,
        pose_relation: opts.pose_relation,
        delta: opts.delta,
        windows,
        calibration: Some(name.to_owned()),
        calibrated_as: Some(CalibratedAs {
            target: Target::Live,
            informative: model.informative,
        }),
        source: None,
    })
}
