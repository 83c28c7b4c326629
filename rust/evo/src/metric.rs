//! What `ape` and `rpe` share, in evo's order: filter, synchronise, align, project,
//! compute, title; the [`Outcome`] holds everything evo prints, saves and plots.

use sitar_estimator::{
    Alignment, DeltaUnit, DirectionRelation, GravityAxis, PoseErrors, PoseRelation, RpeOptions,
    Similarity, Statistics, Trajectory, ape, ape_by_direction, delta_pairs, rpe,
};

use crate::align::{align_estimate, alignment_kind};
use crate::error::{Context, Error, Result, invalid};
use crate::messages::Messages;
use crate::options::{AlgorithmOptions, plane_name};
use crate::read::Loaded;
use crate::sync::{Pairing, estimate_t_offset, synchronise};
use crate::{SEP, pyfmt};

/// An APE pose relation: evo's, or one of SiTAR's direction relations (along_track, …).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ApeRelation {
    /// evo's pose relations.
    Evo(PoseRelation),
    /// SiTAR extra: the error split by direction (reference frame, gravity axis).
    Direction(DirectionRelation),
}

impl ApeRelation {
    /// The description in titles.
    pub fn description(self) -> &'static str {
        match self {
            ApeRelation::Evo(r) => r.description(),
            ApeRelation::Direction(d) => d.description(),
        }
    }

    /// The unit of the values.
    pub fn unit(self) -> &'static str {
        match self {
            ApeRelation::Evo(r) => r.unit(),
            ApeRelation::Direction(d) => d.unit(),
        }
    }
}

impl std::fmt::Display for ApeRelation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ApeRelation::Evo(r) => r.fmt(f),
            ApeRelation::Direction(d) => d.fmt(f),
        }
    }
}

impl From<PoseRelation> for ApeRelation {
    fn from(r: PoseRelation) -> Self {
        ApeRelation::Evo(r)
    }
}

/// APE, or RPE with its pair options.
#[derive(Debug, Clone, Copy)]
pub enum Metric {
    /// Absolute pose error.
    Ape(ApeRelation),
    /// Relative pose error.
    Rpe(RpeOptions),
}

impl Metric {
    /// The pose relation (RPE's are evo's).
    pub fn relation(&self) -> ApeRelation {
        match self {
            Metric::Ape(r) => *r,
            Metric::Rpe(o) => ApeRelation::Evo(o.pose_relation),
        }
    }

    /// "APE" or "RPE".
    pub fn name(&self) -> &'static str {
        match self {
            Metric::Ape(_) => "APE",
            Metric::Rpe(_) => "RPE",
        }
    }
}

/// A computed metric with everything evo prints, saves and plots.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// The metric.
    pub metric: Metric,
    /// evo's title (several lines).
    pub title: String,
    /// The unit of the values (`m`, `deg`, …, after `--change_unit`).
    pub unit: String,
    /// The errors.
    pub errors: PoseErrors,
    /// Their statistics.
    pub stats: Statistics,
    /// The synchronised, aligned (and projected) reference.
    pub reference: Trajectory,
    /// The synchronised, aligned (and projected) estimate.
    pub estimate: Trajectory,
    /// The reference as read (for `--plot_full_ref`).
    pub reference_full: Option<Trajectory>,
    /// Names as given (evo's `ref_name`, `est_name`).
    pub ref_name: String,
    /// The estimate's name.
    pub est_name: String,
    /// The alignment applied and its kind.
    pub alignment: Alignment,
    /// evo's `alignment_transformation_sim3`, when aligned.
    pub alignment_matrix: Option<[[f64; 4]; 4]>,
    /// The transform applied (for the JSON extra).
    pub transform: Option<Similarity>,
    /// Whether the inputs had stamps (not KITTI).
    pub timed: bool,
    /// How the poses were paired by stamps (None for KITTI: by index).
    pub pairing: Option<Pairing>,
    /// The offset found by --estimate_t_offset (s).
    pub t_offset_estimated: Option<f64>,
    /// The gravity axis of --yaw_axis.
    pub gravity_axis: GravityAxis,
}

/// Runs the metric on the loaded inputs.
pub fn compute(
    metric: Metric,
    loaded: Loaded,
    algorithm: &AlgorithmOptions,
    keep_full_reference: bool,
    messages: &dyn Messages,
) -> Result<Outcome> {
    let Loaded {
        reference,
        estimate,
        sync,
    } = loaded;
    let (ref_name, est_name) = (reference.name, estimate.name);
    let (mut reference, mut estimate) = (reference.trajectory, estimate.trajectory);
    let reference_full = keep_full_reference.then(|| reference.clone());
    let timed = sync.is_some();
    downsample_or_filter(algorithm, &mut reference, &mut estimate, timed, messages)?;
    let mut pairing = None;
    let mut t_offset_estimated = None;
    if let Some(sync) = &sync {
        let mut sync = sync.clone();
        if algorithm.estimate_t_offset {
            let (kind, n) = alignment_kind(algorithm)?;
            let offset = estimate_t_offset(
                &reference,
                &estimate,
                &sync,
                kind,
                n,
                algorithm.t_offset_range,
            )
            .with_context(|| format!("{est_name}: estimating the time offset"))?;
            messages.note(&format!("estimated t_offset: {offset:.4} s"));
            sync.t_offset = offset;
            t_offset_estimated = Some(offset);
        }
        let found;
        (reference, estimate, found) =
            synchronise(reference, estimate, &sync, (&ref_name, &est_name), messages)?;
        if algorithm.show_pairing {
            messages.note(&format!("{est_name}: {}", found.text()));
        }
        pairing = Some(found);
    } else if algorithm.estimate_t_offset {
        invalid!("--estimate_t_offset needs stamps (not the kitti format)");
    } else if reference.len() != estimate.len() {
        invalid!(
            "trajectories must have same number of poses ({ref_name}: {}, {est_name}: {})",
            reference.len(),
            estimate.len()
        );
    }
    let relation = metric.relation();
    let (alignment, transform, alignment_matrix) =
        align_estimate(algorithm, &mut estimate, &reference, messages)?;
    if let Some(plane) = algorithm.project_to_plane {
        messages.debug(SEP)?;
        messages.debug(&format!(
            "Projecting trajectories to {} plane.",
            plane_name(plane)
        ))?;
        reference.project(plane);
        estimate.project(plane);
    }
    messages.debug(SEP)?;
    let mut errors = match &metric {
        Metric::Ape(ApeRelation::Evo(r)) => {
            ape(&reference, &estimate, *r).context("computing the APE")?
        }
        Metric::Ape(ApeRelation::Direction(d)) => {
            ape_by_direction(&reference, &estimate, *d, algorithm.yaw_axis)
                .context("computing the APE by direction")?
        }
        Metric::Rpe(options) => {
            if options.all_pairs
                && matches!(options.delta_unit, DeltaUnit::Degrees | DeltaUnit::Radians)
            {
                messages.info(
                    "Searching all pairs with matching rotation delta, this can take a while.",
                )?;
            }
            let all = delta_pairs(
                if options.pairs_from_reference {
                    &reference
                } else {
                    &estimate
                },
                options,
            )?;
            messages.debug(&format!(
                "Found {} pairs with delta {} ({}) among {} poses using {} pairs.",
                all.len(),
                delta_text(options),
                options.delta_unit.name(),
                reference.len(),
                pairs_word(options)
            ))?;
            let errors = rpe(&reference, &estimate, options).context("computing the RPE")?;
            if errors.errors.len() < all.len() {
                messages.warn(&format!(
                    "Ignoring {} zero divisions in ratio calculations.",
                    all.len() - errors.errors.len()
                ));
            }
            messages.debug(&format!(
                "Compared {} relative pose pairs, delta = {} ({}) with {} pairs.",
                errors.errors.len(),
                delta_text(options),
                options.delta_unit.name(),
                pairs_word(options)
            ))?;
            errors
        }
    };
    messages.debug(&format!(
        "Calculating {} for {} pose relation...",
        metric.name(),
        relation.description()
    ))?;
    let mut unit = relation.unit().to_owned();
    if let Some(change) = algorithm.change_unit {
        change
            .convert(&unit, &mut errors.errors)
            .map_err(|e| Error::Invalid(format!("--change_unit {}: {e}", change.name())))?;
        unit = change.name().to_owned();
    }
    let title = title(&metric, &unit, algorithm);
    let stats = errors.statistics();
    Ok(Outcome {
        metric,
        title,
        unit,
        errors,
        stats,
        reference,
        estimate,
        reference_full,
        ref_name,
        est_name,
        alignment,
        alignment_matrix,
        transform,
        timed,
        pairing,
        t_offset_estimated,
        gravity_axis: algorithm.yaw_axis,
    })
}

/// evo's `--downsample` and `--motion_filter`, on both trajectories, before the sync.
fn downsample_or_filter(
    algorithm: &AlgorithmOptions,
    reference: &mut Trajectory,
    estimate: &mut Trajectory,
    timed: bool,
    messages: &dyn Messages,
) -> Result<()> {
    if algorithm.downsample.is_none() && algorithm.motion_filter.is_none() {
        return Ok(());
    }
    messages.debug(SEP)?;
    let before = (reference.len(), estimate.len());
    if let Some(n) = algorithm.downsample {
        messages.debug(&format!("Downsampling trajectories to max {n} poses."))?;
        reference.downsample(n)?;
        estimate.downsample(n)?;
    }
    if let Some(filter) = &algorithm.motion_filter {
        if !timed {
            invalid!(
                "trajectories without timestamps can't be motion filtered in metrics because it could break the required synchronization"
            );
        }
        let (distance, angle) = (filter[0], filter[1]);
        messages.debug(&format!(
            "Filtering trajectories with motion filter thresholds: {distance:.6} m, {angle:.6} deg"
        ))?;
        reference.motion_filter(distance, angle)?;
        estimate.motion_filter(distance, angle)?;
    }
    messages.debug(&format!(
        "Number of poses in reference was reduced from {} to {}.",
        before.0,
        reference.len()
    ))?;
    messages.debug(&format!(
        "Number of poses in estimate was reduced from {} to {}.",
        before.1,
        estimate.len()
    ))?;
    Ok(())
}

/// "all" or "consecutive", as evo names the pairing.
fn pairs_word(options: &RpeOptions) -> &'static str {
    if options.all_pairs {
        "all"
    } else {
        "consecutive"
    }
}

/// The delta as evo prints it: an integer for frames, Python's float repr otherwise.
pub fn delta_text(options: &RpeOptions) -> String {
    if options.delta_unit == DeltaUnit::Frames {
        format!("{}", options.delta as i64)
    } else {
        pyfmt::repr(options.delta)
    }
}

/// evo's title: the metric line(s), then the alignment and projection notes.
fn title(metric: &Metric, unit: &str, algorithm: &AlgorithmOptions) -> String {
    let relation = metric.relation().description();
    let mut title = match metric {
        Metric::Ape(_) => format!("APE w.r.t. {relation} ({unit})"),
        Metric::Rpe(options) => format!(
            "RPE w.r.t. {relation} ({unit})\nfor delta = {} ({}) using {} pairs",
            delta_text(options),
            options.delta_unit.name(),
            pairs_word(options)
        ),
    };
    let (align, scale) = (algorithm.align, algorithm.correct_scale);
    if algorithm.yaw_only {
        title += &format!(
            "\n(with 4-DoF position and yaw alignment about {})",
            algorithm.yaw_axis.name()
        );
    } else if align && !scale {
        title += "\n(with SE(3) Umeyama alignment)";
    } else if align && scale {
        title += "\n(with Sim(3) Umeyama alignment)";
    } else if scale {
        title += "\n(scale corrected)";
    } else if !algorithm.align_origin {
        title += "\n(not aligned)";
    }
    if (align || scale) && algorithm.n_to_align != -1 {
        title += &format!(" (aligned poses: {})", algorithm.n_to_align);
    }
    if algorithm.align_origin {
        title += "\n(with origin alignment)";
    }
    if let Some(plane) = algorithm.project_to_plane {
        title += &format!("\n(projected to {} plane)", plane_name(plane));
    }
    title
}

impl Outcome {
    /// evo's label of the values: `APE (m)`.
    pub fn label(&self) -> String {
        format!("{} ({})", self.metric.name(), self.unit)
    }

    /// evo's statistics in its order: rmse, mean, median, std, min, max, sse.
    pub fn stats_list(&self) -> [(&'static str, f64); 7] {
        let s = &self.stats;
        [
            ("rmse", s.rmse),
            ("mean", s.mean),
            ("median", s.median),
            ("std", s.std),
            ("min", s.min),
            ("max", s.max),
            ("sse", s.sse),
        ]
    }

    /// The statistic named `name` (NaN for an unknown name).
    pub fn stat(&self, name: &str) -> f64 {
        self.stats_list()
            .iter()
            .find(|(k, _)| *k == name)
            .map_or(f64::NAN, |(_, v)| *v)
    }

    /// evo's terminal output: the title, a blank line, then `{name:>10}\t{value:.6f}` per
    /// statistic sorted by name (max, mean, median, min, rmse, sse, std).
    pub fn pretty(&self) -> String {
        let mut stats = self.stats_list();
        stats.sort_by_key(|s| s.0);
        let mut text = format!("{}\n\n", self.title);
        for (name, value) in stats {
            text += &format!("{name:>10}\t{value:.6}\n");
        }
        text
    }

    /// The pose pairs' end indices with the first pose in front, as evo reduces the
    /// trajectories of an RPE result; every index for APE.
    pub fn result_ids(&self) -> Vec<usize> {
        match self.metric {
            Metric::Ape(_) => (0..self.reference.len()).collect(),
            Metric::Rpe(_) => std::iter::once(0)
                .chain(self.errors.pairs.iter().map(|&(_, j)| j))
                .collect(),
        }
    }

    /// The estimate's poses that carry the errors (APE: every pose; RPE: each pair's end
    /// pose), in error order, as evo colours them.
    pub fn error_positions(&self) -> Vec<[f64; 3]> {
        match self.metric {
            Metric::Ape(_) => self
                .estimate
                .positions
                .iter()
                .map(|p| p.to_array())
                .collect(),
            Metric::Rpe(_) => self
                .errors
                .pairs
                .iter()
                .map(|&(_, j)| self.estimate.positions[j].to_array())
                .collect(),
        }
    }
}
