//! `sitar evaluate --format csv|json`: the scores as CSV rows or one JSON document.

use std::fmt::Write as _;

use sitar_estimator::{MeanInterval, PAPER_CLASSIFIERS};

use crate::io::output::json_number;

use crate::analysis::evaluate::statistics::Computed;
use crate::analysis::evaluate::windows::Evaluated;

impl Computed {
    pub(super) fn csv(&self, evaluated: &[Evaluated]) -> String {
        let mut out = String::from(
            "sequence,window_frames,medium_m,high_m,setting,trials,windows,accuracy,macro_f1,sensitivity,specificity\n",
        );
        for r in &self.per_sequence {
            let s = &r.scores;
            let _ = writeln!(
                out,
                "{},{},{},{},{},{},{},{},{},{},{}",
                csv_field(&evaluated[r.sequence].input.name),
                r.window_frames,
                r.boundaries.medium,
                r.boundaries.high,
                r.setting,
                r.trials,
                s.windows,
                s.accuracy,
                s.macro_f1,
                s.sensitivity,
                s.specificity
            );
        }
        for r in &self.averaged {
            let _ = writeln!(
                out,
                "mean,{},{},{},{},{},{},{},{},{},{}",
                r.window_frames,
                r.boundaries.medium,
                r.boundaries.high,
                r.setting,
                r.trials,
                r.windows,
                r.accuracy.mean,
                r.macro_f1.mean,
                r.sensitivity.mean,
                r.specificity.mean
            );
        }
        out
    }
    pub(super) fn json(&self, evaluated: &[Evaluated]) -> String {
        let interval = |i: &MeanInterval| serde_json::json!({"mean": json_number(i.mean), "low": json_number(i.low), "high": json_number(i.high)});
        let results: Vec<serde_json::Value> = self
            .per_sequence
            .iter()
            .map(|r| {
                let s = &r.scores;
                serde_json::json!({
                    "sequence": r.sequence,
                    "window_frames": r.window_frames,
                    "boundaries_m": [r.boundaries.medium, r.boundaries.high],
                    "setting": r.setting.to_string(),
                    "trials": r.trials,
                    "windows": s.windows,
                    "accuracy": json_number(s.accuracy),
                    "macro_f1": json_number(s.macro_f1),
                    "sensitivity": json_number(s.sensitivity),
                    "specificity": json_number(s.specificity),
                    "confusion": s.confusion,
                })
            })
            .collect();
        let averaged: Vec<serde_json::Value> = self
            .averaged
            .iter()
            .map(|r| {
                serde_json::json!({
                    "window_frames": r.window_frames,
                    "boundaries_m": [r.boundaries.medium, r.boundaries.high],
                    "setting": r.setting.to_string(),
                    "trials": r.trials,
                    "windows": r.windows,
                    "accuracy": interval(&r.accuracy),
                    "macro_f1": interval(&r.macro_f1),
                    "sensitivity": interval(&r.sensitivity),
                    "specificity": interval(&r.specificity),
                    "over_predicted_share": json_number(r.over_predicted),
                })
            })
            .collect();
        let agreement: Vec<serde_json::Value> = self
            .agreement
            .iter()
            .map(|r| {
                serde_json::json!({
                    "window_frames": r.window_frames,
                    "setting": r.setting.to_string(),
                    "trials": r.trials,
                    "median_ratio": r.ratios.iter().map(|&v| json_number(v)).collect::<Vec<_>>(),
                    "spearman": r.spearman.iter().map(|&v| json_number(v)).collect::<Vec<_>>(),
                    "mean_median_ratio": interval(&r.ratio),
                    "mean_spearman": interval(&r.rank_correlation),
                    "pooled_median_ratio": json_number(r.pooled_ratio),
                    "high_called_low": r.high_called_low.iter().map(|&v| json_number(v)).collect::<Vec<_>>(),
                    "pooled_high_called_low": json_number(r.pooled_high_called_low),
                    "coverage": r.coverage.as_ref().map(|(_, all)| json_number(*all)),
                    "coverage_per_sequence": r.coverage.as_ref().map(|(per, _)| per.iter().map(|&v| json_number(v)).collect::<Vec<_>>()),
                })
            })
            .collect();
        let sequences: Vec<serde_json::Value> = evaluated
            .iter()
            .map(|e| {
                serde_json::json!({
                    "name": e.input.name,
                    "ground_truth": e.input.ground_truth.display().to_string(),
                    "trials_a": e.trials_a,
                    "trials_b": e.trials_b,
                    "truth_windows": e.by_window.iter().map(|(n, _)| n).collect::<Vec<_>>(),
                })
            })
            .collect();
        let first = &evaluated[0];
        let truth_classes: Vec<serde_json::Value> = PAPER_CLASSIFIERS
            .iter()
            .map(|b| {
                let mut n = [0usize; 3];
                for e in evaluated {
                    if let Some(m) = e.by_window[0].1.first() {
                        for &t in &m.truth {
                            n[b.classify(t).index().unwrap_or(0)] += 1;
                        }
                    }
                }
                serde_json::json!({
                    "boundaries_m": [b.medium, b.high], "low": n[0], "medium": n[1], "high": n[2],
                })
            })
            .collect();
        let mut doc = serde_json::json!({
            "version": 2,
            "sequences": sequences,
            "ground_truth": first.input.ground_truth.display().to_string(),
            "trials_a": first.trials_a,
            "trials_b": first.trials_b,
            "truth_windows": evaluated.iter().map(|e| e.by_window[0].0).sum::<usize>(),
            "truth_classes": truth_classes,
            "confidence": self.confidence,
            "results": results,
            "averaged": averaged,
            "agreement": agreement,
        });
        if let Some(name) = &self.calibration_name {
            doc["calibrated_by"] = serde_json::json!(name);
        }
        doc["truth"] = serde_json::json!(if self.own_truth { "own" } else { "expected" });
        if let Some((train, rows)) = &self.calibration {
            doc["calibration"] = serde_json::json!({
                "train_sequences": train,
                "rows": rows.iter().map(|r| serde_json::json!({
                    "window_frames": r.window_frames,
                    "setting": r.setting.to_string(),
                    "trials": r.trials,
                    "boundaries_m": [r.boundaries.medium, r.boundaries.high],
                    "scale": json_number(r.scale),
                    "held_out_raw": {"accuracy": json_number(r.raw.0), "macro_f1": json_number(r.raw.1)},
                    "held_out_calibrated": {"accuracy": json_number(r.calibrated.0), "macro_f1": json_number(r.calibrated.1)},
                })).collect::<Vec<_>>(),
            });
        }
        if !self.sweeps.is_empty() {
            doc["sweeps"] = self
                .sweeps
                .iter()
                .map(|r| {
                    let s = &r.sweep;
                    serde_json::json!({
                        "window_frames": r.window_frames,
                        "setting": r.setting.to_string(),
                        "trials": r.trials,
                        "boundary_m": s.boundary_m,
                        "positives": s.positives,
                        "negatives": s.negatives,
                        "roc_auc": json_number(s.roc_auc),
                        "average_precision": json_number(s.average_precision),
                        "best_f1": json_number(s.best_f1),
                        "best_f1_threshold_m": json_number(s.best_f1_threshold_m),
                        "points": s.points.iter().map(|p| [json_number(p.threshold_m), json_number(p.fpr), json_number(p.tpr), json_number(p.precision)]).collect::<Vec<_>>(),
                    })
                })
                .collect();
        }
        doc.to_string() + "\n"
    }
}

/// A CSV field, quoted when it holds a comma or a quote.
pub(super) fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}
