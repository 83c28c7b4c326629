//! The options of evo's `ape` and `rpe` (and their sync options), with evo's names and
//! defaults: plain values, filled by the CLI from its arguments and by the Python package
//! from keyword arguments.

use sitar_estimator::{GravityAxis, Plane, TimeUnitRule};

/// evo's algorithm options of `ape` and `rpe` (the pose relation is per metric).
#[derive(Debug, Clone, PartialEq)]
pub struct AlgorithmOptions {
    /// `-a`: Umeyama alignment (no scale).
    pub align: bool,
    /// `-s`: scale correction (alone: scale only; with `align`: Sim(3)).
    pub correct_scale: bool,
    /// Poses used for the alignment, from the start (-1: all).
    pub n_to_align: i64,
    /// SiTAR extra, with `align`: 4-DoF alignment (translation and yaw about `yaw_axis`).
    pub yaw_only: bool,
    /// The gravity axis of `yaw_only` and of the direction relations.
    pub yaw_axis: GravityAxis,
    /// SiTAR extra: search the time offset `t_offset` would need and use it.
    pub estimate_t_offset: bool,
    /// The search range (s) of `estimate_t_offset`.
    pub t_offset_range: f64,
    /// SiTAR extra: note how the poses were paired.
    pub show_pairing: bool,
    /// Align the estimate's origin to the reference's.
    pub align_origin: bool,
    /// The output unit of the errors.
    pub change_unit: Option<ChangeUnit>,
    /// Project both trajectories to a plane (after alignment).
    pub project_to_plane: Option<Plane>,
    /// Downsample both trajectories to at most this many poses (before the sync).
    pub downsample: Option<usize>,
    /// Drop poses moving less than (metres, degrees) from the previous one.
    pub motion_filter: Option<[f64; 2]>,
}

impl Default for AlgorithmOptions {
    fn default() -> Self {
        Self {
            align: false,
            correct_scale: false,
            n_to_align: -1,
            yaw_only: false,
            yaw_axis: GravityAxis::Z,
            estimate_t_offset: false,
            t_offset_range: 1.0,
            show_pairing: false,
            align_origin: false,
            change_unit: None,
            project_to_plane: None,
            downsample: None,
            motion_filter: None,
        }
    }
}

/// evo's time-sync options of the `tum`, `euroc` and `bag` formats.
#[derive(Debug, Clone, PartialEq)]
pub struct SyncOptions {
    /// Maximum stamp difference (s) for the association.
    pub t_max_diff: f64,
    /// Constant offset (s) added to the estimate's stamps for the association.
    pub t_offset: f64,
    /// Nearest stamp or interpolation.
    pub sync_method: SyncMethod,
    /// Only reference poses from this time (s; 0 counts as unset, as in evo).
    pub t_start: Option<f64>,
    /// Only reference poses up to this time (s; 0 counts as unset).
    pub t_end: Option<f64>,
    /// How TUM stamps are read.
    pub time_unit: StampUnit,
}

impl Default for SyncOptions {
    fn default() -> Self {
        Self {
            t_max_diff: 0.01,
            t_offset: 0.0,
            sync_method: SyncMethod::NearestTime,
            t_start: None,
            t_end: None,
            time_unit: StampUnit::S,
        }
    }
}

/// evo's `sync_method`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SyncMethod {
    /// The nearest stamp within `t_max_diff`.
    NearestTime,
    /// Interpolate the denser trajectory at the matched stamps of the other.
    Interpolation,
}

/// `time_unit`: how TUM stamps are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StampUnit {
    /// Seconds, as evo reads TUM files.
    S,
    /// Integer nanoseconds (ARCore).
    Ns,
    /// Nanoseconds when all stamps are integers above 10^11, else seconds.
    Auto,
}

impl StampUnit {
    /// The trajectory library's rule.
    pub fn rule(self) -> TimeUnitRule {
        match self {
            StampUnit::S => TimeUnitRule::Seconds,
            StampUnit::Ns => TimeUnitRule::Nanoseconds,
            StampUnit::Auto => TimeUnitRule::Auto,
        }
    }
}

/// `change_unit`: evo's angle and length units.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChangeUnit {
    /// Degrees.
    Deg,
    /// Radians.
    Rad,
    /// Millimetres.
    Mm,
    /// Centimetres.
    Cm,
    /// Metres.
    M,
    /// Kilometres.
    Km,
}

impl ChangeUnit {
    /// Every unit, in evo's order.
    pub const ALL: [ChangeUnit; 6] = [
        ChangeUnit::Deg,
        ChangeUnit::Rad,
        ChangeUnit::Mm,
        ChangeUnit::Cm,
        ChangeUnit::M,
        ChangeUnit::Km,
    ];

    /// evo's unit name.
    pub fn name(self) -> &'static str {
        match self {
            ChangeUnit::Deg => "deg",
            ChangeUnit::Rad => "rad",
            ChangeUnit::Mm => "mm",
            ChangeUnit::Cm => "cm",
            ChangeUnit::M => "m",
            ChangeUnit::Km => "km",
        }
    }

    /// The unit named `name` (evo's names).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|u| u.name() == name)
    }

    /// Metres per unit for lengths.
    fn metres(self) -> Option<f64> {
        match self {
            ChangeUnit::Mm => Some(1e-3),
            ChangeUnit::Cm => Some(1e-2),
            ChangeUnit::M => Some(1.0),
            ChangeUnit::Km => Some(1e3),
            ChangeUnit::Deg | ChangeUnit::Rad => None,
        }
    }

    /// Converts `values` from the unit named `from` (evo's `change_unit`); errors name both.
    pub fn convert(self, from: &str, values: &mut [f64]) -> Result<(), String> {
        if from == self.name() {
            return Ok(());
        }
        let from_unit =
            Self::from_name(from).ok_or_else(|| format!("{from} does not support conversions"))?;
        let factor = match (from_unit.metres(), self.metres()) {
            (Some(a), Some(b)) => a / b,
            (None, None) if from_unit == ChangeUnit::Rad => 180.0 / std::f64::consts::PI,
            (None, None) => std::f64::consts::PI / 180.0,
            _ => return Err(format!("cannot convert {from} to {}", self.name())),
        };
        for v in values {
            *v = if from_unit == ChangeUnit::Rad && self == ChangeUnit::Deg {
                v.to_degrees()
            } else if from_unit == ChangeUnit::Deg && self == ChangeUnit::Rad {
                v.to_radians()
            } else {
                *v * factor
            };
        }
        Ok(())
    }
}

/// evo's name of a projection plane (`xy`, `xz`, `yz`).
pub fn plane_name(plane: Plane) -> &'static str {
    match plane {
        Plane::Xy => "xy",
        Plane::Xz => "xz",
        Plane::Yz => "yz",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn change_unit_converts_lengths_and_angles_and_refuses_mixtures() {
        let mut v = [1.0, 2.5];
        ChangeUnit::Mm.convert("m", &mut v).unwrap();
        assert_eq!(v, [1000.0, 2500.0]);
        let mut a = [std::f64::consts::PI];
        ChangeUnit::Deg.convert("rad", &mut a).unwrap();
        assert_eq!(a, [180.0]);
        assert_eq!(
            ChangeUnit::Deg.convert("m", &mut [1.0]).unwrap_err(),
            "cannot convert m to deg"
        );
        assert!(ChangeUnit::M.convert("unit-less", &mut [1.0]).is_err());
    }
}
