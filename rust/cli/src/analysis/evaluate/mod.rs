//! `sitar evaluate`: the paper's evaluation protocol (section 3.3, Figure 5, Table 2) against
//! ground truth, over one or many sequences, with what the paper left open: bootstrap
//! intervals over sequences, estimate/truth agreement, a calibrated scale, threshold sweeps
//! and the sub-trajectory length.

mod args;
mod calibration;
mod documents;
mod plot;
mod statistics;
mod table;
mod windows;

pub use args::Args;

use anyhow::{Context, Result, bail};
use sitar_estimator::{
    Calibration, EstimateOptions, EvaluationOptions, PAPER_CLASSIFIERS, Setting,
    calibrated_matched_windows, matched_windows, own_error_matched_windows,
};

use crate::analysis::sequences::{self, SequenceInput};
use crate::io::input::{self, progress_bar};
use crate::io::output::emit;

use crate::analysis::evaluate::args::{Report, Truth};
use crate::analysis::evaluate::plot::{PlotRow, plot};
use crate::analysis::evaluate::statistics::Computed;
use crate::analysis::evaluate::windows::Evaluated;

/// The paper's trial counts.
const PAPER_COUNTS: [usize; 11] = [5, 10, 20, 30, 40, 50, 60, 70, 80, 90, 100];

/// Expands the SEQUENCE arguments (or the single-sequence flags).
fn sequence_inputs(args: &Args) -> Result<Vec<SequenceInput>> {
    if let (Some(gt), Some(a), Some(b)) = (&args.ground_truth, &args.trials_a, &args.trials_b) {
        return Ok(vec![SequenceInput {
            name: gt.display().to_string(),
            ground_truth: gt.clone(),
            set_a: input::trial_files(a)?,
            set_b: input::trial_files(b)?,
            dir_a: a.clone(),
            dir_b: b.clone(),
        }]);
    }
    if args.sequences.is_empty() {
        bail!("give SEQUENCE directories, or --ground_truth with --trials_a and --trials_b");
    }
    sequences::sequence_inputs(&args.sequences, args.split)
}

pub fn run(args: Args) -> Result<()> {
    let window_frames = args
        .window_frames
        .clone()
        .unwrap_or_else(|| vec![args.delta]);
    if window_frames.contains(&0) {
        bail!("--delta and --window_frames must be at least 1 frame");
    }
    if !(args.confidence > 0.0 && args.confidence < 1.0) {
        bail!(
            "--confidence must be between 0 and 1, got {}",
            args.confidence
        );
    }
    if args.bootstrap == 0 || args.bootstrap > 1_000_000 {
        bail!(
            "--bootstrap must be between 1 and 1000000, got {}",
            args.bootstrap
        );
    }
    let inputs = sequence_inputs(&args)?;
    let calibration = match &args.calibration {
        Some(path) => Some(Calibration::read(path)?),
        None => None,
    };
    let settings = match (&args.settings, &calibration) {
        (Some(settings), _) => settings.clone(),
        // A calibration is fitted for one setting.
        (None, Some(c)) => vec![c.fitted_on.setting.parse()?],
        (None, None) => Setting::ALL.to_vec(),
    };
    let bar = progress_bar(inputs.len() as u64, "evaluating sequences");
    let mut evaluated = Vec::new();
    let mut counts: Option<Vec<usize>> = None;
    for input in inputs {
        let (files_a, files_b) = (input.set_a.clone(), input.set_b.clone());
        if files_b.len() < 2 {
            bail!(
                "{}: the estimate needs at least 2 trials, found {}",
                input.dir_b.display(),
                files_b.len()
            );
        }
        let fewest = if args.truth == Truth::Own && calibration.is_some() {
            1
        } else {
            2
        };
        let these = trial_counts(&args, files_b.len(), fewest)?;
        match &counts {
            Some(c) if *c != these => bail!(
                "{}: {} trials in set B give other trial counts than the first sequence's; give --trial_counts",
                input.dir_b.display(),
                files_b.len()
            ),
            _ => counts = Some(these.clone()),
        }
        let hidden = indicatif::ProgressBar::hidden();
        let gt = input::read(&input.ground_truth, args.input_format)?;
        let trials_a = input::read_all(&files_a, args.input_format, &hidden)?;
        let trials_b = input::read_all(&files_b, args.input_format, &hidden)?;
        let context = || {
            format!(
                "evaluating {} (trial i = the i-th file of {} or {})",
                input.name,
                input.dir_a.display(),
                input.dir_b.display()
            )
        };
        let mut by_window = Vec::new();
        for &delta in &window_frames {
            let opts = EvaluationOptions {
                trial_counts: these.clone(),
                settings: settings.clone(),
                boundaries: PAPER_CLASSIFIERS.to_vec(),
                estimate: EstimateOptions {
                    delta,
                    t_max_diff_s: args.t_max_diff,
                    ..EstimateOptions::default()
                },
            };
            let matched = match (args.truth, &calibration) {
                (Truth::Own, c) => own_error_matched_windows(&gt, &trials_b, &opts, c.as_ref()),
                (Truth::Expected, Some(c)) => {
                    calibrated_matched_windows(&gt, &trials_a, &trials_b, &opts, c)
                }
                (Truth::Expected, None) => matched_windows(&gt, &trials_a, &trials_b, &opts),
            };
            by_window.push(matched.with_context(context)?);
        }
        evaluated.push(Evaluated {
            input,
            trials_a: files_a.len(),
            trials_b: files_b.len(),
            by_window,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let counts = counts.unwrap_or_default();
    let report = Computed::new(&args, &evaluated, &window_frames, &settings, &counts)?;
    let text = match args.format {
        Report::Table => report.table(&evaluated),
        Report::Csv => report.csv(&evaluated),
        Report::Json => report.json(&evaluated),
    };
    emit(args.output.as_deref(), &text)?;
    if !args.no_plot {
        let rows: Vec<PlotRow> = report
            .averaged
            .iter()
            .filter(|r| r.window_frames == window_frames[0])
            .map(|r| PlotRow {
                boundaries: r.boundaries,
                setting: r.setting,
                trials: r.trials,
                accuracy: r.accuracy.mean,
                macro_f1: r.macro_f1.mean,
            })
            .collect();
        plot(&args.plot, &rows, &settings, &counts)?;
        eprintln!("wrote the plot to {}", args.plot.display());
    }
    Ok(())
}

fn trial_counts(args: &Args, available: usize, fewest: usize) -> Result<Vec<usize>> {
    Ok(match &args.trial_counts {
        Some(counts) => {
            if let Some(&bad) = counts.iter().find(|&&k| k < fewest || k > available) {
                bail!(
                    "--trial_counts: {bad} is not between {fewest} and the {available} trials of set B"
                );
            }
            counts.clone()
        }
        None => {
            let counts: Vec<usize> = PAPER_COUNTS
                .iter()
                .copied()
                .filter(|&k| k <= available)
                .collect();
            if counts.is_empty() {
                vec![available]
            } else {
                counts
            }
        }
    })
}
