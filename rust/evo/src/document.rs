//! The JSON documents `sitar ape|rpe --format json` prints: one run's, and several runs'
//! with each statistic summarised over the runs.

use serde_json::{Map, Value, json};
use sitar_estimator::{Alignment, GravityAxis, Statistics, TimeUnit};

use crate::metric::{ApeRelation, Metric, Outcome, delta_text};

/// The document's version (bumped when a key changes meaning).
pub const VERSION: u32 = 1;

/// evo's statistics in the order `ape`/`rpe` print them.
pub const STATS: [&str; 7] = ["rmse", "mean", "median", "std", "min", "max", "sse"];

/// The names of the statistics over runs, in the order printed.
pub const ACROSS: [&str; 5] = ["mean", "median", "min", "max", "std"];

/// A finite number as JSON, NaN/inf as null.
pub fn json_number(v: f64) -> Value {
    serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)
}

/// One run's document: metric, relation, unit, alignment and transform, statistics, errors
/// (stamps integer ns), the pairing, and for RPE the delta.
pub fn outcome_json(outcome: &Outcome) -> Value {
    let reference = &outcome.reference;
    let ape = matches!(outcome.metric, Metric::Ape(_));
    let rows: Vec<Value> = outcome
        .errors
        .pairs
        .iter()
        .zip(&outcome.errors.errors)
        .map(|(&(i, j), &e)| {
            if ape {
                json!({ "t": reference.stamps[i], "error": json_number(e) })
            } else {
                json!({
                    "start": reference.stamps[i],
                    "end": reference.stamps[j],
                    "error": json_number(e),
                })
            }
        })
        .collect();
    let stats: Map<String, Value> = outcome
        .stats_list()
        .iter()
        .map(|&(k, v)| (k.to_owned(), json_number(v)))
        .collect();
    let transform = outcome.transform.map(|t| {
        let r = t.rotation.transpose().to_cols_array_2d();
        json!({
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
    let mut doc = json!({
        "version": VERSION,
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
            || json!({ "paired": reference.len(), "by": "index" }),
            |p| p.json(),
        );
        object.insert("pairing".into(), pairing);
        if let Some(offset) = outcome.t_offset_estimated {
            object.insert("t_offset_estimated_s".into(), offset.into());
        }
        if let Metric::Ape(ApeRelation::Direction(_)) = outcome.metric {
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

/// Several runs' document: each run's [`outcome_json`] under `trials`, and each statistic
/// over the runs under `across_trials`. `outcomes` must not be empty.
pub fn runs_json(outcomes: &[Outcome]) -> Value {
    let first = &outcomes[0];
    let n = outcomes.len();
    json!({
        "version": VERSION,
        "metric": first.metric.name().to_lowercase(),
        "reference": first.ref_name,
        "title": first.title,
        "unit": first.unit,
        "runs": n,
        "trials": outcomes.iter().map(outcome_json).collect::<Vec<_>>(),
        "across_trials": across_trials(&STATS, |k, name| outcomes[k].stat(name), n),
    })
}

/// A statistic's summary over runs: mean, median, min, max, std (population, as numpy's
/// `std` with ddof 0), in [`ACROSS`]'s order.
pub fn across(values: &[f64]) -> [f64; 5] {
    let s = Statistics::from_errors(values);
    [s.mean, s.median, s.min, s.max, s.std]
}

/// `{"mean": …, "median": …, "min": …, "max": …, "std": …}` of `values`.
pub fn across_json(values: &[f64]) -> Value {
    let summary = across(values);
    Value::Object(
        ACROSS
            .iter()
            .zip(summary)
            .map(|(k, v)| ((*k).to_owned(), json_number(v)))
            .collect(),
    )
}

/// `{statistic: across_json(its value in each run)}` for the named statistics.
pub fn across_trials(names: &[&str], value: impl Fn(usize, &str) -> f64, runs: usize) -> Value {
    let mut object = Map::new();
    for name in names {
        let values: Vec<f64> = (0..runs).map(|k| value(k, name)).collect();
        object.insert((*name).to_owned(), across_json(&values));
    }
    Value::Object(object)
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
