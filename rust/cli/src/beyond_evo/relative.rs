//! `sitar relative`: rpg_trajectory_evaluation's relative error at sub-trajectory lengths,
//! computed by `sitar_estimator::relative_errors`; this module parses, pairs, aligns, prints
//! and plots, as `drift` does.

use anyhow::{Result, anyhow, bail};
use serde_json::{Value, json};
use sitar_estimator::{
    RPG_DEFAULT_PERCENTS, RelativeAtLength, RelativeSample, Statistics, cumulative_path_length,
    lengths_from_percents, relative_errors,
};

use crate::beyond_evo::shared_args::{
    AlignmentArgs, AlignmentWords, LengthArgs, LengthWords, ReportArgs, ReportWords,
};
use crate::figures::canvas::Page;
use crate::figures::figure::{DistributionKind, Drawing};
use crate::io::console::{Console, SEP, UsabilityArgs};
use crate::io::output::{OutputFormat, emit, json_number};
use crate::io::source::{self, format_subcommands};
use crate::results::runs::{across_table, csv_field, run_label, table};
use sitar_evo::document::across_trials;
use sitar_evo::{AlgorithmOptions, Loaded};

/// Relative error at sub-trajectory lengths, as rpg_trajectory_evaluation defines it.
///
/// Every pose starts one sub-trajectory per length L (--lengths in metres, or
/// --lengths_percent of the reference's path, default 10,20,30,40,50 % truncated to cm as
/// rpg does); it ends at the pose whose path distance is nearest to L, within 0.2·L. Per
/// sub-trajectory: translation error (m, %), rotation angle (deg, deg/m), and its yaw and
/// roll/pitch parts in the world frame. Alignment changes only the scale (-s, Sim(3)), as in
/// rpg. Several estimates are repeated runs of one system.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar relative tum ground_truth.txt run0.txt\n  sitar relative tum gt.txt run0.txt run1.txt --lengths 8,16,24 --format json -o rel.json\n  sitar relative euroc data.csv est.tum -as --save_plot rel.pdf"
)]
pub struct Args {
    #[command(subcommand)]
    source: Format,
}

/// `sitar relative`'s options.
#[derive(clap::Args, Debug)]
pub struct Options {
    #[command(flatten)]
    sub_trajectories: LengthArgs<RelativeWords>,
    #[command(flatten)]
    alignment: AlignmentArgs<RelativeWords>,
    #[command(flatten)]
    report: ReportArgs<RelativeWords>,
    #[command(flatten)]
    usability: UsabilityArgs,
}

format_subcommands!(Format, Options);

/// `sitar relative`'s help for the options it shares with `sitar drift` and `sitar bench`.
#[derive(Debug)]
pub struct RelativeWords;

impl LengthWords for RelativeWords {
    const LENGTHS: &'static str = "Sub-trajectory lengths in metres, comma-separated";
    const LENGTHS_PERCENT: &'static str = "Sub-trajectory lengths as percentages of the \
        reference's path [default: 10,20,30,40,50]";
}

impl AlignmentWords for RelativeWords {
    const ALIGN: &'static str =
        "Alignment with Umeyama's method (a rigid alignment leaves every error as it is)";
    const CORRECT_SCALE: &'static str =
        "Correct scale with Umeyama's method: the estimate's relative translations are scaled";
    const N_TO_ALIGN: &'static str =
        "The number of poses to use for the alignment, counted from the start (-1: all)";
    const YAW_ONLY: &'static str =
        "With -a: 4-DoF alignment (rpg's posyaw). Cannot be combined with -s";
}

impl ReportWords for RelativeWords {
    const PLOT: &'static str =
        "Show the box plots (one box per length); without a display sitar says so";
    const SAVE_PLOT: &'static str =
        "Save the box plots: PNG, SVG or PDF by the extension (FILE_trans_percent.png, …)";
    const FORMAT: &'static str =
        "Print CSV (one row per sub-trajectory) or JSON instead of the tables";
    const HTML: &'static str = "Also write one self-contained HTML page (tables, every box plot \
        inline, the JSON document); it fetches nothing when opened";
}

/// The metrics, as the JSON and CSV name them, and their labels.
const METRICS: [(&str, &str); 6] = [
    ("trans_m", "trans (m)"),
    ("trans_percent", "trans (%)"),
    ("rot_deg", "rot (deg)"),
    ("rot_deg_per_m", "rot (deg/m)"),
    ("yaw_deg", "yaw (deg)"),
    ("roll_pitch_deg", "roll/pitch (deg)"),
];

fn metric(s: &RelativeSample, name: &str) -> f64 {
    match name {
        "trans_m" => s.trans_m,
        "trans_percent" => s.trans_percent,
        "rot_deg" => s.rot_deg,
        "rot_deg_per_m" => s.rot_deg_per_m,
        "yaw_deg" => s.yaw_deg,
        _ => s.roll_pitch_deg,
    }
}

struct Outcome {
    est_name: String,
    ref_name: String,
    scale: f64,
    at: Vec<RelativeAtLength>,
}

impl Outcome {
    /// Every sample of every length.
    fn all(&self) -> impl Iterator<Item = &RelativeSample> {
        self.at.iter().flat_map(|a| &a.samples)
    }

    fn mean(&self, name: &str) -> f64 {
        let v: Vec<f64> = self.all().map(|s| metric(s, name)).collect();
        Statistics::from_errors(&v).mean
    }
}

pub fn run(args: Args) -> Result<()> {
    let (source, options) = args.source.split();
    let console = Console::new(&options.usability)?;
    if options.alignment.yaw_only && options.alignment.correct_scale {
        bail!("--yaw_only cannot be combined with -s (posyaw has no scale)");
    }
    let runs = source::load(&source, &console)?;
    let outcomes = runs
        .into_iter()
        .map(|loaded| compute(loaded, &options, &console))
        .collect::<Result<Vec<_>>>()?;
    emit_outcomes(&outcomes, &options, &console)
}

fn compute(loaded: Loaded, options: &Options, console: &Console) -> Result<Outcome> {
    let Loaded {
        reference,
        estimate,
        sync,
    } = loaded;
    let (ref_name, est_name) = (reference.name, estimate.name);
    let lengths = match (
        &options.sub_trajectories.lengths,
        &options.sub_trajectories.lengths_percent,
    ) {
        (Some(m), _) => m.clone(),
        (None, p) => lengths_from_percents(
            cumulative_path_length(&reference.trajectory),
            p.as_deref().unwrap_or(&RPG_DEFAULT_PERCENTS),
        ),
    };
    let (mut reference, mut estimate) = (reference.trajectory, estimate.trajectory);
    if let Some(sync) = &sync {
        (reference, estimate, _) = sitar_evo::sync::synchronise(
            reference,
            estimate,
            sync,
            (&ref_name, &est_name),
            console,
        )?;
    } else if reference.len() != estimate.len() {
        bail!(
            "trajectories must have same number of poses ({ref_name}: {}, {est_name}: {})",
            reference.len(),
            estimate.len()
        );
    }
    let algorithm = AlgorithmOptions {
        align: options.alignment.align,
        correct_scale: options.alignment.correct_scale,
        n_to_align: options.alignment.n_to_align,
        yaw_only: options.alignment.yaw_only,
        ..AlgorithmOptions::default()
    };
    // rpg uses the estimate as read and only the alignment's scale (see the estimator).
    let mut aligned = estimate.clone();
    let (_, transform, _) =
        sitar_evo::align::align_estimate(&algorithm, &mut aligned, &reference, console)?;
    let scale = transform.map_or(1.0, |t| t.scale);
    let at = relative_errors(&reference, &estimate, scale, &lengths)
        .map_err(|e| anyhow!("{est_name}: {e}"))?;
    Ok(Outcome {
        est_name,
        ref_name,
        scale,
        at,
    })
}

fn stats_json(values: &[f64]) -> Value {
    if values.is_empty() {
        return Value::Null;
    }
    let s = Statistics::from_errors(values);
    json!({"rmse": json_number(s.rmse), "mean": json_number(s.mean),
           "median": json_number(s.median), "std": json_number(s.std),
           "min": json_number(s.min), "max": json_number(s.max)})
}

fn document(o: &Outcome) -> Value {
    let by_length: Vec<Value> =
        o.at.iter()
            .map(|a| {
                let mut entry = json!({"length_m": a.length_m, "samples": a.samples.len()});
                for (name, _) in METRICS {
                    let v: Vec<f64> = a.samples.iter().map(|s| metric(s, name)).collect();
                    entry[name] = stats_json(&v);
                }
                entry
            })
            .collect();
    json!({
        "version": 1,
        "metric": "relative",
        "reference": o.ref_name,
        "estimate": o.est_name,
        "scale": json_number(o.scale),
        "lengths_m": o.at.iter().map(|a| a.length_m).collect::<Vec<_>>(),
        "by_length": by_length,
    })
}

fn length_table(o: &Outcome) -> String {
    let mut header = vec!["length (m)", "samples"];
    header.extend(METRICS.map(|m| m.1));
    let rows: Vec<Vec<String>> =
        o.at.iter()
            .map(|a| {
                let mut row = vec![a.length_m.to_string(), a.samples.len().to_string()];
                for (name, _) in METRICS {
                    let v: Vec<f64> = a.samples.iter().map(|s| metric(s, name)).collect();
                    row.push(if v.is_empty() {
                        "–".into()
                    } else {
                        format!("{:.6}", Statistics::from_errors(&v).mean)
                    });
                }
                row
            })
            .collect();
    table(&header, &rows, 0) + "(means per length)\n"
}

fn emit_outcomes(outcomes: &[Outcome], options: &Options, console: &Console) -> Result<()> {
    let names: Vec<&str> = METRICS.map(|m| m.0).to_vec();
    let n = outcomes.len();
    let value = |k: usize, name: &str| outcomes[k].mean(name);
    // The JSON document: one run's, or the runs' with their summary.
    let full_document = || match n {
        1 => document(&outcomes[0]),
        _ => json!({
            "version": 1,
            "metric": "relative",
            "reference": outcomes[0].ref_name,
            "runs": n,
            "trials": outcomes.iter().map(document).collect::<Vec<_>>(),
            "across_trials": across_trials(&names, value, n),
        }),
    };
    match (options.report.format, n) {
        (Some(OutputFormat::Json), _) => emit(
            options.report.output.as_deref(),
            &(full_document().to_string() + "\n"),
        )?,
        (Some(OutputFormat::Csv), _) => {
            let mut text = format!("trial,estimate,length_m,start,end,{}\n", names.join(","));
            for (k, o) in outcomes.iter().enumerate() {
                for a in &o.at {
                    for s in &a.samples {
                        let cells: Vec<String> =
                            names.iter().map(|m| metric(s, m).to_string()).collect();
                        text += &format!(
                            "{k},{},{},{},{},{}\n",
                            csv_field(&o.est_name),
                            a.length_m,
                            s.start,
                            s.end,
                            cells.join(",")
                        );
                    }
                }
            }
            emit(options.report.output.as_deref(), &text)?;
        }
        (None, _) => {
            console.debug(SEP)?;
            let mut text = String::new();
            for o in outcomes {
                text += &format!(
                    "relative error at sub-trajectory lengths (rpg_trajectory_evaluation), scale {}\n{} against {}\n\n{}\n",
                    o.scale,
                    o.est_name,
                    o.ref_name,
                    length_table(o)
                );
            }
            if n > 1 {
                text += &across_table(&names, value, n);
            }
            console.info(text.trim_end())?;
        }
    }
    // One box per length, every run pooled (rpg's per-dataset box plots).
    let boxes: Vec<(String, Drawing)> = METRICS
        .iter()
        .map(|(name, label)| {
            let groups = outcomes[0]
                .at
                .iter()
                .enumerate()
                .map(|(i, a)| {
                    let values = outcomes
                        .iter()
                        .flat_map(|o| o.at[i].samples.iter().map(|s| metric(s, name)))
                        .collect();
                    (format!("{} m", a.length_m), values)
                })
                .collect();
            let drawing = Drawing::Distributions {
                title: format!(
                    "relative error, {n} run(s): {}",
                    run_label(&outcomes[0].est_name)
                ),
                label: (*label).to_owned(),
                kind: DistributionKind::Box,
                groups,
            };
            ((*name).to_owned(), drawing)
        })
        .collect();
    let pages: Vec<(&str, Page<'_>)> = boxes
        .iter()
        .map(|(name, d)| (name.as_str(), Page::Other(d)))
        .collect();
    crate::results::runs::plots(
        &pages,
        options.report.plot,
        options.report.save_plot.as_deref(),
        None,
        console,
    )?;
    if let Some(path) = &options.report.html {
        crate::figures::html::write(path, &full_document(), &pages)?;
    }
    Ok(())
}
