//! `sitar evaluate --calibrate`: a scale fitted on training sequences, scored on the held-out
//! ones.

use anyhow::{Result, bail};
use sitar_estimator::{PAPER_CLASSIFIERS, Setting, Thresholds, classification_scores, fit_scale};

use crate::analysis::evaluate::args::Args;
use crate::analysis::evaluate::windows::{Evaluated, pooled, windows_of};

/// The calibration of one (window frames, setting, trials, boundaries).
pub(super) struct CalibrationRow {
    pub(super) window_frames: usize,
    pub(super) setting: Setting,
    pub(super) trials: usize,
    pub(super) boundaries: Thresholds,
    pub(super) scale: f64,
    pub(super) raw: (f64, f64),
    pub(super) calibrated: (f64, f64),
}

/// `--calibrate`: per (window frames, setting, trials), the scale fitted on the pooled windows
/// of the training sequences, and the held-out sequences' mean accuracy and F1 without and
/// with it, per classifier.
pub(super) fn calibrate(
    args: &Args,
    evaluated: &[Evaluated],
    window_frames: &[usize],
    settings: &[Setting],
    counts: &[usize],
) -> Result<(usize, Vec<CalibrationRow>)> {
    if evaluated.len() < 2 {
        bail!("--calibrate needs at least 2 sequences (a training and a held-out one)");
    }
    let train = args.train.unwrap_or(evaluated.len() / 2).max(1);
    if train >= evaluated.len() {
        bail!(
            "--train {train}: must leave at least one of the {} sequences held out",
            evaluated.len()
        );
    }
    let mut rows = Vec::new();
    for (w, &frames) in window_frames.iter().enumerate() {
        for &trials in counts {
            for &setting in settings {
                let windows = windows_of(evaluated, w, setting, trials);
                let (truth, estimate) = pooled(&windows[..train]);
                let scale = fit_scale(&truth, &estimate)?;
                for boundaries in PAPER_CLASSIFIERS {
                    let (mut raw, mut calibrated) = ((0.0, 0.0), (0.0, 0.0));
                    let held_out = &windows[train..];
                    for m in held_out {
                        let r = classification_scores(&m.truth, &m.estimate, boundaries)?;
                        let scaled: Vec<f64> = m.estimate.iter().map(|e| e * scale).collect();
                        let c = classification_scores(&m.truth, &scaled, boundaries)?;
                        raw = (raw.0 + r.accuracy, raw.1 + r.macro_f1);
                        calibrated = (calibrated.0 + c.accuracy, calibrated.1 + c.macro_f1);
                    }
                    let n = held_out.len() as f64;
                    rows.push(CalibrationRow {
                        window_frames: frames,
                        setting,
                        trials,
                        boundaries,
                        scale,
                        raw: (raw.0 / n, raw.1 / n),
                        calibrated: (calibrated.0 / n, calibrated.1 / n),
                    });
                }
            }
        }
    }
    Ok((train, rows))
}
