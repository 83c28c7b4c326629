//! The estimate from one walk: every window of one run, coloured by a calibration from the
//! run's own motion, with no replay and no network (on the phone, the moment the walk stops).

use glam::{DQuat, DVec3};

use super::features::{WindowFeatures, smooth_features};
use super::file::Calibration;
use super::model::Target;
use super::motion::run_motion;
use crate::{Error, ErrorInterval, PoseRelation, ResultWindow, Results};

/// Where results come from: the walk alone.
pub const SOURCE_WALK: &str = "walk";
/// Where results come from: replays (with the walk as the live run, where there is one).
pub const SOURCE_REPLAYS: &str = "replays";

impl Calibration {
    /// The calibrated error and interval of every window of one run (`stamps`, `positions`,
    /// `orientations` of every frame; windows of `window_frames` frames, one per start
    /// frame), as results named `name` with `"target": "live"`, `"source": "walk"` and
    /// `"runs": 1`. Refused when the calibration was fitted for another window length or
    /// pose relation, or has no model for one run (a version-1 file).
    pub fn estimate_walk(
        &self,
        name: &str,
        stamps: &[i64],
        positions: &[DVec3],
        orientations: &[DQuat],
        window_frames: usize,
        relation: PoseRelation,
    ) -> Result<Results, Error> {
        self.check(None, window_frames, relation.name())?;
        let model = self.model(Target::Live, 1)?;
        if positions.len() != stamps.len() || orientations.len() != stamps.len() {
            return Err(Error::arg(
                "walk",
                format!(
                    "{} stamps, {} positions and {} orientations",
                    stamps.len(),
                    positions.len(),
                    orientations.len()
                ),
            ));
        }
        if let Some(k) = stamps.windows(2).position(|w| w[1] < w[0]) {
            return Err(Error::arg(
                "walk",
                format!(
                    "stamp {} goes back in time after {}",
                    stamps[k + 1],
                    stamps[k]
                ),
            ));
        }
        let features: Vec<WindowFeatures> =
            run_motion(stamps, positions, orientations, window_frames)
                .into_iter()
                .map(WindowFeatures::of_motion)
                .collect();
        let smoothed = smooth_features(&features, model.smoothing_windows);
        let windows = smoothed
            .iter()
            .enumerate()
            .map(|(k, f)| {
                let p = model.predict(f);
                ResultWindow {
                    start: stamps[k],
                    end: Some(stamps[k + window_frames]),
                    error: p.value,
                    pairs: None,
                    raw: None,
                    interval: Some(ErrorInterval {
                        lower: p.lower,
                        upper: p.upper,
                    }),
                }
            })
            .filter(|w| w.error.is_finite() && w.interval.is_some_and(|i| i.upper.is_finite()))
            .collect();
        Ok(Results {
            windows,
            setting: None,
            trials: Some(1),
            window_frames: u32::try_from(window_frames).ok(),
            relation,
            calibration: Some(name.to_owned()),
            target: Some(Target::Live.name().to_owned()),
            source: Some(SOURCE_WALK.to_owned()),
            runs: Some(1),
            informative: Some(model.informative),
        })
    }
}
