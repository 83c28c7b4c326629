//! A venue user's session as the backend holds it once played: the phone's files and the
//! estimate of its trials, made into the session's contribution to the venue map.

use std::path::Path;

use sitar_core::venue::{Contribution, SessionFiles};
use sitar_core::{Convention, DisplayRotation, SessionConfig, Thresholds};
use sitar_estimator::{EstimateOptions, estimate};

use crate::{Error, VenueUser, simulate_trials};

impl VenueUser {
    /// Records the phone session (ARCore convention, no camera images, phone held upright),
    /// saves its folder into `dir` as the phone does, plays `trials` simulated trials of the
    /// recording, estimates them pairwise with the backend's defaults (trim_mean_30,
    /// translation RPE over 10 frames) and returns the session's [`Contribution`] to a venue
    /// whose anchor is `anchor`, under the id `session`.
    pub fn contribution(
        &self,
        session: &str,
        anchor: &str,
        trials: u32,
        dir: &Path,
    ) -> Result<Contribution, Error> {
        if trials < 2 {
            return Err(Error::InvalidArgument(format!(
                "an estimate compares pairs of trials: {trials} is fewer than 2"
            )));
        }
        let core = |e: sitar_core::Error| Error::InvalidArgument(format!("venue session: {e}"));
        let config =
            SessionConfig::from_json(r#"{"convention":"arcore","images":false}"#).map_err(core)?;
        self.phone_session(config, DisplayRotation::Deg90)?
            .save(dir)
            .map_err(core)?;
        let read = |name: &str| {
            std::fs::read_to_string(dir.join(name))
                .map_err(|e| Error::InvalidArgument(format!("{}: {e}", dir.join(name).display())))
        };
        let (trajectory, anchors, subtrajectories) = (
            read("trajectory.txt")?,
            read("anchors.csv")?,
            read("subtrajectories.csv")?,
        );
        let played = simulate_trials(&self.recording, trials);
        let results = estimate(&played, &EstimateOptions::default())
            .map_err(|e| Error::InvalidArgument(format!("estimating user {}: {e}", self.index)))?
            .to_json(Thresholds::DEFAULT_M);
        Contribution::from_files(
            &SessionFiles {
                session,
                convention: Convention::Arcore,
                anchors_csv: Some(&anchors),
                trajectory_txt: Some(&trajectory),
                subtrajectories_csv: Some(&subtrajectories),
                results_json: Some(&results),
            },
            anchor,
        )
        .map_err(core)
    }
}
