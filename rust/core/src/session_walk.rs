//! The estimate from one walk on the phone: with a calibration, the session colours its own
//! walk the moment it stops, from the walk's own motion, offline; results from the backend
//! replace it when they arrive.

use crate::calibration::{Calibration, SOURCE_WALK};
use crate::{Error, Results, Session, SessionState};

/// The name results estimated on the phone give their calibration (`"calibration"`).
pub const ON_DEVICE_CALIBRATION: &str = "on_device";

impl Session {
    /// Takes a calibration (the JSON file `sitar calibrate` writes, version 1 or 2). It must
    /// be fitted for this session's window (`subtrajectory_frames`) and pose relation, and
    /// have a model for one run (version 2). A stopped session without results, or with
    /// results from its walk, is coloured from its walk at once; otherwise at
    /// [`Session::stop`]. Results loaded from the backend are kept. Replaces an earlier
    /// calibration; a refused one changes nothing.
    pub fn set_calibration(&mut self, json: &str) -> Result<(), Error> {
        let calibration = Calibration::from_json(json, "calibration")?;
        calibration.check(
            None,
            self.config.subtrajectory_frames as usize,
            self.config.pose_relation.name(),
        )?;
        calibration.model(crate::calibration::Target::Live, 1)?;
        self.calibration = Some(calibration);
        if self.state == SessionState::Stopped
            && self
                .results
                .as_ref()
                // Loaded results that do not say where they come from (legacy CSV) are
                // the backend's too: only the walk's own estimate is redone.
                .is_none_or(|r| r.source.as_deref() == Some(SOURCE_WALK))
        {
            self.estimate_from_walk()?;
            self.refresh_markers();
        }
        Ok(())
    }

    /// The calibration given with [`Session::set_calibration`], if any.
    pub fn calibration(&self) -> Option<&Calibration> {
        self.calibration.as_ref()
    }

    /// The walk: the start pose and every frame's pose, as TUM text with integer
    /// nanoseconds (the session folder's `walk.txt`, the phone log the backend estimates
    /// from before any replay).
    pub fn walk_tum(&self) -> String {
        crate::tum::to_tum(self.walk.iter().map(|(t, pose)| (*t, pose)))
    }

    /// Number of poses of the walk (start and frames).
    pub fn walk_len(&self) -> usize {
        self.walk.len()
    }

    /// Sets the results to the calibrated estimate of the walk alone (`"source": "walk"`),
    /// when a calibration is set; `Ok(false)` without one.
    pub(crate) fn estimate_from_walk(&mut self) -> Result<bool, Error> {
        let Some(calibration) = &self.calibration else {
            return Ok(false);
        };
        let n = self.walk.len();
        let (mut stamps, mut positions, mut orientations) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        for (t, pose) in &self.walk {
            stamps.push(*t);
            positions.push(pose.position);
            orientations.push(pose.rotation);
        }
        let results: Results = calibration.estimate_walk(
            ON_DEVICE_CALIBRATION,
            &stamps,
            &positions,
            &orientations,
            self.config.subtrajectory_frames as usize,
            self.config.pose_relation,
        )?;
        self.results = Some(results);
        Ok(true)
    }
}
