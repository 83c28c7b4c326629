//! evo's alignment of the estimate onto the reference: Umeyama (`align`, `correct_scale`,
//! `n_to_align`), SiTAR's 4-DoF `yaw_only`, then `align_origin`.

use sitar_estimator::{Alignment, Similarity, Trajectory, align_first, umeyama};

use crate::error::{Context, Result, invalid};
use crate::messages::Messages;
use crate::options::AlgorithmOptions;
use crate::{SEP, pyfmt};

/// The alignment `align_estimate` will apply (before --align_origin) and --n_to_align.
pub(crate) fn alignment_kind(algorithm: &AlgorithmOptions) -> Result<(Alignment, Option<usize>)> {
    let n = match algorithm.n_to_align {
        -1 => None,
        n if n > 0 => Some(n as usize),
        n => invalid!("--n_to_align must be -1 (all poses) or a positive number of poses, got {n}"),
    };
    if algorithm.yaw_only && algorithm.correct_scale {
        invalid!(
            "--yaw_only aligns without scale (a translation and a yaw about the gravity axis): it cannot be combined with -s/--correct_scale"
        );
    }
    let kind = match (algorithm.align, algorithm.correct_scale) {
        (true, _) if algorithm.yaw_only => Alignment::PositionYaw {
            axis: algorithm.yaw_axis,
        },
        (true, true) => Alignment::Sim3,
        (true, false) => Alignment::Se3,
        (false, true) => Alignment::ScaleOnly,
        (false, false) => Alignment::None,
    };
    Ok((kind, n))
}

/// The alignment kind, the transform applied and evo's `alignment_transformation_sim3`.
pub type AlignmentOutcome = (Alignment, Option<Similarity>, Option<[[f64; 4]; 4]>);

/// evo's alignment: Umeyama (`-a`, `-s`, `--n_to_align`), then `--align_origin`. Returns the
/// kind, the transform applied and evo's `alignment_transformation_sim3`.
pub fn align_estimate(
    algorithm: &AlgorithmOptions,
    estimate: &mut Trajectory,
    reference: &Trajectory,
    messages: &dyn Messages,
) -> Result<AlignmentOutcome> {
    let n = match algorithm.n_to_align {
        -1 => None,
        n if n > 0 => Some(n as usize),
        n => invalid!("--n_to_align must be -1 (all poses) or a positive number of poses, got {n}"),
    };
    let mut result = (Alignment::None, None, None);
    if algorithm.yaw_only {
        if algorithm.correct_scale {
            invalid!(
                "--yaw_only aligns without scale (a translation and a yaw about the gravity axis): it cannot be combined with -s/--correct_scale"
            );
        }
        if !algorithm.align {
            invalid!("--yaw_only needs -a/--align");
        }
        let axis = algorithm.yaw_axis;
        messages.debug(SEP)?;
        messages.debug(&format!(
            "Aligning positions and yaw about the {} axis (4-DoF)...",
            axis.name()
        ))?;
        let kind = Alignment::PositionYaw { axis };
        let applied = align_first(estimate, reference, kind, n).context("aligning the estimate")?;
        return Ok((kind, Some(applied), Some(applied.to_matrix())));
    }
    if algorithm.align || algorithm.correct_scale {
        messages.debug(SEP)?;
        let kind = match (algorithm.align, algorithm.correct_scale) {
            (true, true) => Alignment::Sim3,
            (true, false) => Alignment::Se3,
            _ => Alignment::ScaleOnly,
        };
        messages.debug(if kind == Alignment::ScaleOnly {
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
        messages.debug(&format!("Scale correction: {}", pyfmt::repr(applied.scale)))?;
        result = (
            kind,
            Some(applied),
            Some(fitted.unwrap_or(applied).to_matrix()),
        );
    }
    if algorithm.align_origin {
        messages.debug(SEP)?;
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
    messages: &dyn Messages,
) -> Result<(Similarity, Similarity)> {
    messages.debug(match kind {
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
        messages.debug(&format!(
            "Rotation of alignment:\n{}\nTranslation of alignment:\n{}",
            pyfmt::numpy_matrix(&rows),
            pyfmt::numpy_vector(&fitted.translation.to_array())
        ))?;
    }
    messages.debug(&format!("Scale correction: {}", pyfmt::repr(fitted.scale)))?;
    Ok((applied, fitted))
}
