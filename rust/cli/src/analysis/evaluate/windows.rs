//! One sequence evaluated (the matched windows of every window length, setting and trial
//! count), and those windows gathered over sequences.

use sitar_estimator::{MatchedWindows, Setting};

use crate::analysis::sequences::SequenceInput;

/// One sequence evaluated: per window length, the matched windows of every (k, setting).
pub(super) struct Evaluated {
    pub(super) input: SequenceInput,
    pub(super) trials_a: usize,
    pub(super) trials_b: usize,
    /// Per entry of `window_frames`: ground-truth windows and the matched windows.
    pub(super) by_window: Vec<(usize, Vec<MatchedWindows>)>,
}

/// The windows of every sequence for one (window-frames index, setting, trials).
pub(super) fn windows_of(
    evaluated: &[Evaluated],
    w: usize,
    setting: Setting,
    trials: usize,
) -> Vec<&MatchedWindows> {
    evaluated
        .iter()
        .filter_map(|e| {
            e.by_window[w]
                .1
                .iter()
                .find(|m| m.setting == setting && m.trials == trials)
        })
        .collect()
}

pub(super) fn pooled(windows: &[&MatchedWindows]) -> (Vec<f64>, Vec<f64>) {
    let truth = windows
        .iter()
        .flat_map(|m| m.truth.iter().copied())
        .collect();
    let estimate = windows
        .iter()
        .flat_map(|m| m.estimate.iter().copied())
        .collect();
    (truth, estimate)
}

/// (windows whose interval holds the truth, windows).
pub(super) fn held(m: &MatchedWindows) -> (usize, usize) {
    let inside = (0..m.truth.len())
        .filter(|&i| m.lower[i] <= m.truth[i] && m.truth[i] <= m.upper[i])
        .count();
    (inside, m.truth.len())
}
