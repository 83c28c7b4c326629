//! Evidence of a sub-trajectory: what the camera saw, how it moved, what depth it had, and
//! the likely causes of its error (the study found blank walls, glass and large spaces
//! behind most errors).

use serde::{Deserialize, Serialize};

use crate::ImageProperties;

/// How the camera moved over a sub-trajectory (start → midpoint → end of the logged poses).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct MotionProperties {
    /// Path length over duration (m/s); the path runs through every frame.
    pub linear_speed_m_s: f64,
    /// Rotation start → midpoint plus midpoint → end, over duration (°/s).
    pub angular_speed_deg_s: f64,
}

/// The depth of a sub-trajectory's midpoint.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct DepthProperties {
    /// A depth image was given for the midpoint.
    pub given: bool,
    /// The sample was usable (a surface point and normal).
    pub valid: bool,
    /// Distance along the ray to the surface (m; 0 when not valid).
    pub distance_m: f64,
    /// Share of pixels with depth in the 5×5 sample window (0…1; 0 when not given).
    pub valid_share: f64,
}

/// Likely causes of a sub-trajectory's error, a bit set (more than one may apply).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Causes(pub u32);

impl Causes {
    /// Too few corners for visual tracking (blank walls, floors).
    pub const LOW_TEXTURE: Causes = Causes(1);
    /// Too dark for features.
    pub const DARK: Causes = Causes(2);
    /// Washed out (windows, lamps).
    pub const OVEREXPOSED: Causes = Causes(4);
    /// Motion blur or defocus: texture without sharp edges.
    pub const BLUR: Causes = Causes(8);
    /// The camera moved or turned fast.
    pub const FAST_MOTION: Causes = Causes(16);
    /// The surface faced was far (large spaces).
    pub const FAR_SURFACE: Causes = Causes(32);
    /// Depth was given but missing at the sample (typical of glass and mirrors).
    pub const NO_DEPTH: Causes = Causes(64);

    /// Every cause with its machine name, in bit order.
    pub const ALL: [(Causes, &'static str); 7] = [
        (Self::LOW_TEXTURE, "low_texture"),
        (Self::DARK, "dark"),
        (Self::OVEREXPOSED, "overexposed"),
        (Self::BLUR, "blur"),
        (Self::FAST_MOTION, "fast_motion"),
        (Self::FAR_SURFACE, "far_surface"),
        (Self::NO_DEPTH, "no_depth"),
    ];

    /// No cause found.
    pub fn is_empty(&self) -> bool {
        self.0 == 0
    }

    /// Whether every bit of `other` is set.
    pub fn contains(&self, other: Causes) -> bool {
        self.0 & other.0 == other.0
    }

    /// The machine names of the set causes, in bit order.
    pub fn names(&self) -> impl Iterator<Item = &'static str> + '_ {
        Self::ALL
            .iter()
            .filter(|(c, _)| self.contains(*c))
            .map(|(_, n)| *n)
    }

    /// Parses machine names (e.g. from the properties table); unknown names are `None`.
    pub fn from_names<'a>(names: impl IntoIterator<Item = &'a str>) -> Option<Causes> {
        let mut set = Causes(0);
        for name in names {
            let (c, _) = Self::ALL.iter().find(|(_, n)| *n == name)?;
            set.0 |= c.0;
        }
        Some(set)
    }
}

impl std::fmt::Display for Causes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut first = true;
        for name in self.names() {
            if !first {
                f.write_str(" ")?;
            }
            f.write_str(name)?;
            first = false;
        }
        Ok(())
    }
}

/// Fewer FAST corners per 10 000 px than this is low texture whatever the session: ORB-SLAM
/// style trackers want ~100+ features in a 640×480 frame (≈ 3 per 10 000 px) to keep tracking.
pub const LOW_TEXTURE_CORNERS: f64 = 3.0;
/// Also low texture below this share of the session's median corner density, while under
/// [`LOW_TEXTURE_CEILING`]: a sub-trajectory far poorer in features than the rest of its walk.
pub const LOW_TEXTURE_RELATIVE: f64 = 0.25;
/// The relative texture rule applies only below this density (a richly textured room's
/// poorest view still tracks).
pub const LOW_TEXTURE_CEILING: f64 = 10.0;
/// Mean luminance below this is dark: at ~15 % of full scale the sensor's noise rivals the
/// FAST threshold and exposure times grow long enough to blur.
pub const DARK_MEAN: f64 = 40.0;
/// More than this share of saturated pixels is overexposed: a quarter of the view carries no
/// gradient at all.
pub const OVEREXPOSED_SHARE: f64 = 0.25;
/// Blur: Laplacian variance below this share of the session median, with texture present
/// (corners above [`LOW_TEXTURE_CORNERS`] and contrast above [`BLUR_MIN_CONTRAST`]), since a
/// plain wall is smooth without being blurred.
pub const BLUR_RELATIVE: f64 = 0.3;
/// The contrast (luminance std) below which sharpness is not judged (a plain view).
pub const BLUR_MIN_CONTRAST: f64 = 10.0;
/// Absolute blur floor: a textured view whose Laplacian variance is below this is blurred
/// whatever the session (sharp 640×480 indoor views score in the hundreds).
pub const BLUR_LAPLACIAN_VAR: f64 = 20.0;
/// Turning faster than this is fast motion: at 30 fps and a 60° field of view, 90°/s shifts
/// the image by 5 % per frame, where rolling shutter and blur degrade features.
pub const FAST_ANGULAR_DEG_S: f64 = 90.0;
/// Moving faster than this is fast motion: brisk walking pace for a hand-held phone.
pub const FAST_LINEAR_M_S: f64 = 1.2;
/// Also fast motion when above this multiple of the session's median speed (linear or angular)
/// and above half the absolute limit: a jerk relative to how this user walked.
pub const FAST_RELATIVE: f64 = 3.0;
/// A surface farther than this is far: phone depth (ARCore) is specified to 8 m, and its error
/// grows with the square of the distance, so beyond 4 m features are few and parallax small.
pub const FAR_SURFACE_M: f64 = 4.0;
/// Below this share of valid pixels in the 5×5 depth window, depth counts as missing: glass and
/// mirrors leave holes in the depth image where the colour image shows a surface.
pub const NO_DEPTH_VALID_SHARE: f64 = 0.5;

/// The session's medians the relative rules compare with.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SessionMedians {
    /// Median corners per 10 000 px over the sub-trajectories with an image.
    pub corners_per_10k: f64,
    /// Median Laplacian variance over the sub-trajectories with an image.
    pub laplacian_var: f64,
    /// Median linear speed (m/s).
    pub linear_speed_m_s: f64,
    /// Median angular speed (°/s).
    pub angular_speed_deg_s: f64,
}

impl SessionMedians {
    /// Medians of the given properties (0 for an empty list).
    pub fn of(image: &[ImageProperties], motion: &[MotionProperties]) -> Self {
        Self {
            corners_per_10k: median(image.iter().map(|p| p.corners_per_10k)),
            laplacian_var: median(image.iter().map(|p| p.laplacian_var)),
            linear_speed_m_s: median(motion.iter().map(|m| m.linear_speed_m_s)),
            angular_speed_deg_s: median(motion.iter().map(|m| m.angular_speed_deg_s)),
        }
    }
}

fn median(values: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = values.filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The likely causes for one sub-trajectory, from its properties, the session's medians and
/// the floors above. Without an image only motion and depth causes can apply.
pub fn likely_causes(
    image: Option<&ImageProperties>,
    motion: &MotionProperties,
    depth: &DepthProperties,
    medians: &SessionMedians,
) -> Causes {
    let mut causes = 0;
    if let Some(p) = image {
        let low_texture = p.corners_per_10k < LOW_TEXTURE_CORNERS
            || (p.corners_per_10k < LOW_TEXTURE_RELATIVE * medians.corners_per_10k
                && p.corners_per_10k < LOW_TEXTURE_CEILING);
        if low_texture {
            causes |= Causes::LOW_TEXTURE.0;
        }
        if p.mean_brightness < DARK_MEAN {
            causes |= Causes::DARK.0;
        }
        if p.saturated_share > OVEREXPOSED_SHARE {
            causes |= Causes::OVEREXPOSED.0;
        }
        let textured = !low_texture && p.contrast_std >= BLUR_MIN_CONTRAST;
        let soft = p.laplacian_var < BLUR_LAPLACIAN_VAR
            || p.laplacian_var < BLUR_RELATIVE * medians.laplacian_var;
        if textured && soft {
            causes |= Causes::BLUR.0;
        }
    }
    let fast = |v: f64, limit: f64, median: f64| {
        v > limit || (v > FAST_RELATIVE * median && v > 0.5 * limit)
    };
    if fast(
        motion.linear_speed_m_s,
        FAST_LINEAR_M_S,
        medians.linear_speed_m_s,
    ) || fast(
        motion.angular_speed_deg_s,
        FAST_ANGULAR_DEG_S,
        medians.angular_speed_deg_s,
    ) {
        causes |= Causes::FAST_MOTION.0;
    }
    if depth.valid && depth.distance_m > FAR_SURFACE_M {
        causes |= Causes::FAR_SURFACE.0;
    }
    if depth.given && (!depth.valid || depth.valid_share < NO_DEPTH_VALID_SHARE) {
        causes |= Causes::NO_DEPTH.0;
    }
    Causes(causes)
}

/// Everything known of one sub-trajectory's input: what `sitar_session_subtrajectory_evidence`
/// returns.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Evidence {
    /// Sub-trajectory index.
    pub index: u32,
    /// Its image properties, if an image was given at its midpoint.
    pub image: Option<ImageProperties>,
    /// Its motion (zero until its endpoint is reached).
    pub motion: MotionProperties,
    /// Its midpoint's depth.
    pub depth: DepthProperties,
    /// Likely causes of its error.
    pub causes: Causes,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(corners: f64, mean: f64, lap: f64, std: f64, sat: f64) -> ImageProperties {
        ImageProperties {
            mean_brightness: mean,
            contrast_std: std,
            laplacian_var: lap,
            corners_per_10k: corners,
            saturated_share: sat,
        }
    }

    const STILL: MotionProperties = MotionProperties {
        linear_speed_m_s: 0.3,
        angular_speed_deg_s: 10.0,
    };
    const GOOD_DEPTH: DepthProperties = DepthProperties {
        given: true,
        valid: true,
        distance_m: 2.0,
        valid_share: 1.0,
    };
    const MEDIANS: SessionMedians = SessionMedians {
        corners_per_10k: 40.0,
        laplacian_var: 300.0,
        linear_speed_m_s: 0.3,
        angular_speed_deg_s: 10.0,
    };

    fn causes(p: ImageProperties, m: MotionProperties, d: DepthProperties) -> String {
        likely_causes(Some(&p), &m, &d, &MEDIANS).to_string()
    }

    #[test]
    fn each_rule_fires_alone() {
        let good = image(40.0, 120.0, 300.0, 50.0, 0.0);
        assert_eq!(causes(good, STILL, GOOD_DEPTH), "");
        assert_eq!(
            causes(image(1.0, 120.0, 5.0, 3.0, 0.0), STILL, GOOD_DEPTH),
            "low_texture"
        );
        // Relative: 8 corners where the session has 40.
        assert_eq!(
            causes(image(8.0, 120.0, 300.0, 50.0, 0.0), STILL, GOOD_DEPTH),
            "low_texture"
        );
        assert_eq!(
            causes(image(40.0, 20.0, 300.0, 50.0, 0.0), STILL, GOOD_DEPTH),
            "dark"
        );
        assert_eq!(
            causes(image(40.0, 200.0, 300.0, 50.0, 0.4), STILL, GOOD_DEPTH),
            "overexposed"
        );
        assert_eq!(
            causes(image(40.0, 120.0, 60.0, 50.0, 0.0), STILL, GOOD_DEPTH),
            "blur"
        );
        let fast = MotionProperties {
            linear_speed_m_s: 0.3,
            angular_speed_deg_s: 120.0,
        };
        assert_eq!(causes(good, fast, GOOD_DEPTH), "fast_motion");
        let jerk = MotionProperties {
            linear_speed_m_s: 1.0,
            angular_speed_deg_s: 10.0,
        };
        assert_eq!(causes(good, jerk, GOOD_DEPTH), "fast_motion");
        let far = DepthProperties {
            distance_m: 6.0,
            ..GOOD_DEPTH
        };
        assert_eq!(causes(good, STILL, far), "far_surface");
        let glass = DepthProperties {
            valid: false,
            distance_m: 0.0,
            valid_share: 0.0,
            given: true,
        };
        assert_eq!(causes(good, STILL, glass), "no_depth");
        let holes = DepthProperties {
            valid_share: 0.3,
            ..GOOD_DEPTH
        };
        assert_eq!(causes(good, STILL, holes), "no_depth");
        // No depth given at all is no evidence either way.
        assert_eq!(causes(good, STILL, DepthProperties::default()), "");
    }

    #[test]
    fn a_plain_wall_is_low_texture_not_blur_and_several_causes_combine() {
        let plain_dark = image(0.0, 25.0, 2.0, 3.0, 0.0);
        assert_eq!(causes(plain_dark, STILL, GOOD_DEPTH), "low_texture dark");
    }

    #[test]
    fn names_round_trip() {
        let c = Causes(Causes::LOW_TEXTURE.0 | Causes::NO_DEPTH.0);
        assert_eq!(Causes::from_names(c.names()), Some(c));
        assert_eq!(Causes::from_names(["glass"]), None);
    }
}
