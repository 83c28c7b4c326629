//! `sitar drift`: the KITTI odometry benchmark's drift (translational error in %, rotational
//! error in deg/m over segments of ground-truth path length), computed by
//! `sitar_estimator::drift`; this module parses, pairs, aligns, prints and plots.

use anyhow::Result;
use serde_json::Value;
use sitar_estimator::{
    Drift, DriftBin, DriftOptions, KITTI_LENGTHS_M, KITTI_SPEED_STEP_M_S, KITTI_STEP,
};
use sitar_evo::DriftSettings;
use sitar_evo::drift::{DriftOutcome as Outcome, compute_drift, drift_runs_json, lengths_text};

use crate::beyond_evo::shared_args::{AlignmentArgs, AlignmentWords, ReportArgs, ReportWords};
use crate::figures::canvas::Page;
use crate::figures::figure::{DistributionKind, Drawing, PALETTE, Series};
use crate::io::console::{Console, SEP, UsabilityArgs};
use crate::io::output::{OutputFormat, emit};
use crate::io::source::{self, format_subcommands};
use crate::results::metric_args::AxisArg;
use crate::results::runs::{across_table, csv_field, run_label, table};

/// Drift over path length, as the KITTI odometry benchmark measures it.
///
/// Segments of 100, 200, …, 800 m of the reference's path (--lengths), one starting every
/// 10 poses (--step), each ending at the first pose beyond its length; per segment the
/// translational error (%) and the rotational error (deg/m) of its relative pose, averaged per
/// length, per speed and over every segment (the devkit's evaluate_odometry.cpp; no
/// alignment unless -a/-s). tum, euroc and bag pair poses by stamps as `ape` does; kitti by
/// index. Several estimates are repeated runs of one system.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar drift kitti 00.txt results/00.txt\n  sitar drift tum ground_truth.txt run0.txt --lengths 1,2,3,4,5,6,7,8 --speed_step 0.2\n  sitar drift euroc data.csv estimate.tum -s --save_plot drift.pdf\n  sitar drift tum gt.txt run0.txt run1.txt run2.txt --lengths 1,2,4,8 --format json -o drift.json"
)]
pub struct Args {
    #[command(subcommand)]
    source: Format,
}

/// `sitar drift`'s options.
#[derive(clap::Args, Debug)]
pub struct Options {
    /// Segment lengths along the reference's path, metres, comma-separated [default: KITTI's
    /// 100,200,…,800; indoors e.g. 1,2,3,4,5,6,7,8].
    #[arg(long, value_delimiter = ',', value_name = "METRES")]
    lengths: Option<Vec<f64>>,
    /// A segment starts at every STEP-th (associated) pose.
    #[arg(long, default_value_t = KITTI_STEP, value_name = "STEP")]
    step: usize,
    /// Spacing of the speed bins (m/s): centres S, 2S, …, 12S, each taking the segments
    /// within ± S (the devkit's 2, 4, …, 24 m/s).
    #[arg(long = "speed_step", alias = "speed-step", default_value_t = KITTI_SPEED_STEP_M_S, value_name = "S")]
    speed_step: f64,
    #[command(flatten)]
    alignment: AlignmentArgs<DriftWords>,
    /// The gravity axis for --yaw_only: z or y (gravity along -y).
    #[arg(long = "yaw_axis", alias = "yaw-axis", value_enum, default_value_t = AxisArg::Z)]
    yaw_axis: AxisArg,
    #[command(flatten)]
    report: ReportArgs<DriftWords>,
    #[command(flatten)]
    usability: UsabilityArgs,
}

format_subcommands!(Format, Options);

/// `sitar drift`'s help for the options it shares with `sitar relative`.
#[derive(Debug)]
pub struct DriftWords;

impl AlignmentWords for DriftWords {
    const ALIGN: &'static str = "Alignment with Umeyama's method (no scale); a rigid alignment \
        leaves every segment's error as it is";
    const CORRECT_SCALE: &'static str =
        "Correct scale with Umeyama's method (alone: scale only; with -a: Sim(3))";
    const N_TO_ALIGN: &'static str =
        "The number of poses to use for Umeyama alignment, counted from the start (-1: all)";
    const YAW_ONLY: &'static str = "SiTAR extra, with -a: 4-DoF alignment (translation and yaw \
        about the gravity axis), as ape's --yaw_only. Cannot be combined with -s";
}

impl ReportWords for DriftWords {
    const PLOT: &'static str = "Show the plots (errors against length and against speed); \
        without a display sitar says so and shows nothing";
    const SAVE_PLOT: &'static str = "Path to save the plots: PNG, SVG or PDF by the extension \
        (FILE_length.png and FILE_speed.png, with several runs also FILE_t_err_box_plot.png and \
        FILE_r_err_box_plot.png; one PDF with every page)";
    const FORMAT: &'static str =
        "Print CSV (one row per segment; per run with several) or JSON instead of the tables";
    const HTML: &'static str = "SiTAR extra: also write one self-contained HTML page (tables, \
        both plots inline, the JSON document); it fetches nothing when opened";
}

pub fn run(args: Args) -> Result<()> {
    let (source, options) = args.source.split();
    let console = Console::new(&options.usability)?;
    let drift = DriftSettings {
        lengths: options
            .lengths
            .clone()
            .unwrap_or_else(|| KITTI_LENGTHS_M.to_vec()),
        step: options.step,
        speed_step: options.speed_step,
        align: options.alignment.align,
        correct_scale: options.alignment.correct_scale,
        n_to_align: options.alignment.n_to_align,
        yaw_only: options.alignment.yaw_only,
        yaw_axis: options.yaw_axis.axis(),
    };
    let settings = drift.options()?;
    let runs = source::load(&source, &console)?;
    let outcomes = runs
        .into_iter()
        .map(|loaded| compute_drift(loaded, &drift, settings.clone(), &console))
        .collect::<sitar_evo::Result<Vec<_>>>()?;
    let title = drift.title();
    match outcomes.as_slice() {
        [one] => finish_one(one, &title, &settings, &options, &console),
        several => finish_runs(several, &title, &settings, &options, &console),
    }
}

/// Lengths with too few segments for their average (the devkit's plots need 3), none
/// included.
fn left_out(d: &Drift, settings: &DriftOptions) -> Vec<f64> {
    settings
        .lengths_m
        .iter()
        .copied()
        .filter(|&l| !d.by_length.iter().any(|b| b.centre == l))
        .collect()
}

/// The per-length table and the overall line.
fn length_table(outcome: &Outcome, settings: &DriftOptions) -> String {
    let d = &outcome.drift;
    let row = |label: String, n: usize, t: f64, r: f64| {
        vec![label, n.to_string(), format!("{t:.6}"), format!("{r:.6}")]
    };
    let mut rows: Vec<Vec<String>> = d
        .by_length
        .iter()
        .map(|b| {
            row(
                b.centre.to_string(),
                b.segments,
                b.t_err_percent,
                b.r_err_deg_per_m,
            )
        })
        .collect();
    rows.push(row(
        "all".into(),
        d.segments.len(),
        d.t_err_percent,
        d.r_err_deg_per_m,
    ));
    let mut text = table(
        &["length (m)", "segments", "t_err (%)", "r_err (deg/m)"],
        &rows,
        0,
    );
    let missing = left_out(d, settings);
    if !missing.is_empty() {
        text += &format!(
            "(left out, fewer than {} segments, as in the devkit's plots: {})\n",
            settings.min_segments_per_bin,
            lengths_text(&missing)
        );
    }
    text
}

/// The segments as CSV.
fn segments_csv(outcome: &Outcome) -> String {
    let mut text = String::from("first,last,length_m,speed_m_s,t_err_percent,r_err_deg_per_m\n");
    for s in &outcome.drift.segments {
        text += &format!(
            "{},{},{},{},{},{}\n",
            s.first, s.last, s.length_m, s.speed_m_s, s.t_err_percent, s.r_err_deg_per_m
        );
    }
    text
}

/// The error-against-length and error-against-speed figures, one line per run.
fn curves(outcomes: &[Outcome], title: &str) -> (Drawing, Drawing) {
    let figure = |x_label: &str, bins: &dyn Fn(&Drift) -> &Vec<DriftBin>| {
        let series = |value: fn(&DriftBin) -> f64| -> Vec<Series> {
            outcomes
                .iter()
                .enumerate()
                .map(|(k, o)| Series {
                    name: run_label(&o.est_name),
                    points: bins(&o.drift)
                        .iter()
                        .map(|b| (b.centre, value(b)))
                        .collect(),
                    colour: PALETTE[k % PALETTE.len()],
                    dashed: false,
                    markers: true,
                })
                .collect()
        };
        Drawing::Panels {
            title: title.to_owned(),
            x_label: x_label.to_owned(),
            panels: vec![
                (
                    "translation error (%)".to_owned(),
                    series(|b| b.t_err_percent),
                ),
                (
                    "rotation error (deg/m)".to_owned(),
                    series(|b| b.r_err_deg_per_m),
                ),
            ],
            y_from_zero: true,
        }
    };
    (
        figure("path length (m)", &|d| &d.by_length),
        figure("speed (m/s)", &|d| &d.by_speed),
    )
}

fn finish_one(
    outcome: &Outcome,
    title: &str,
    settings: &DriftOptions,
    options: &Options,
    console: &Console,
) -> Result<()> {
    match options.report.format {
        Some(OutputFormat::Json) => emit(
            options.report.output.as_deref(),
            &(outcome.json(title, settings).to_string() + "\n"),
        )?,
        Some(OutputFormat::Csv) => emit(options.report.output.as_deref(), &segments_csv(outcome))?,
        None => {
            console.debug(SEP)?;
            console.info(&format!(
                "{title}\n{} against {}\n\n{}",
                outcome.est_name,
                outcome.ref_name,
                length_table(outcome, settings)
            ))?;
        }
    }
    let (length, speed) = curves(std::slice::from_ref(outcome), title);
    let pages = [
        ("length", Page::Other(&length)),
        ("speed", Page::Other(&speed)),
    ];
    crate::results::runs::plots(
        &pages,
        options.report.plot,
        options.report.save_plot.as_deref(),
        None,
        console,
    )?;
    html_page(options, &outcome.json(title, settings), &pages, console)
}

/// `--html FILE`, when given.
fn html_page(
    options: &Options,
    document: &Value,
    pages: &[(&str, Page<'_>)],
    console: &Console,
) -> Result<()> {
    let Some(path) = &options.report.html else {
        return Ok(());
    };
    crate::figures::html::write(path, document, pages)?;
    console.debug(&format!("Page saved to {}", path.display()))
}

fn finish_runs(
    outcomes: &[Outcome],
    title: &str,
    settings: &DriftOptions,
    options: &Options,
    console: &Console,
) -> Result<()> {
    const NAMES: [&str; 2] = ["t_err_percent", "r_err_deg_per_m"];
    let n = outcomes.len();
    let value = |k: usize, name: &str| match name {
        "t_err_percent" => outcomes[k].drift.t_err_percent,
        _ => outcomes[k].drift.r_err_deg_per_m,
    };
    match options.report.format {
        Some(OutputFormat::Json) => {
            let doc = drift_runs_json(outcomes, title, settings);
            emit(options.report.output.as_deref(), &(doc.to_string() + "\n"))?;
        }
        Some(OutputFormat::Csv) => {
            let mut text = format!("trial,estimate,segments,{}\n", NAMES.join(","));
            for (k, o) in outcomes.iter().enumerate() {
                text += &format!(
                    "{k},{},{},{},{}\n",
                    csv_field(&o.est_name),
                    o.drift.segments.len(),
                    o.drift.t_err_percent,
                    o.drift.r_err_deg_per_m
                );
            }
            for (i, summary) in crate::results::runs::ACROSS.iter().enumerate() {
                text += &format!("{summary},,");
                let cells: Vec<String> = NAMES
                    .iter()
                    .map(|name| {
                        let values: Vec<f64> = (0..n).map(|k| value(k, name)).collect();
                        crate::results::runs::across(&values)[i].to_string()
                    })
                    .collect();
                text += &format!(",{}\n", cells.join(","));
            }
            emit(options.report.output.as_deref(), &text)?;
        }
        None => {
            console.debug(SEP)?;
            let rows: Vec<Vec<String>> = outcomes
                .iter()
                .enumerate()
                .map(|(k, o)| {
                    vec![
                        k.to_string(),
                        o.est_name.clone(),
                        o.drift.segments.len().to_string(),
                        format!("{:.6}", o.drift.t_err_percent),
                        format!("{:.6}", o.drift.r_err_deg_per_m),
                    ]
                })
                .collect();
            console.info(&format!(
                "{title}\n{n} runs against {}\n\n{}\n{}",
                outcomes[0].ref_name,
                table(
                    &[
                        "trial",
                        "estimate",
                        "segments",
                        "t_err (%)",
                        "r_err (deg/m)"
                    ],
                    &rows,
                    2
                ),
                across_table(&NAMES, value, n)
            ))?;
        }
    }
    let (length, speed) = curves(outcomes, title);
    let boxes =
        |label: &str, value: fn(&sitar_estimator::DriftSegment) -> f64| Drawing::Distributions {
            title: format!("{title}\n{n} runs: every segment"),
            label: label.to_owned(),
            kind: DistributionKind::Box,
            groups: outcomes
                .iter()
                .map(|o| {
                    (
                        run_label(&o.est_name),
                        o.drift.segments.iter().map(value).collect(),
                    )
                })
                .collect(),
        };
    let t_box = boxes("translation error (%)", |s| s.t_err_percent);
    let r_box = boxes("rotation error (deg/m)", |s| s.r_err_deg_per_m);
    let pages = [
        ("length", Page::Other(&length)),
        ("speed", Page::Other(&speed)),
        ("t_err_box_plot", Page::Other(&t_box)),
        ("r_err_box_plot", Page::Other(&r_box)),
    ];
    crate::results::runs::plots(
        &pages,
        options.report.plot,
        options.report.save_plot.as_deref(),
        None,
        console,
    )?;
    html_page(
        options,
        &drift_runs_json(outcomes, title, settings),
        &pages,
        console,
    )
}
