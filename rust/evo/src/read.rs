//! Reading REF and EST the way evo does (`tum`, `euroc`, `kitti`): stamps as written,
//! quaternions normalised, repeated or decreasing stamps kept with a warning; errors name
//! the file, line and column, and suggest the format a file does read as.

use std::path::Path;

use sitar_estimator::{
    ReadOptions, ReadReport, StampOrder, Trajectory, read_euroc_csv_with, read_kitti, read_tum_with,
};

use crate::error::{Error, Result, full_chain, invalid};
use crate::messages::Messages;
use crate::options::{StampUnit, SyncOptions};

/// What evo knows of a loaded trajectory: its poses and its name (the path as given).
#[derive(Debug, Clone)]
pub struct Named {
    /// The poses.
    pub trajectory: Trajectory,
    /// The path as given (evo's `name`).
    pub name: String,
    /// Every quaternion was read with unit norm (by numpy's `allclose`, as evo's check).
    pub unit_quaternions: bool,
}

/// Reference and estimate as read, with the sync options (None: KITTI, paired by index).
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The reference.
    pub reference: Named,
    /// The estimate.
    pub estimate: Named,
    /// The sync options (None for KITTI).
    pub sync: Option<SyncOptions>,
}

/// evo's file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileFormat {
    /// TUM files (reference and estimate).
    Tum,
    /// A EuRoC ground-truth CSV and a TUM estimate.
    Euroc,
    /// KITTI pose files (no stamps: poses pair by index).
    Kitti,
}

impl FileFormat {
    /// The format named as evo's subcommand (`tum`, `euroc`, `kitti`).
    pub fn from_name(name: &str) -> Result<Self> {
        match name {
            "tum" => Ok(FileFormat::Tum),
            "euroc" => Ok(FileFormat::Euroc),
            "kitti" => Ok(FileFormat::Kitti),
            other => invalid!(
                "unknown format '{other}' (choose from 'tum', 'euroc', 'kitti'; bags: the sitar command)"
            ),
        }
    }
}

/// evo's reading options with the stamp unit of `time_unit`.
pub fn evo_read_options(unit: StampUnit) -> ReadOptions {
    ReadOptions {
        time_unit: unit.rule(),
        stamp_order: StampOrder::AsWritten,
        normalise_quaternions: true,
    }
}

/// Reads one TUM file by evo's rules, telling `messages` what it met.
pub fn read_tum_evo(path: &Path, unit: StampUnit, messages: &dyn Messages) -> Result<Named> {
    let (trajectory, report) = read_tum_with(path, &evo_read_options(unit))
        .map_err(|e| with_format_hint(e, path, "tum"))?;
    finish(path, trajectory, &report, true, messages)
}

/// Reads one EuRoC ground-truth file by evo's rules.
pub fn read_euroc_evo(path: &Path, messages: &dyn Messages) -> Result<Named> {
    let (trajectory, report) = read_euroc_csv_with(path, &evo_read_options(StampUnit::Ns))
        .map_err(|e| with_format_hint(e, path, "euroc"))?;
    finish(path, trajectory, &report, true, messages)
}

/// Reads one KITTI file.
pub fn read_kitti_evo(path: &Path, messages: &dyn Messages) -> Result<Named> {
    let trajectory = read_kitti(path).map_err(|e| with_format_hint(e, path, "kitti"))?;
    finish(path, trajectory, &ReadReport::default(), false, messages)
}

/// Reads a reference and its estimates in `format`: one [`Loaded`] per estimate (the
/// reference read once, then each estimate in the order given).
pub fn load_files(
    format: FileFormat,
    reference: &Path,
    estimates: &[&Path],
    sync: &SyncOptions,
    messages: &dyn Messages,
) -> Result<Vec<Loaded>> {
    let (reference, sync) = match format {
        FileFormat::Tum => (
            read_tum_evo(reference, sync.time_unit, messages)?,
            Some(sync),
        ),
        FileFormat::Euroc => (read_euroc_evo(reference, messages)?, Some(sync)),
        FileFormat::Kitti => (read_kitti_evo(reference, messages)?, None),
    };
    estimates
        .iter()
        .map(|path| {
            let estimate = match format {
                FileFormat::Kitti => read_kitti_evo(path, messages)?,
                _ => read_tum_evo(path, sync.map_or(StampUnit::S, |s| s.time_unit), messages)?,
            };
            Ok(Loaded {
                reference: reference.clone(),
                estimate,
                sync: sync.cloned(),
            })
        })
        .collect()
}

/// `error` (reading `path` as `given`), with a hint naming the format the file does read
/// as, if one does: `ape euroc` on a TUM file suggests `tum`.
fn with_format_hint(error: sitar_estimator::Error, path: &Path, given: &str) -> Error {
    let options = evo_read_options(StampUnit::S);
    let readers: [(&str, &dyn Fn() -> bool); 3] = [
        ("tum", &|| {
            read_tum_with(path, &options).is_ok_and(|t| !t.0.is_empty())
        }),
        ("euroc", &|| {
            read_euroc_csv_with(path, &options).is_ok_and(|t| !t.0.is_empty())
        }),
        ("kitti", &|| read_kitti(path).is_ok_and(|t| !t.is_empty())),
    ];
    match readers
        .iter()
        .find(|(name, reads)| *name != given && reads())
    {
        Some((name, _)) => Error::Invalid(format!(
            "{} (the file reads as the {name} format: use `{name}` in place of `{given}`)",
            full_chain(&error)
        )),
        None => error.into(),
    }
}

fn finish(
    path: &Path,
    trajectory: Trajectory,
    report: &ReadReport,
    timed: bool,
    messages: &dyn Messages,
) -> Result<Named> {
    let name = path.display().to_string();
    if trajectory.is_empty() {
        invalid!("{name}: no poses");
    }
    if let Some(line) = report.first_repeated_line {
        messages.warn(&format!(
            "{name}: {} repeated timestamp(s), the first on line {line}; both poses are kept, as evo keeps them",
            report.repeated_stamps
        ));
    }
    if let Some(line) = report.first_decreasing_line {
        messages.warn(&format!(
            "{name}: {} timestamp(s) below the previous one, the first on line {line}; the poses are kept in file order, as evo keeps them",
            report.decreasing_stamps
        ));
    }
    if report.normalised_quaternions > 0 {
        messages.debug(&format!(
            "{name}: normalised {} quaternion(s) whose norm was not 1",
            report.normalised_quaternions
        ))?;
    }
    messages.debug(&format!(
        "Loaded {} {} from: {name}",
        trajectory.len(),
        if timed { "stamps and poses" } else { "poses" }
    ))?;
    Ok(Named {
        trajectory,
        name,
        unit_quaternions: report.quaternions_off_unit == 0,
    })
}
