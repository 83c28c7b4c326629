//! What `sitar ape` and `sitar rpe` share, in evo's order: read, filter, synchronise, align,
//! project, compute, title, print the table, save the result archive and the plots.

use anyhow::{Context, Result, bail};
use sitar_estimator::{
    Alignment, DeltaUnit, DirectionRelation, GravityAxis, PoseErrors, PoseRelation, RpeOptions,
    Similarity, Statistics, Trajectory, align_first, ape, ape_by_direction, delta_pairs,
    match_trajectories, rpe, seconds_to_ns, umeyama,
};

use crate::archive::{Array, ResultArchive};
use crate::console::{Console, SEP};
use crate::metric_args::AlgorithmArgs;
use crate::source::{Loaded, SyncArgs, SyncMethod};

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
    algorithm: &AlgorithmArgs,
    keep_full_reference: bool,
    console: &Console,
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
    downsample_or_filter(algorithm, &mut reference, &mut estimate, timed, console)?;
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
            eprintln!("estimated t_offset: {offset:.4} s");
            sync.t_offset = offset;
            t_offset_estimated = Some(offset);
        }
        let found;
        (reference, estimate, found) =
            synchronise(reference, estimate, &sync, (&ref_name, &est_name), console)?;
        if algorithm.show_pairing {
            eprintln!("{est_name}: {}", found.text());
        }
        pairing = Some(found);
    } else if algorithm.estimate_t_offset {
        bail!("--estimate_t_offset needs stamps (not the kitti format)");
    } else if reference.len() != estimate.len() {
        bail!(
            "trajectories must have same number of poses ({ref_name}: {}, {est_name}: {})",
            reference.len(),
            estimate.len()
        );
    }
    let relation = metric.relation();
    let (alignment, transform, alignment_matrix) =
        align_estimate(algorithm, &mut estimate, &reference, console)?;
    if let Some(plane) = algorithm.project_to_plane {
        console.debug(SEP)?;
        console.debug(&format!(
            "Projecting trajectories to {} plane.",
            plane.name()
        ))?;
        reference.project(plane.plane());
        estimate.project(plane.plane());
    }
    console.debug(SEP)?;
    let mut errors = match &metric {
        Metric::Ape(ApeRelation::Evo(r)) => {
            ape(&reference, &estimate, *r).context("computing the APE")?
        }
        Metric::Ape(ApeRelation::Direction(d)) => {
            ape_by_direction(&reference, &estimate, *d, algorithm.yaw_axis.axis())
                .context("computing the APE by direction")?
        }
        Metric::Rpe(options) => {
            if options.all_pairs
                && matches!(options.delta_unit, DeltaUnit::Degrees | DeltaUnit::Radians)
            {
                console.info(
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
            console.debug(&format!(
                "Found {} pairs with delta {} ({}) among {} poses using {} pairs.",
                all.len(),
                delta_text(options),
                options.delta_unit.name(),
                reference.len(),
                pairs_word(options)
            ))?;
            let errors = rpe(&reference, &estimate, options).context("computing the RPE")?;
            if errors.errors.len() < all.len() {
                console.warn(&format!(
                    "Ignoring {} zero divisions in ratio calculations.",
                    all.len() - errors.errors.len()
                ));
            }
            console.debug(&format!(
                "Compared {} relative pose pairs, delta = {} ({}) with {} pairs.",
                errors.errors.len(),
                delta_text(options),
                options.delta_unit.name(),
                pairs_word(options)
            ))?;
            errors
        }
    };
    console.debug(&format!(
        "Calculating {} for {} pose relation...",
        metric.name(),
        relation.description()
    ))?;
    let mut unit = relation.unit().to_owned();
    if let Some(change) = algorithm.change_unit {
        change
            .convert(&unit, &mut errors.errors)
            .map_err(|e| anyhow::anyhow!("--change_unit {}: {e}", change.name()))?;
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
        gravity_axis: algorithm.yaw_axis.axis(),
    })
}

/// The alignment `align_estimate` will apply (before --align_origin) and --n_to_align.
fn alignment_kind(algorithm: &AlgorithmArgs) -> Result<(Alignment, Option<usize>)> {
    let n = match algorithm.n_to_align {
        -1 => None,
        n if n > 0 => Some(n as usize),
        n => bail!("--n_to_align must be -1 (all poses) or a positive number of poses, got {n}"),
    };
    if algorithm.yaw_only && algorithm.correct_scale {
        bail!(
            "--yaw_only aligns without scale (a translation and a yaw about the gravity axis): it cannot be combined with -s/--correct_scale"
        );
    }
    let kind = match (algorithm.align, algorithm.correct_scale) {
        (true, _) if algorithm.yaw_only => Alignment::PositionYaw {
            axis: algorithm.yaw_axis.axis(),
        },
        (true, true) => Alignment::Sim3,
        (true, false) => Alignment::Se3,
        (false, true) => Alignment::ScaleOnly,
        (false, false) => Alignment::None,
    };
    Ok((kind, n))
}

/// evo's `--downsample` and `--motion_filter`, on both trajectories, before the sync.
fn downsample_or_filter(
    algorithm: &AlgorithmArgs,
    reference: &mut Trajectory,
    estimate: &mut Trajectory,
    timed: bool,
    console: &Console,
) -> Result<()> {
    if algorithm.downsample.is_none() && algorithm.motion_filter.is_none() {
        return Ok(());
    }
    console.debug(SEP)?;
    let before = (reference.len(), estimate.len());
    if let Some(n) = algorithm.downsample {
        console.debug(&format!("Downsampling trajectories to max {n} poses."))?;
        reference.downsample(n)?;
        estimate.downsample(n)?;
    }
    if let Some(filter) = &algorithm.motion_filter {
        if !timed {
            bail!(
                "trajectories without timestamps can't be motion filtered in metrics because it could break the required synchronization"
            );
        }
        let (distance, angle) = (filter[0], filter[1]);
        console.debug(&format!(
            "Filtering trajectories with motion filter thresholds: {distance:.6} m, {angle:.6} deg"
        ))?;
        reference.motion_filter(distance, angle)?;
        estimate.motion_filter(distance, angle)?;
    }
    console.debug(&format!(
        "Number of poses in reference was reduced from {} to {}.",
        before.0,
        reference.len()
    ))?;
    console.debug(&format!(
        "Number of poses in estimate was reduced from {} to {}.",
        before.1,
        estimate.len()
    ))?;
    Ok(())
}

/// evo's time range and synchronisation (`--t_start/--t_end` cut the reference; nearest
/// stamp or interpolation; `--t_offset` shifts the estimate for the association only).
pub fn synchronise(
    mut reference: Trajectory,
    estimate: Trajectory,
    sync: &SyncArgs,
    names: (&str, &str),
    console: &Console,
) -> Result<(Trajectory, Trajectory, Pairing)> {
    if !(sync.t_max_diff.is_finite() && sync.t_max_diff >= 0.0 && sync.t_offset.is_finite()) {
        bail!(
            "--t_max_diff must be a non-negative number of seconds and --t_offset finite (got {}, {})",
            sync.t_max_diff,
            sync.t_offset
        );
    }
    // evo: `if args.t_start or args.t_end` (0.0 counts as unset).
    let t_start = sync.t_start.filter(|&t| t != 0.0);
    let t_end = sync.t_end.filter(|&t| t != 0.0);
    if t_start.is_some() || t_end.is_some() {
        if let Some(t) = t_start {
            console.info(&format!(
                "Using time range start: {}s",
                crate::pyfmt::repr(t)
            ))?;
        }
        if let Some(t) = t_end {
            console.info(&format!("Using time range end: {}s", crate::pyfmt::repr(t)))?;
        }
        reference
            .reduce_to_time_range(t_start, t_end)
            .context("--t_start/--t_end")?;
        if reference.is_empty() {
            bail!("{}: no poses within --t_start/--t_end", names.0);
        }
    }
    let second_longer = estimate.len() > reference.len();
    let (short, long) = if second_longer {
        (&reference, &estimate)
    } else {
        (&estimate, &reference)
    };
    let offset_s = if second_longer {
        sync.t_offset
    } else {
        -sync.t_offset
    };
    if !long.is_sorted() {
        console.warn("Timestamps aren't sorted, using slower linear matching.");
    } else {
        console.debug("Timestamps are sorted, using binary search for matching.")?;
    }
    let (ids_short, ids_long) = match_trajectories(short, long, sync.t_max_diff, offset_s);
    if ids_short.is_empty() {
        bail!(
            "found no matching timestamps between {} and {} with max. time diff {} (s) and time offset {} (s)",
            names.0,
            names.1,
            crate::pyfmt::repr(sync.t_max_diff),
            crate::pyfmt::repr(sync.t_offset)
        );
    }
    let short_synced = short.reduce_to_ids(&ids_short);
    let long_synced = match sync.sync_method {
        SyncMethod::NearestTime => long.reduce_to_ids(&ids_long),
        SyncMethod::Interpolation => {
            let offset = seconds_to_ns(offset_s);
            let at: Vec<i64> = short_synced.stamps.iter().map(|&t| t - offset).collect();
            long.interpolate(&at)
                .context("--sync_method interpolation")?
        }
    };
    let max_pairs = short.len();
    console.debug(&format!(
        "Found {} of max. {max_pairs} possible matching timestamps between...\n\t{}\nand:\t{}\n..with max. time diff.: {} (s) and time offset: {} (s).",
        ids_short.len(),
        names.0,
        names.1,
        crate::pyfmt::repr(sync.t_max_diff),
        crate::pyfmt::repr(sync.t_offset)
    ))?;
    if ids_short.len() < max_pairs {
        console.warn(&format!(
            "associated {} of max. {max_pairs} possible poses of {} and {}: {} dropped (no stamp within {} s)",
            ids_short.len(),
            names.0,
            names.1,
            max_pairs - ids_short.len(),
            crate::pyfmt::repr(sync.t_max_diff)
        ));
    }
    let pairing = Pairing {
        reference_poses: reference.len(),
        estimate_poses: estimate.len(),
        paired: ids_short.len(),
        max_diff_s: sync.t_max_diff,
        t_offset_s: sync.t_offset,
    };
    Ok(if second_longer {
        (short_synced, long_synced, pairing)
    } else {
        (long_synced, short_synced, pairing)
    })
}

/// How the estimate's poses were paired with the reference's (SiTAR extra: `--show_pairing`
/// and the JSON's `"pairing"`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pairing {
    /// Reference poses offered (after --t_start/--t_end).
    pub reference_poses: usize,
    /// Estimate poses read (after --downsample/--motion_filter).
    pub estimate_poses: usize,
    /// Pairs made.
    pub paired: usize,
    /// --t_max_diff (s).
    pub max_diff_s: f64,
    /// The offset used (s).
    pub t_offset_s: f64,
}

impl Pairing {
    /// Estimate poses left without a partner.
    pub fn dropped(&self) -> usize {
        self.estimate_poses.saturating_sub(self.paired)
    }

    /// `paired 1347 of 1350 estimate poses; 3 without a reference pose within 0.01 s`.
    pub fn text(&self) -> String {
        let mut text = format!(
            "paired {} of {} estimate poses",
            self.paired, self.estimate_poses
        );
        if self.dropped() > 0 {
            text += &format!(
                "; {} without a reference pose within {} s",
                self.dropped(),
                crate::pyfmt::repr(self.max_diff_s)
            );
            if self.t_offset_s != 0.0 {
                text += &format!(" (t_offset {} s)", crate::pyfmt::repr(self.t_offset_s));
            }
        }
        text
    }

    /// The JSON object.
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "estimate_poses": self.estimate_poses,
            "reference_poses": self.reference_poses,
            "paired": self.paired,
            "estimate_dropped": self.dropped(),
            "reason": if self.dropped() > 0 {
                format!("no reference pose within {} s", crate::pyfmt::repr(self.max_diff_s))
            } else {
                String::new()
            },
            "t_max_diff_s": self.max_diff_s,
            "t_offset_s": self.t_offset_s,
        })
    }
}

/// The search of `--estimate_t_offset`: the offset (s, as --t_offset: added to the
/// estimate's stamps) in ±`range_s` minimising the translation APE RMSE after `kind`'s
/// alignment, associated as evo (`sync`'s method and --t_max_diff) at every offset. A grid
/// of steps of min(t_max_diff, range/50), then a grid 40 times finer around the best, whose
/// best values' interval gives its middle. Only offsets pairing at least 90 % of the most
/// pairs found count (few pairs fit too well).
pub fn estimate_t_offset(
    reference: &Trajectory,
    estimate: &Trajectory,
    sync: &SyncArgs,
    kind: Alignment,
    n: Option<usize>,
    range_s: f64,
) -> Result<f64> {
    if !(range_s.is_finite() && range_s > 0.0) {
        bail!("--t_offset_range must be a positive number of seconds, got {range_s}");
    }
    let mut reference = reference.clone();
    let t_start = sync.t_start.filter(|&t| t != 0.0);
    let t_end = sync.t_end.filter(|&t| t != 0.0);
    if t_start.is_some() || t_end.is_some() {
        reference
            .reduce_to_time_range(t_start, t_end)
            .context("--t_start/--t_end")?;
    }
    let kind = if kind == Alignment::None {
        Alignment::Se3
    } else {
        kind
    };
    let evaluate = |offset: f64| -> Option<(usize, f64)> {
        let (r, mut e) = pair_quiet(&reference, estimate, sync, offset)?;
        if r.len() < 3 {
            return None;
        }
        align_first(&mut e, &r, kind, n).ok()?;
        let errors = ape(&r, &e, PoseRelation::TranslationPart).ok()?;
        Some((r.len(), errors.statistics().rmse))
    };
    let scan = |from: f64, to: f64, step: f64| -> Vec<(f64, usize, f64)> {
        let count = ((to - from) / step).round() as i64;
        (0..=count)
            .filter_map(|k| {
                let offset = from + k as f64 * step;
                evaluate(offset).map(|(pairs, rmse)| (offset, pairs, rmse))
            })
            .collect()
    };
    let best = |found: &[(f64, usize, f64)], least: usize| {
        found
            .iter()
            .filter(|c| c.1 >= least && c.2.is_finite())
            .min_by(|a, b| a.2.total_cmp(&b.2))
            .copied()
    };
    let step = sync.t_max_diff.min(range_s / 50.0).max(range_s / 20_000.0);
    let coarse = scan(-range_s, range_s, step);
    let most = coarse.iter().map(|c| c.1).max().unwrap_or(0);
    let least = (most * 9).div_ceil(10);
    let Some((centre, _, _)) = best(&coarse, least) else {
        bail!(
            "--estimate_t_offset: no offset within ±{range_s} s pairs at least 3 poses (--t_max_diff {} s)",
            crate::pyfmt::repr(sync.t_max_diff)
        );
    };
    let fine = scan(
        (centre - step).max(-range_s),
        (centre + step).min(range_s),
        step / 40.0,
    );
    // Nearest-stamp association makes the RMSE a step function of the offset: the best
    // value holds on an interval (about one reference period wide); take its middle.
    let Some((_, _, low)) = best(&fine, least) else {
        return Ok(centre);
    };
    let on_plateau: Vec<f64> = fine
        .iter()
        .filter(|c| c.1 >= least && c.2 <= low * (1.0 + 1e-12))
        .map(|c| c.0)
        .collect();
    let (first, last) = (on_plateau[0], on_plateau[on_plateau.len() - 1]);
    Ok(0.5 * (first + last))
}

/// The association of `synchronise` without its messages, at `offset_s` (as --t_offset).
fn pair_quiet(
    reference: &Trajectory,
    estimate: &Trajectory,
    sync: &SyncArgs,
    offset_s: f64,
) -> Option<(Trajectory, Trajectory)> {
    let second_longer = estimate.len() > reference.len();
    let (short, long) = if second_longer {
        (reference, estimate)
    } else {
        (estimate, reference)
    };
    let offset = if second_longer { offset_s } else { -offset_s };
    let (ids_short, ids_long) = match_trajectories(short, long, sync.t_max_diff, offset);
    if ids_short.is_empty() {
        return None;
    }
    let short_synced = short.reduce_to_ids(&ids_short);
    let long_synced = match sync.sync_method {
        SyncMethod::NearestTime => long.reduce_to_ids(&ids_long),
        SyncMethod::Interpolation => {
            let shift = seconds_to_ns(offset);
            let at: Vec<i64> = short_synced.stamps.iter().map(|&t| t - shift).collect();
            long.interpolate(&at).ok()?
        }
    };
    Some(if second_longer {
        (short_synced, long_synced)
    } else {
        (long_synced, short_synced)
    })
}

/// The alignment kind, the transform applied and evo's `alignment_transformation_sim3`.
pub type AlignmentOutcome = (Alignment, Option<Similarity>, Option<[[f64; 4]; 4]>);

/// evo's alignment: Umeyama (`-a`, `-s`, `--n_to_align`), then `--align_origin`. Returns the
/// kind, the transform applied and evo's `alignment_transformation_sim3`.
pub fn align_estimate(
    algorithm: &AlgorithmArgs,
    estimate: &mut Trajectory,
    reference: &Trajectory,
    console: &Console,
) -> Result<AlignmentOutcome> {
    let n = match algorithm.n_to_align {
        -1 => None,
        n if n > 0 => Some(n as usize),
        n => bail!("--n_to_align must be -1 (all poses) or a positive number of poses, got {n}"),
    };
    let mut result = (Alignment::None, None, None);
    if algorithm.yaw_only {
        if algorithm.correct_scale {
            bail!(
                "--yaw_only aligns without scale (a translation and a yaw about the gravity axis): it cannot be combined with -s/--correct_scale"
            );
        }
        if !algorithm.align {
            bail!("--yaw_only needs -a/--align");
        }
        let axis = algorithm.yaw_axis.axis();
        console.debug(SEP)?;
        console.debug(&format!(
            "Aligning positions and yaw about the {} axis (4-DoF)...",
            axis.name()
        ))?;
        let kind = Alignment::PositionYaw { axis };
        let applied = align_first(estimate, reference, kind, n).context("aligning the estimate")?;
        return Ok((kind, Some(applied), Some(applied.to_matrix())));
    }
    if algorithm.align || algorithm.correct_scale {
        console.debug(SEP)?;
        let kind = match (algorithm.align, algorithm.correct_scale) {
            (true, true) => Alignment::Sim3,
            (true, false) => Alignment::Se3,
            _ => Alignment::ScaleOnly,
        };
        console.debug(if kind == Alignment::ScaleOnly {
            "Correcting scale..."
        } else if kind == Alignment::Sim3 {
            "Aligning using Umeyama's method... (with scale correction)"
        } else {
            "Aligning using Umeyama's method..."
        })?;
        // evo saves the whole Sim(3) fit even when it applies only the scale.
        let fitted = if kind == Alignment::ScaleOnly {
            let k = n.unwrap_or(usize::MAX).min(estimate.len());
            Some(umeyama(
                &estimate.positions[..k],
                &reference.positions[..k],
                true,
            )?)
        } else {
            None
        };
        let applied = align_first(estimate, reference, kind, n).context("aligning the estimate")?;
        console.debug(&format!(
            "Scale correction: {}",
            crate::pyfmt::repr(applied.scale)
        ))?;
        result = (
            kind,
            Some(applied),
            Some(fitted.unwrap_or(applied).to_matrix()),
        );
    }
    if algorithm.align_origin {
        console.debug(SEP)?;
        let applied = align_first(estimate, reference, Alignment::Origin, None)
            .context("aligning the origin")?;
        result = (Alignment::Origin, Some(applied), Some(applied.to_matrix()));
    }
    Ok(result)
}

/// Umeyama alignment with evo's debug lines (the fit, the scale); returns the transform
/// applied and the fit (they differ for scale only: evo saves the whole fit).
pub fn align_logged(
    estimate: &mut Trajectory,
    reference: &Trajectory,
    kind: Alignment,
    n: Option<usize>,
    console: &Console,
) -> Result<(Similarity, Similarity)> {
    console.debug(match kind {
        Alignment::ScaleOnly => "Correcting scale...",
        Alignment::Sim3 => "Aligning using Umeyama's method... (with scale correction)",
        _ => "Aligning using Umeyama's method...",
    })?;
    let k = n
        .unwrap_or(usize::MAX)
        .min(estimate.len())
        .min(reference.len());
    let fitted = umeyama(
        &estimate.positions[..k],
        &reference.positions[..k],
        kind != Alignment::Se3,
    )
    .context("aligning the estimate")?;
    let applied = align_first(estimate, reference, kind, n).context("aligning the estimate")?;
    if kind != Alignment::ScaleOnly {
        let r = fitted.rotation;
        let rows: Vec<Vec<f64>> = (0..3)
            .map(|i| (0..3).map(|j| r.col(j)[i]).collect())
            .collect();
        console.debug(&format!(
            "Rotation of alignment:\n{}\nTranslation of alignment:\n{}",
            crate::pyfmt::numpy_matrix(&rows),
            crate::pyfmt::numpy_vector(&fitted.translation.to_array())
        ))?;
    }
    console.debug(&format!(
        "Scale correction: {}",
        crate::pyfmt::repr(fitted.scale)
    ))?;
    Ok((applied, fitted))
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
        crate::pyfmt::repr(options.delta)
    }
}

/// evo's title: the metric line(s), then the alignment and projection notes.
fn title(metric: &Metric, unit: &str, algorithm: &AlgorithmArgs) -> String {
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
            algorithm.yaw_axis.axis().name()
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
        title += &format!("\n(projected to {} plane)", plane.name());
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
    fn result_ids(&self) -> Vec<usize> {
        match self.metric {
            Metric::Ape(_) => (0..self.reference.len()).collect(),
            Metric::Rpe(_) => std::iter::once(0)
                .chain(self.errors.pairs.iter().map(|&(_, j)| j))
                .collect(),
        }
    }

    /// The result as evo's archive: info, stats, the arrays evo writes.
    pub fn archive(&self) -> ResultArchive {
        let info = vec![
            ("title".to_owned(), self.title.clone()),
            ("ref_name".to_owned(), self.ref_name.clone()),
            ("est_name".to_owned(), self.est_name.clone()),
            ("label".to_owned(), self.label()),
        ];
        let stats = self
            .stats_list()
            .iter()
            .map(|&(k, v)| (k.to_owned(), v))
            .collect();
        let mut arrays = vec![(
            "error_array".to_owned(),
            Array::vector(self.errors.errors.clone()),
        )];
        if self.timed {
            let ids = self.result_ids();
            let (reference, estimate) = (
                self.reference.reduce_to_ids(&ids),
                self.estimate.reduce_to_ids(&ids),
            );
            // RPE drops the first pose again: it only anchors the distances.
            let skip = usize::from(matches!(self.metric, Metric::Rpe(_)));
            // Seconds as evo holds them (floats), differences taken in floats as evo does.
            let stamps = estimate.seconds();
            let from_start: Vec<f64> = stamps.iter().map(|&t| t - stamps[0]).collect();
            arrays.push((
                "seconds_from_start".into(),
                Array::vector(from_start[skip..].to_vec()),
            ));
            arrays.push(("timestamps".into(), Array::vector(stamps[skip..].to_vec())));
            arrays.push((
                "distances_from_start".into(),
                Array::vector(reference.distances()[skip..].to_vec()),
            ));
            arrays.push((
                "distances".into(),
                Array::vector(estimate.distances()[skip..].to_vec()),
            ));
        }
        if let Some(m) = self.alignment_matrix {
            arrays.push((
                "alignment_transformation_sim3".into(),
                Array::matrix(m.iter().flatten().copied().collect(), 4, 4),
            ));
        }
        ResultArchive {
            info,
            stats,
            arrays,
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
