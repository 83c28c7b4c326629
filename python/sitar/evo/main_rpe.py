"""evo.main_rpe's library function ``rpe``: align, compute and wrap the result."""

import copy
import logging
import typing

from sitar.evo import _main
from sitar.evo._missing import missing
from sitar.evo.core import metrics
from sitar.evo.core.result import Result
from sitar.evo.core.trajectory import Plane, PosePath3D

logger = logging.getLogger(__name__)


def rpe(traj_ref: PosePath3D, traj_est: PosePath3D, pose_relation: metrics.PoseRelation, *,
        delta: float, delta_unit: metrics.Unit, rel_delta_tol: float = 0.1,
        all_pairs: bool = False, pairs_from_reference: bool = False, align: bool = False,
        correct_scale: bool = False, n_to_align: int = -1, align_origin: bool = False,
        support_loop: bool = False, change_unit: typing.Optional[metrics.Unit] = None,
        project_to_plane: typing.Optional[Plane] = None) -> Result:
    """The RPE Result as evo's: ``traj_est`` aligned in place, both trajectories reduced to
    the pairs' second poses (and the first pose; on copies with ``support_loop``), the
    title, ``error_array``, stamps and distances of each value."""
    transformation = _main.prepare(traj_ref, traj_est, align, correct_scale, n_to_align,
                                   align_origin, project_to_plane)
    ref_name = traj_ref.name or "reference"
    est_name = traj_est.name or "estimate"
    metric = metrics.RPE(pose_relation, delta, delta_unit, rel_delta_tol, all_pairs,
                         pairs_from_reference)
    metric.process_data((traj_ref, traj_est))
    if change_unit:
        metric.change_unit(change_unit)
    result = metric.get_result(ref_name, est_name)
    result.info["title"] = _main.title(metric, align, correct_scale, n_to_align, align_origin,
                                       project_to_plane)
    logger.info(result.pretty_str())
    if support_loop:
        traj_ref, traj_est = copy.deepcopy(traj_ref), copy.deepcopy(traj_est)
    ids = [0] + metric.delta_ids
    traj_ref.reduce_to_ids(ids)
    traj_est.reduce_to_ids(ids)
    result.add_trajectory(ref_name, traj_ref)
    result.add_trajectory(est_name, traj_est)
    _main.add_times(result, traj_ref, traj_est, skip_first=True)
    if transformation is not None:
        result.add_np_array("alignment_transformation_sim3", transformation)
    return result


__getattr__ = missing(
    "evo.main_rpe",
    {name: "the sitar command: sitar rpe FORMAT REF EST ..." for name in ("run", "parser")},
)
