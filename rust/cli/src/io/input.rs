//! Reading trajectories and trial sets from files.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use sitar_estimator::{
    ReadOptions, ReadReport, TimeUnitRule, Trajectory, read_euroc_csv_with, read_kitti,
    read_tum_with,
};

/// Trajectory file format (evo's format subcommands).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum Format {
    /// `t x y z qx qy qz qw`, stamps in seconds, or integer nanoseconds above 10^11.
    #[default]
    Tum,
    /// EuRoC ground-truth CSV (`#timestamp [ns], px, py, pz, qw, qx, qy, qz, …`).
    Euroc,
    /// KITTI poses (3×4 matrices, no time: stamps are pose indices).
    Kitti,
}

/// Reads one trajectory as `sitar ape` does (TUM stamps by [`TimeUnitRule::Auto`]):
/// quaternions normalised, a repeated stamp kept with a warning (published ground truth
/// repeats some, and evo keeps both poses); a stamp below the previous one is refused, since
/// windows and association follow time. Errors name the file (and line and column for bad
/// content).
pub fn read(path: &Path, format: Format) -> Result<Trajectory> {
    read_with(path, format, TimeUnitRule::Auto)
}

/// [`read`] with an explicit rule for TUM stamps (`--time_unit`).
pub fn read_with(path: &Path, format: Format, time_unit: TimeUnitRule) -> Result<Trajectory> {
    let options = ReadOptions {
        time_unit,
        ..ReadOptions::EVO
    };
    let (trajectory, report) = match format {
        Format::Tum => read_tum_with(path, &options),
        Format::Euroc => read_euroc_csv_with(path, &options),
        Format::Kitti => read_kitti(path).map(|t| (t, ReadReport::default())),
    }?;
    if trajectory.is_empty() {
        bail!("{}: no poses", path.display());
    }
    if let Some(line) = report.first_decreasing_line {
        bail!(
            "{}: line {line}: the timestamp is below the previous one ({} such); windows follow time, so the poses must be in time order",
            path.display(),
            report.decreasing_stamps
        );
    }
    if let Some(line) = report.first_repeated_line {
        eprintln!(
            "warning: {}: {} repeated timestamp(s), the first on line {line}; both poses are kept, as evo keeps them",
            path.display(),
            report.repeated_stamps
        );
    }
    Ok(trajectory)
}

/// Expands the trial arguments: files stay in the order given; a directory contributes its
/// `*.txt` files in natural order (`trajectory_2.txt` before `trajectory_10.txt`).
pub fn expand_trials(args: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for arg in args {
        if arg.is_dir() {
            files.extend(trial_files(arg)?);
        } else {
            files.push(arg.clone());
        }
    }
    Ok(files)
}

/// The `*.txt` files of a directory in natural order.
pub fn trial_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("{}: cannot list", dir.display()))?;
    let mut files = Vec::new();
    for entry in entries {
        let path = entry
            .with_context(|| format!("{}: cannot list", dir.display()))?
            .path();
        if path.is_file() && path.extension().is_some_and(|e| e == "txt") {
            files.push(path);
        }
    }
    files.sort_by_cached_key(|p| natural_key(p));
    if files.is_empty() {
        bail!("{}: no trial files (*.txt)", dir.display());
    }
    Ok(files)
}

/// Sort key splitting a file name into text and number runs.
fn natural_key(path: &Path) -> Vec<(String, u128)> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut key = Vec::new();
    let mut chars = name.chars().peekable();
    while chars.peek().is_some() {
        let text: String = std::iter::from_fn(|| chars.next_if(|c| !c.is_ascii_digit())).collect();
        let digits: String = std::iter::from_fn(|| chars.next_if(char::is_ascii_digit)).collect();
        key.push((text, digits.parse().unwrap_or(0)));
    }
    key
}

/// Reads many trajectories in parallel, keeping their order; stops at the first error.
pub fn read_all(
    paths: &[PathBuf],
    format: Format,
    progress: &ProgressBar,
) -> Result<Vec<Trajectory>> {
    read_all_with(paths, format, TimeUnitRule::Auto, progress)
}

/// [`read_all`] with an explicit rule for TUM stamps (`--time_unit`).
pub fn read_all_with(
    paths: &[PathBuf],
    format: Format,
    time_unit: TimeUnitRule,
    progress: &ProgressBar,
) -> Result<Vec<Trajectory>> {
    paths
        .par_iter()
        .map(|p| {
            let t = read_with(p, format, time_unit);
            progress.inc(1);
            t
        })
        .collect()
}

/// A progress bar on stderr, only when stderr is a terminal.
pub fn progress_bar(len: u64, message: &str) -> ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len).with_message(message.to_owned());
    if let Ok(style) = ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} {elapsed}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn natural_order_sorts_numbers_by_value() {
        let mut v: Vec<PathBuf> = [
            "trajectory_10.txt",
            "trajectory_2.txt",
            "trajectory_1.txt",
            "a.txt",
        ]
        .iter()
        .map(PathBuf::from)
        .collect();
        v.sort_by_cached_key(|p| natural_key(p));
        let names: Vec<_> = v.iter().map(|p| p.to_string_lossy().into_owned()).collect();
        assert_eq!(
            names,
            [
                "a.txt",
                "trajectory_1.txt",
                "trajectory_2.txt",
                "trajectory_10.txt"
            ]
        );
    }
}
