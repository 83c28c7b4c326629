//! The output of `sitar ape` and `sitar rpe` after the metric: evo's table, SiTAR's CSV and
//! JSON extras, the result archive and the plots.

use anyhow::Result;
use sitar_estimator::PoseRelation;
use sitar_evo::document::outcome_json;
use sitar_evo::metric::{Metric, Outcome};

use crate::io::console::{Console, SEP};
use crate::io::output::{OutputFormat, emit};
use crate::results::archive::ResultArchive;
use crate::results::metric_args::OutputArgs;

/// Prints, saves and plots an outcome as the output options say.
pub fn finish(outcome: &Outcome, output: &OutputArgs, console: &Console) -> Result<()> {
    // SiTAR's single-file `--plot FILE` is written first: an unwritable file fails the
    // command before anything is printed. evo's plots follow the table, as in evo.
    crate::results::error_figures::single_file(outcome, output, console)?;
    match output.format {
        Some(format) => {
            let text = match format {
                OutputFormat::Csv => csv(outcome),
                OutputFormat::Json => outcome_json(outcome).to_string() + "\n",
            };
            emit(output.output.as_deref(), &text)?;
        }
        None => {
            console.debug(SEP)?;
            console.info(&outcome.pretty())?;
        }
    }
    crate::results::error_figures::collection(outcome, output, console)?;
    if let Some(path) = &output.html {
        let figure = crate::results::error_figures::error_figure(outcome, output)?;
        let pages = [
            ("raw", crate::figures::canvas::Page::Raw(&figure)),
            (
                "map",
                crate::figures::canvas::Page::Map(&figure, output.plot_mode),
            ),
        ];
        crate::figures::html::write(path, &outcome_json(outcome), &pages)?;
        console.debug(&format!("Page saved to {}", path.display()))?;
    }
    if let Some(path) = &output.save_results {
        console.debug(SEP)?;
        if path.exists() {
            console.warn(&format!("{} exists, overwriting", path.display()));
        }
        ResultArchive::of(outcome).write(path)?;
        console.debug(&format!("Saved results to {}", path.display()))?;
    }
    Ok(())
}

/// CSV rows: APE `t,error` per pose, RPE `start,end,error` per pair (reference stamps in
/// the reference's unit).
fn csv(outcome: &Outcome) -> String {
    let reference = &outcome.reference;
    let unit = reference.time_unit;
    let mut out = String::with_capacity(48 * (outcome.errors.errors.len() + 1));
    let ape = matches!(outcome.metric, Metric::Ape(_));
    out.push_str(if ape {
        "t,error\n"
    } else {
        "start,end,error\n"
    });
    for (&(i, j), e) in outcome.errors.pairs.iter().zip(&outcome.errors.errors) {
        if ape {
            out.push_str(&format!("{},{e}\n", unit.format_stamp(reference.stamps[i])));
        } else {
            out.push_str(&format!(
                "{},{},{e}\n",
                unit.format_stamp(reference.stamps[i]),
                unit.format_stamp(reference.stamps[j])
            ));
        }
    }
    out
}

/// A path's file name, for figure titles (the whole path if it has none).
pub fn file_name(path: &std::path::Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The unit of an error value as SiTAR's figures label it ("" when unit-less).
pub fn unit(relation: PoseRelation) -> &'static str {
    match relation.unit() {
        "unit-less" => "",
        u => u,
    }
}
