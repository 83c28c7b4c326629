//! A session's estimate settings, parsed once when the session is created and stored typed:
//! the statistic per window, the window length in frames and the pose relation.

use sitar_core::Thresholds;
use sitar_estimator::{EstimateOptions, PoseRelation, Setting};

use crate::error::Error;
use crate::error::short;

/// Window length when a session names none: the phone's 10-frame sub-trajectories.
pub(crate) const DEFAULT_WINDOW_FRAMES: u32 = 10;

/// Accepted window lengths (frames). Below 2 a window has no inside; above 1000 (33 s at
/// 30 fps) it is no longer a sub-trajectory of a walk.
pub(crate) const WINDOW_FRAMES: std::ops::RangeInclusive<u32> = 2..=1000;

/// How a session's trials are estimated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct EstimateSettings {
    /// The statistic per window over the pair values.
    pub setting: Setting,
    /// RPE delta in frames: the length of every window (the phone's sub-trajectory).
    pub window_frames: u32,
    /// `trans_part` (metres) or `angle_deg` (degrees).
    pub pose_relation: PoseRelation,
}

impl EstimateSettings {
    /// The server's defaults: its setting (`--setting`), 10-frame windows, the translation
    /// part.
    pub fn defaults(default_setting: &str) -> Result<EstimateSettings, Error> {
        Ok(EstimateSettings {
            setting: parse_setting(default_setting)?,
            window_frames: DEFAULT_WINDOW_FRAMES,
            pose_relation: PoseRelation::TranslationPart,
        })
    }

    /// The defaults with whatever a request names replaced; a bad value is a 400 that names
    /// its JSON key.
    pub fn from_request(
        default_setting: &str,
        setting: Option<&str>,
        window_frames: Option<u32>,
        pose_relation: Option<&str>,
    ) -> Result<EstimateSettings, Error> {
        let mut settings = EstimateSettings::defaults(default_setting)?;
        if let Some(name) = setting {
            settings.setting = parse_setting(name)?;
        }
        if let Some(frames) = window_frames {
            settings.window_frames = check_window_frames(frames)?;
        }
        if let Some(name) = pose_relation {
            settings.pose_relation = parse_pose_relation(name)?;
        }
        Ok(settings)
    }

    /// The estimator's options for these settings (association tolerance: evo's 0.01 s).
    pub fn options(&self) -> EstimateOptions {
        EstimateOptions {
            setting: self.setting,
            delta: self.window_frames as usize,
            pose_relation: self.pose_relation,
            ..EstimateOptions::default()
        }
    }

    /// The class thresholds in the unit of these settings' errors, of the server's metre
    /// and degree thresholds.
    pub fn thresholds(&self, metres: Thresholds, degrees: Thresholds) -> Thresholds {
        match self.pose_relation {
            PoseRelation::RotationAngleDeg => degrees,
            _ => metres,
        }
    }

    /// The unit of the window values: `m` or `deg`.
    pub fn unit(&self) -> &'static str {
        match self.pose_relation {
            PoseRelation::RotationAngleDeg => "deg",
            _ => "m",
        }
    }
}

/// Parses a setting name (JSON key `setting`), naming the accepted ones when it is wrong.
pub(crate) fn parse_setting(name: &str) -> Result<Setting, Error> {
    name.parse::<Setting>().map_err(|e| {
        // Both quote the client's string: short prefixes only.
        let (name, why) = (short(name, 64), short(&e.to_string(), 300));
        Error::BadRequest(format!("setting {name:?}: {why}"))
    })
}

/// Checks a window length (JSON key `window_frames`).
pub(crate) fn check_window_frames(frames: u32) -> Result<u32, Error> {
    if WINDOW_FRAMES.contains(&frames) {
        Ok(frames)
    } else {
        Err(Error::BadRequest(format!(
            "window_frames: {frames} is not in {}..={}",
            WINDOW_FRAMES.start(),
            WINDOW_FRAMES.end()
        )))
    }
}

/// Parses a pose relation (JSON key `pose_relation`): evo's `trans_part` or `angle_deg`, the
/// two the phone can colour.
pub(crate) fn parse_pose_relation(name: &str) -> Result<PoseRelation, Error> {
    match name {
        "trans_part" => Ok(PoseRelation::TranslationPart),
        "angle_deg" => Ok(PoseRelation::RotationAngleDeg),
        other => Err(Error::BadRequest(format!(
            "pose_relation: {:?} is not trans_part or angle_deg",
            short(other, 64)
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_override_the_defaults_and_bad_values_name_their_key() {
        let config = crate::config::ServerConfig::new("unused");
        let defaults =
            EstimateSettings::from_request(&config.default_setting, None, None, None).unwrap();
        assert_eq!(defaults.setting, Setting::TrimMean(30));
        assert_eq!(defaults.window_frames, 10);
        assert_eq!(defaults.pose_relation, PoseRelation::TranslationPart);
        assert_eq!(defaults.options().delta, 10);
        assert_eq!(
            defaults.thresholds(config.thresholds, config.thresholds_deg),
            Thresholds::DEFAULT_M
        );
        assert_eq!(defaults.unit(), "m");

        let asked = EstimateSettings::from_request(
            &config.default_setting,
            Some("median"),
            Some(20),
            Some("angle_deg"),
        )
        .unwrap();
        assert_eq!(asked.setting, Setting::Median);
        assert_eq!(asked.options().delta, 20);
        assert_eq!(
            asked.options().pose_relation,
            PoseRelation::RotationAngleDeg
        );
        assert_eq!(
            asked.thresholds(config.thresholds, config.thresholds_deg),
            Thresholds::DEFAULT_DEG
        );
        assert_eq!(asked.unit(), "deg");

        for frames in [2, 1000] {
            assert!(
                EstimateSettings::from_request(&config.default_setting, None, Some(frames), None)
                    .is_ok()
            );
        }
        let bad = [
            (Some("trim_mean_33"), None, None, "setting"),
            (None, Some(1), None, "window_frames"),
            (None, Some(1001), None, "window_frames"),
            (None, Some(0), None, "window_frames"),
            (None, None, Some("angle_rad"), "pose_relation"),
            (None, None, Some("trans"), "pose_relation"),
        ];
        for (setting, frames, relation, key) in bad {
            let err =
                EstimateSettings::from_request(&config.default_setting, setting, frames, relation)
                    .unwrap_err()
                    .to_string();
            assert!(err.starts_with(key), "{key}: {err}");
        }
    }
}
