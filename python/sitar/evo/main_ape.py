"""evo.main_ape's library function ``ape``: align, compute and wrap the result."""

import logging
import typing

from sitar.evo import _main
from sitar.evo._missing import missing
from sitar.evo.core import metrics
from sitar.evo.core.result import Result
from sitar.evo.core.trajectory import Plane, PosePath3D

logger = logging.getLogger(__name__)


def ape(traj_ref: PosePath3D, traj_est: PosePath3D, pose_relation: metrics.PoseRelation, *,
        align: bool = False, correct_scale: bool = False, n_to_align: int = -1,
        align_origin: bool = False, change_unit: typing.Optional[metrics.Unit] = None,
        project_to_plane: typing.Optional[Plane] = None) -> Result:
    """The APE Result as evo's: ``traj_est`` aligned in place, the title naming the
    alignment, the trajectories, ``error_array``, stamps and distances, and
    ``alignment_transformation_sim3`` when aligned."""
    transformation = _main.prepare(traj_ref, traj_est, align, correct_scale, n_to_align,
                                   align_origin, project_to_plane)
    ref_name = traj_ref.name or "reference"
    est_name = traj_est.name or "estimate"
    metric = metrics.APE(pose_relation)
    metric.process_data((traj_ref, traj_est))
    if change_unit:
        metric.change_unit(change_unit)
    result = metric.get_result(ref_name, est_name)
    result.info["title"] = _main.title(metric, align, correct_scale, n_to_align, align_origin,
                                       project_to_plane)
    logger.info(result.pretty_str())
    result.add_trajectory(ref_name, traj_ref)
    result.add_trajectory(est_name, traj_est)
    _main.add_times(result, traj_ref, traj_est, skip_first=False)
    if transformation is not None:
        result.add_np_array("alignment_transformation_sim3", transformation)
    return result


__getattr__ = missing(
    "evo.main_ape",
    {name: "the sitar command: sitar ape FORMAT REF EST ..." for name in ("run", "parser")},
)
