//! `sitar evaluate`'s scores: per sequence and averaged over sequences with bootstrap
//! intervals, estimate/truth agreement and threshold sweeps, for every (window frames,
//! setting, trials, boundaries).

use anyhow::Result;
use sitar_estimator::{
    ClassificationScores, MeanInterval, PAPER_CLASSIFIERS, Setting, ThresholdSweep, Thresholds,
    bootstrap_mean, classification_scores, high_called_low, median_ratio, spearman,
    threshold_sweep,
};

use crate::analysis::evaluate::args::Args;
use crate::analysis::evaluate::calibration::{CalibrationRow, calibrate};
use crate::analysis::evaluate::windows::{Evaluated, held, pooled, windows_of};

/// The true-error boundaries a threshold sweep looks at (metres): the paper's 2, 5 and 10 cm.
pub(super) const SWEEP_BOUNDARIES: [f64; 3] = [0.02, 0.05, 0.10];

/// Scores of one sequence for one (window frames, setting, trials, boundaries).
pub(super) struct SequenceRow {
    pub(super) sequence: usize,
    pub(super) window_frames: usize,
    pub(super) setting: Setting,
    pub(super) trials: usize,
    pub(super) boundaries: Thresholds,
    pub(super) scores: ClassificationScores,
}

/// The mean over sequences of one (window frames, setting, trials, boundaries).
pub(super) struct AveragedRow {
    pub(super) window_frames: usize,
    pub(super) setting: Setting,
    pub(super) trials: usize,
    pub(super) boundaries: Thresholds,
    pub(super) accuracy: MeanInterval,
    pub(super) macro_f1: MeanInterval,
    pub(super) sensitivity: MeanInterval,
    pub(super) specificity: MeanInterval,
    /// Share of the misclassified windows (all sequences) whose class was predicted too high.
    pub(super) over_predicted: f64,
    pub(super) windows: usize,
}

/// How the estimate follows the truth for one (window frames, setting, trials).
pub(super) struct AgreementRow {
    pub(super) window_frames: usize,
    pub(super) setting: Setting,
    pub(super) trials: usize,
    /// Per sequence: median estimate/truth ratio and Spearman's rank correlation.
    pub(super) ratios: Vec<f64>,
    pub(super) spearman: Vec<f64>,
    pub(super) ratio: MeanInterval,
    pub(super) rank_correlation: MeanInterval,
    /// Over the windows of all sequences together.
    pub(super) pooled_ratio: f64,
    /// Per sequence: the share of the truly high windows (5 & 10 cm) the estimate calls low.
    pub(super) high_called_low: Vec<f64>,
    /// The same over the windows of all sequences.
    pub(super) pooled_high_called_low: f64,
    /// With a calibration: per sequence and over all windows, the share of windows whose
    /// interval holds the true error.
    pub(super) coverage: Option<(Vec<f64>, f64)>,
}

/// One sweep over the pooled windows of every sequence.
pub(super) struct SweepRow {
    pub(super) window_frames: usize,
    pub(super) setting: Setting,
    pub(super) trials: usize,
    pub(super) sweep: ThresholdSweep,
}

pub(super) struct Computed {
    pub(super) per_sequence: Vec<SequenceRow>,
    pub(super) averaged: Vec<AveragedRow>,
    pub(super) agreement: Vec<AgreementRow>,
    pub(super) calibration: Option<(usize, Vec<CalibrationRow>)>,
    pub(super) sweeps: Vec<SweepRow>,
    pub(super) confidence: f64,
    /// The calibration scored (`--calibration`), by its file name.
    pub(super) calibration_name: Option<String>,
    /// `--truth own`: each live run against its own error.
    pub(super) own_truth: bool,
}

impl Computed {
    pub(super) fn new(
        args: &Args,
        evaluated: &[Evaluated],
        window_frames: &[usize],
        settings: &[Setting],
        counts: &[usize],
    ) -> Result<Self> {
        let interval = |values: &[f64], salt: u64| -> MeanInterval {
            bootstrap_mean(values, args.bootstrap, args.confidence, 0x5175_7a72 ^ salt).unwrap_or(
                MeanInterval {
                    mean: f64::NAN,
                    low: f64::NAN,
                    high: f64::NAN,
                },
            )
        };
        let mut per_sequence = Vec::new();
        let mut averaged = Vec::new();
        let mut agreement = Vec::new();
        let mut sweeps = Vec::new();
        let mut salt = 0u64;
        for (w, &frames) in window_frames.iter().enumerate() {
            for &trials in counts {
                for &setting in settings {
                    let windows = windows_of(evaluated, w, setting, trials);
                    let (ratios, ranks): (Vec<f64>, Vec<f64>) = windows
                        .iter()
                        .map(|m| {
                            (
                                median_ratio(&m.truth, &m.estimate).unwrap_or(f64::NAN),
                                spearman(&m.truth, &m.estimate).unwrap_or(f64::NAN),
                            )
                        })
                        .unzip();
                    let (truth, estimate) = pooled(&windows);
                    let high_low_per_sequence: Vec<f64> = windows
                        .iter()
                        .map(|m| high_called_low(&m.truth, &m.estimate, Thresholds::DEFAULT_M))
                        .collect();
                    let coverage = windows.iter().all(|m| !m.lower.is_empty()).then(|| {
                        let per: Vec<(usize, usize)> = windows.iter().map(|m| held(m)).collect();
                        let (inside, total) =
                            per.iter().fold((0, 0), |(a, b), &(i, t)| (a + i, b + t));
                        (
                            per.iter().map(|&(i, t)| i as f64 / t as f64).collect(),
                            inside as f64 / total.max(1) as f64,
                        )
                    });
                    salt += 1;
                    agreement.push(AgreementRow {
                        pooled_high_called_low: high_called_low(
                            &truth,
                            &estimate,
                            Thresholds::DEFAULT_M,
                        ),
                        high_called_low: high_low_per_sequence,
                        coverage,
                        window_frames: frames,
                        setting,
                        trials,
                        ratio: interval(&ratios, salt),
                        rank_correlation: interval(&ranks, salt + (1 << 40)),
                        ratios,
                        spearman: ranks,
                        pooled_ratio: median_ratio(&truth, &estimate).unwrap_or(f64::NAN),
                    });
                    if args.sweep && trials == *counts.last().unwrap_or(&trials) {
                        for boundary in SWEEP_BOUNDARIES {
                            sweeps.push(SweepRow {
                                window_frames: frames,
                                setting,
                                trials,
                                sweep: threshold_sweep(&truth, &estimate, boundary)?,
                            });
                        }
                    }
                    for boundaries in PAPER_CLASSIFIERS {
                        let mut scores = Vec::new();
                        for (sequence, m) in windows.iter().enumerate() {
                            let s = classification_scores(&m.truth, &m.estimate, boundaries)?;
                            per_sequence.push(SequenceRow {
                                sequence,
                                window_frames: frames,
                                setting,
                                trials,
                                boundaries,
                                scores: s,
                            });
                            scores.push(s);
                        }
                        let metric = |f: fn(&ClassificationScores) -> f64| -> Vec<f64> {
                            scores.iter().map(f).collect()
                        };
                        let (mut over, mut wrong) = (0usize, 0usize);
                        for s in &scores {
                            for t in 0..3 {
                                for p in 0..3 {
                                    if p != t {
                                        wrong += s.confusion[t][p];
                                        if p > t {
                                            over += s.confusion[t][p];
                                        }
                                    }
                                }
                            }
                        }
                        salt += 4;
                        averaged.push(AveragedRow {
                            window_frames: frames,
                            setting,
                            trials,
                            boundaries,
                            accuracy: interval(&metric(|s| s.accuracy), salt),
                            macro_f1: interval(&metric(|s| s.macro_f1), salt + 1),
                            sensitivity: interval(&metric(|s| s.sensitivity), salt + 2),
                            specificity: interval(&metric(|s| s.specificity), salt + 3),
                            over_predicted: if wrong > 0 {
                                over as f64 / wrong as f64
                            } else {
                                f64::NAN
                            },
                            windows: scores.iter().map(|s| s.windows).sum(),
                        });
                    }
                }
            }
        }
        let calibration = if args.calibrate {
            Some(calibrate(args, evaluated, window_frames, settings, counts)?)
        } else {
            None
        };
        Ok(Self {
            per_sequence,
            averaged,
            agreement,
            calibration,
            sweeps,
            confidence: args.confidence,
            own_truth: args.truth == crate::analysis::evaluate::args::Truth::Own,
            calibration_name: args
                .calibration
                .as_deref()
                .map(crate::analysis::estimate::calibration_name),
        })
    }
}
