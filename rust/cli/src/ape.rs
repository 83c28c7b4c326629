//! `sitar ape`: absolute pose error, as evo_ape.

use anyhow::{Context, Result};
use sitar_estimator::ape;

use crate::compare::{PairArgs, error_figure, result_json};
use crate::output::{OutputFormat, emit};
use crate::plot::{self, PlotArgs};

/// Absolute pose error of EST against REF, as evo_ape.
///
/// Writes CSV `t,error` or JSON with the statistics; --plot also draws the errors as SVG.
/// Trials live in their own world frame: use --align (or --align-origin).
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  sitar ape ground_truth.txt trials/trajectory_0.txt --align --format json\n  sitar ape ground_truth.txt trials/trajectory_0.txt --align --plot ape.svg"
)]
pub struct Args {
    #[command(flatten)]
    pair: PairArgs,
    #[command(flatten)]
    plot: PlotArgs,
}

pub fn run(args: Args) -> Result<()> {
    let prepared = args.pair.prepare()?;
    let errors = ape(
        &prepared.reference,
        &prepared.estimate,
        args.pair.pose_relation,
    )
    .context("computing the APE")?;
    if let Some(path) = &args.plot.plot {
        let figure = error_figure("APE", &args.pair, &prepared, &errors);
        plot::write(path, args.plot.plot_mode, &figure)?;
    }
    let reference = &prepared.reference;
    let text = match args.pair.format {
        OutputFormat::Csv => {
            let mut out = String::with_capacity(32 * (errors.errors.len() + 1));
            out.push_str("t,error\n");
            for (&(i, _), e) in errors.pairs.iter().zip(&errors.errors) {
                out.push_str(&format!(
                    "{},{e}\n",
                    reference.time_unit.format_stamp(reference.stamps[i])
                ));
            }
            out
        }
        OutputFormat::Json => {
            result_json(
                "ape",
                &args.pair,
                &prepared,
                &errors,
                serde_json::Map::new(),
            ) + "\n"
        }
    };
    emit(args.pair.output.as_deref(), &text)
}
