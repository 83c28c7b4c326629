//! `sitar evaluate`'s report as aligned text tables.

use std::fmt::Write as _;

use sitar_estimator::{PAPER_CLASSIFIERS, Thresholds};

use crate::analysis::evaluate::statistics::Computed;
use crate::analysis::evaluate::windows::Evaluated;

impl Computed {
    pub(super) fn table(&self, evaluated: &[Evaluated]) -> String {
        let mut out = String::new();
        let protocol = if self.own_truth {
            "true error: each run of set B's own, the run estimated as the live one with k − 1 others as its replays"
        } else {
            "true error: mean over set A, estimate: first k of set B"
        };
        let _ = writeln!(
            out,
            "{} sequence(s); {protocol}; mean over sequences [{:.0} % bootstrap interval]",
            evaluated.len(),
            100.0 * self.confidence
        );
        if let Some(name) = &self.calibration_name {
            let _ = writeln!(out, "estimate calibrated by {name}");
        }
        for e in evaluated {
            let _ = writeln!(
                out,
                "  {}: {} + {} trials, {} windows",
                e.input.name, e.trials_a, e.trials_b, e.by_window[0].0
            );
        }
        let several_windows = self
            .averaged
            .iter()
            .any(|r| r.window_frames != self.averaged[0].window_frames);
        for bounds in PAPER_CLASSIFIERS {
            let _ = writeln!(out);
            let _ = writeln!(out, "class boundaries {}", cm(&bounds));
            let _ = writeln!(
                out,
                "{:<14} {:>6} {:>6} {:>8} {:>22} {:>20} {:>12} {:>12} {:>6}",
                "setting",
                "frames",
                "trials",
                "windows",
                "accuracy",
                "F1",
                "sensitivity",
                "specificity",
                "over"
            );
            for r in self.averaged.iter().filter(|r| r.boundaries == bounds) {
                let _ = writeln!(
                    out,
                    "{:<14} {:>6} {:>6} {:>8} {:>6.1}% [{:>5.1}, {:>5.1}] {:>6.3} [{:.3}, {:.3}] {:>12.3} {:>12.3} {:>5.0}%",
                    r.setting.to_string(),
                    r.window_frames,
                    r.trials,
                    r.windows,
                    100.0 * r.accuracy.mean,
                    100.0 * r.accuracy.low,
                    100.0 * r.accuracy.high,
                    r.macro_f1.mean,
                    r.macro_f1.low,
                    r.macro_f1.high,
                    r.sensitivity.mean,
                    r.specificity.mean,
                    100.0 * r.over_predicted
                );
            }
        }
        let _ = writeln!(out);
        let _ = writeln!(
            out,
            "estimate vs truth per window: median ratio estimate/truth and Spearman's rank correlation"
        );
        for r in &self.agreement {
            let _ = writeln!(
                out,
                "agreement {:<14}{} trials {:>3}: ratio {:.2} [{:.2}, {:.2}] (all windows {:.2}), rank correlation {:.3} [{:.3}, {:.3}]",
                r.setting.to_string(),
                if several_windows {
                    format!(" frames {:>3}", r.window_frames)
                } else {
                    String::new()
                },
                r.trials,
                r.ratio.mean,
                r.ratio.low,
                r.ratio.high,
                r.pooled_ratio,
                r.rank_correlation.mean,
                r.rank_correlation.low,
                r.rank_correlation.high
            );
            let _ = writeln!(
                out,
                "          {:<14}{} high (≥ 10 cm) called low (< 5 cm): {:.1} % of the high windows{}",
                "",
                if several_windows { "           " } else { "" },
                100.0 * r.pooled_high_called_low,
                match &r.coverage {
                    Some((per, all)) => format!(
                        "; interval coverage {:.1} % (per sequence {})",
                        100.0 * all,
                        per.iter()
                            .map(|c| format!("{:.1} %", 100.0 * c))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                    None => String::new(),
                }
            );
        }
        if let Some((train, rows)) = &self.calibration {
            let _ = writeln!(out);
            let _ = writeln!(
                out,
                "calibration: one scale fitted on the first {train} sequence(s), scored on the other {}",
                evaluated.len() - train
            );
            for r in rows {
                let _ = writeln!(
                    out,
                    "calibrated {:<14} frames {:>3} trials {:>3} {:>12}: scale {:.3}, accuracy {:.1}% -> {:.1}%, F1 {:.3} -> {:.3}",
                    r.setting.to_string(),
                    r.window_frames,
                    r.trials,
                    cm(&r.boundaries),
                    r.scale,
                    100.0 * r.raw.0,
                    100.0 * r.calibrated.0,
                    r.raw.1,
                    r.calibrated.1
                );
            }
        }
        if !self.sweeps.is_empty() {
            let _ = writeln!(out);
            let _ = writeln!(
                out,
                "threshold sweep (all windows): the estimate as a detector of true error >= boundary"
            );
            for r in &self.sweeps {
                let s = &r.sweep;
                let _ = writeln!(
                    out,
                    "sweep {:<14} frames {:>3} trials {:>3} boundary {:>4.0} cm: {} positive / {} negative, ROC AUC {:.3}, average precision {:.3}, best F1 {:.3} at {:.1} cm",
                    r.setting.to_string(),
                    r.window_frames,
                    r.trials,
                    100.0 * s.boundary_m,
                    s.positives,
                    s.negatives,
                    s.roc_auc,
                    s.average_precision,
                    s.best_f1,
                    100.0 * s.best_f1_threshold_m
                );
            }
        }
        out
    }
}

pub(super) fn cm(b: &Thresholds) -> String {
    format!("{} & {} cm", b.medium * 100.0, b.high * 100.0)
}
