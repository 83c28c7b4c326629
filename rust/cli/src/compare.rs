//! The output of `sitar ape` and `sitar rpe` after the metric: evo's table, SiTAR's CSV and
//! JSON extras, the result archive and the plots.

use anyhow::Result;
use sitar_estimator::{Alignment, GravityAxis, PoseRelation, TimeUnit};

use crate::console::{Console, SEP};
use crate::metric::{Metric, Outcome, delta_text};
use crate::metric_args::OutputArgs;
use crate::output::{OutputFormat, emit, json_number};

/// Prints, saves and plots an outcome as the output options say.
pub fn finish(outcome: &Outcome, output: &OutputArgs, console: &Console) -> Result<()> {
    // SiTAR's single-file `--plot FILE` is written first: an unwritable file fails the
    // command before anything is printed. evo's plots follow the table, as in evo.
    crate::figures::single_file(outcome, output, console)?;
    match output.format {
        Some(format) => {
            let text = match format {
                OutputFormat::Csv => csv(outcome),
                OutputFormat::Json => json(outcome).to_string() + "\n",
            };
            emit(output.output.as_deref(), &text)?;
        }
        None => {
            console.debug(SEP)?;
            console.info(&outcome.pretty())?;
        }
    }
    crate::figures::collection(outcome, output, console)?;
    if let Some(path) = &output.html {
        let figure = crate::figures::error_figure(outcome, output)?;
        let pages = [
            ("raw", crate::canvas::Page::Raw(&figure)),
            ("map", crate::canvas::Page::Map(&figure, output.plot_mode)),
        ];
        crate::html::write(path, &json(outcome), &pages)?;
        console.debug(&format!("Page saved to {}", path.display()))?;
    }
    if let Some(path) = &output.save_results {
        console.debug(SEP)?;
        if path.exists() {
            console.warn(&format!("{} exists, overwriting", path.display()));
        }
        outcome.archive().write(path)?;
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

/// The JSON document: metric, relation, unit, alignment and transform, statistics, errors
/// (stamps integer ns), and for RPE the delta.
pub fn json(outcome: &Outcome) -> serde_json::Value {
    let reference = &outcome.reference;
    let ape = matches!(outcome.metric, Metric::Ape(_));
    let rows: Vec<serde_json::Value> = outcome
        .errors
        .pairs
        .iter()
        .zip(&outcome.errors.errors)
        .map(|(&(i, j), &e)| {
            if ape {
                serde_json::json!({ "t": reference.stamps[i], "error": json_number(e) })
            } else {
                serde_json::json!({
                    "start": reference.stamps[i],
                    "end": reference.stamps[j],
                    "error": json_number(e),
                })
            }
        })
        .collect();
    let stats: serde_json::Map<String, serde_json::Value> = outcome
        .stats_list()
        .iter()
        .map(|&(k, v)| (k.to_owned(), json_number(v)))
        .collect();
    let transform = outcome.transform.map(|t| {
        let r = t.rotation.transpose().to_cols_array_2d();
        serde_json::json!({
            "rotation": r,
            "translation": [t.translation.x, t.translation.y, t.translation.z],
            "scale": t.scale,
        })
    });
    let metric = match outcome.metric {
        Metric::Ape(_) => "ape",
        Metric::Rpe(_) => "rpe",
    };
    let relation = outcome.metric.relation();
    let mut doc = serde_json::json!({
        "version": 1,
        "metric": metric,
        "reference": outcome.ref_name,
        "estimate": outcome.est_name,
        "title": outcome.title,
        "pose_relation": relation.to_string(),
        "unit": outcome.unit,
        "alignment": alignment_name(outcome.alignment),
        "transform": transform,
        "time_unit": time_unit_name(reference.time_unit),
        "associated_poses": reference.len(),
        "statistics": stats,
        "errors": rows,
    });
    if let Some(object) = doc.as_object_mut() {
        let pairing = outcome.pairing.map_or_else(
            || serde_json::json!({ "paired": reference.len(), "by": "index" }),
            |p| p.json(),
        );
        object.insert("pairing".into(), pairing);
        if let Some(offset) = outcome.t_offset_estimated {
            object.insert("t_offset_estimated_s".into(), offset.into());
        }
        if let Metric::Ape(crate::metric::ApeRelation::Direction(_)) = outcome.metric {
            object.insert("yaw_axis".into(), outcome.gravity_axis.name().into());
        }
    }
    if let (Metric::Rpe(o), Some(object)) = (outcome.metric, doc.as_object_mut()) {
        object.insert("delta".into(), o.delta.into());
        object.insert("delta_text".into(), delta_text(&o).into());
        object.insert("delta_unit".into(), o.delta_unit.name().into());
        object.insert("all_pairs".into(), o.all_pairs.into());
    }
    doc
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

/// The alignment's name in the JSON documents.
pub fn alignment_name(a: Alignment) -> &'static str {
    match a {
        Alignment::None => "none",
        Alignment::Se3 => "se3",
        Alignment::Sim3 => "sim3",
        Alignment::ScaleOnly => "scale",
        Alignment::Origin => "origin",
        Alignment::PositionYaw {
            axis: GravityAxis::Z,
        } => "position_yaw_z",
        Alignment::PositionYaw {
            axis: GravityAxis::Y,
        } => "position_yaw_y",
    }
}

/// "ns" or "s".
pub fn time_unit_name(unit: TimeUnit) -> &'static str {
    match unit {
        TimeUnit::Nanoseconds => "ns",
        TimeUnit::Seconds | TimeUnit::RosStamp => "s",
    }
}
