//! `sitar rpe`: relative pose error, as evo_rpe.

use anyhow::{Context, Result};
use clap::ValueEnum;
use sitar_estimator::{DeltaUnit, RpeOptions, rpe};

use crate::compare::{PairArgs, error_figure, result_json};
use crate::output::{OutputFormat, emit};
use crate::plot::{self, PlotArgs};

/// Relative pose error of EST against REF, as evo_rpe.
///
/// Writes CSV `start,end,error` (one row per pose pair, times in the input's unit) or JSON
/// with the statistics; --plot also draws each pair's error at its start as SVG.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar rpe ground_truth.txt trials/trajectory_0.txt --all-pairs --format json\n  sitar rpe ground_truth.txt trials/trajectory_0.txt --plot rpe.svg --plot-mode xz"
)]
pub struct Args {
    #[command(flatten)]
    pair: PairArgs,
    /// Delta between the poses of a pair, in --delta-unit.
    #[arg(short = 'd', long, default_value_t = 10.0)]
    delta: f64,
    /// Unit of --delta: f (frames) or m (metres of path).
    #[arg(short = 'u', long = "delta-unit", alias = "delta_unit", value_enum, default_value_t = Unit::F)]
    delta_unit: Unit,
    /// Use every start pose, not only consecutive, non-overlapping pairs.
    #[arg(long = "all-pairs", alias = "all_pairs")]
    all_pairs: bool,
    /// Relative tolerance of a metre delta.
    #[arg(long = "delta-tol", alias = "delta_tol", default_value_t = 0.1)]
    delta_tol: f64,
    /// Choose pose pairs on the reference instead of the estimate.
    #[arg(long = "pairs-from-reference", alias = "pairs_from_reference")]
    pairs_from_reference: bool,
    #[command(flatten)]
    plot: PlotArgs,
}

/// RPE delta unit, as evo's `-u f|m`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Unit {
    /// Frames.
    F,
    /// Metres of travelled path.
    M,
}

pub fn run(args: Args) -> Result<()> {
    let prepared = args.pair.prepare()?;
    let options = RpeOptions {
        pose_relation: args.pair.pose_relation,
        delta: args.delta,
        delta_unit: match args.delta_unit {
            Unit::F => DeltaUnit::Frames,
            Unit::M => DeltaUnit::Meters,
        },
        all_pairs: args.all_pairs,
        rel_delta_tol: args.delta_tol,
        pairs_from_reference: args.pairs_from_reference,
    };
    let errors =
        rpe(&prepared.reference, &prepared.estimate, &options).context("computing the RPE")?;
    if let Some(path) = &args.plot.plot {
        let figure = error_figure("RPE", &args.pair, &prepared, &errors);
        plot::write(path, args.plot.plot_mode, &figure)?;
    }
    let reference = &prepared.reference;
    let text = match args.pair.format {
        OutputFormat::Csv => {
            let mut out = String::with_capacity(48 * (errors.errors.len() + 1));
            out.push_str("start,end,error\n");
            for (&(i, j), e) in errors.pairs.iter().zip(&errors.errors) {
                let unit = reference.time_unit;
                out.push_str(&format!(
                    "{},{},{e}\n",
                    unit.format_stamp(reference.stamps[i]),
                    unit.format_stamp(reference.stamps[j])
                ));
            }
            out
        }
        OutputFormat::Json => {
            let mut extra = serde_json::Map::new();
            extra.insert("delta".into(), args.delta.into());
            extra.insert(
                "delta_unit".into(),
                match args.delta_unit {
                    Unit::F => "f",
                    Unit::M => "m",
                }
                .into(),
            );
            extra.insert("all_pairs".into(), args.all_pairs.into());
            result_json("rpe", &args.pair, &prepared, &errors, extra) + "\n"
        }
    };
    emit(args.pair.output.as_deref(), &text)
}
