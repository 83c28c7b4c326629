//! evo's time range and synchronisation, the pairing it made, and SiTAR's search of the
//! time offset (`estimate_t_offset`).

use sitar_estimator::{
    Alignment, PoseRelation, Trajectory, align_first, ape, match_trajectories, seconds_to_ns,
};

use crate::error::{Context, Result, invalid};
use crate::messages::Messages;
use crate::options::{SyncMethod, SyncOptions};
use crate::pyfmt;

/// evo's time range and synchronisation (`--t_start/--t_end` cut the reference; nearest
/// stamp or interpolation; `--t_offset` shifts the estimate for the association only).
pub fn synchronise(
    mut reference: Trajectory,
    estimate: Trajectory,
    sync: &SyncOptions,
    names: (&str, &str),
    messages: &dyn Messages,
) -> Result<(Trajectory, Trajectory, Pairing)> {
    if !(sync.t_max_diff.is_finite() && sync.t_max_diff >= 0.0 && sync.t_offset.is_finite()) {
        invalid!(
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
            messages.info(&format!("Using time range start: {}s", pyfmt::repr(t)))?;
        }
        if let Some(t) = t_end {
            messages.info(&format!("Using time range end: {}s", pyfmt::repr(t)))?;
        }
        reference
            .reduce_to_time_range(t_start, t_end)
            .context("--t_start/--t_end")?;
        if reference.is_empty() {
            invalid!("{}: no poses within --t_start/--t_end", names.0);
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
        messages.warn("Timestamps aren't sorted, using slower linear matching.");
    } else {
        messages.debug("Timestamps are sorted, using binary search for matching.")?;
    }
    let (ids_short, ids_long) = match_trajectories(short, long, sync.t_max_diff, offset_s);
    if ids_short.is_empty() {
        invalid!(
            "found no matching timestamps between {} and {} with max. time diff {} (s) and time offset {} (s)",
            names.0,
            names.1,
            pyfmt::repr(sync.t_max_diff),
            pyfmt::repr(sync.t_offset)
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
    messages.debug(&format!(
        "Found {} of max. {max_pairs} possible matching timestamps between...\n\t{}\nand:\t{}\n..with max. time diff.: {} (s) and time offset: {} (s).",
        ids_short.len(),
        names.0,
        names.1,
        pyfmt::repr(sync.t_max_diff),
        pyfmt::repr(sync.t_offset)
    ))?;
    if ids_short.len() < max_pairs {
        messages.warn(&format!(
            "associated {} of max. {max_pairs} possible poses of {} and {}: {} dropped (no stamp within {} s)",
            ids_short.len(),
            names.0,
            names.1,
            max_pairs - ids_short.len(),
            pyfmt::repr(sync.t_max_diff)
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
                pyfmt::repr(self.max_diff_s)
            );
            if self.t_offset_s != 0.0 {
                text += &format!(" (t_offset {} s)", pyfmt::repr(self.t_offset_s));
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
                format!("no reference pose within {} s", pyfmt::repr(self.max_diff_s))
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
    sync: &SyncOptions,
    kind: Alignment,
    n: Option<usize>,
    range_s: f64,
) -> Result<f64> {
    if !(range_s.is_finite() && range_s > 0.0) {
        invalid!("--t_offset_range must be a positive number of seconds, got {range_s}");
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
        invalid!(
            "--estimate_t_offset: no offset within ±{range_s} s pairs at least 3 poses (--t_max_diff {} s)",
            pyfmt::repr(sync.t_max_diff)
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
    sync: &SyncOptions,
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
