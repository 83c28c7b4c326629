"""What ``main_ape.ape`` and ``main_rpe.rpe`` share: alignment, projection and the title."""

import logging
import typing

import numpy as np

from sitar.evo.core import lie_algebra
from sitar.evo.core.trajectory import Plane, PosePath3D, PoseTrajectory3D

logger = logging.getLogger(__name__)


def prepare(traj_ref: PosePath3D, traj_est: PosePath3D, align: bool, correct_scale: bool,
            n_to_align: int, align_origin: bool,
            project_to_plane: typing.Optional[Plane]) -> typing.Optional[np.ndarray]:
    """Aligns ``traj_est`` in place (Umeyama or origin) and projects both; returns the
    alignment's Sim(3) matrix (or the origin transform), None without one."""
    if align and align_origin:
        raise ValueError("align and align_origin can't be used simultaneously")
    only_scale = correct_scale and not align
    transformation = None
    if align or correct_scale:
        transformation = lie_algebra.sim3(
            *traj_est.align(traj_ref, correct_scale, only_scale, n=n_to_align)
        )
    if align_origin:
        transformation = traj_est.align_origin(traj_ref)
    if project_to_plane:
        traj_ref.project(project_to_plane)
        traj_est.project(project_to_plane)
    return transformation


def title(metric, align: bool, correct_scale: bool, n_to_align: int, align_origin: bool,
          project_to_plane: typing.Optional[Plane]) -> str:
    """evo's result title: the metric's, then how the estimate was aligned and projected."""
    text = str(metric)
    if align and not correct_scale:
        text += "\n(with SE(3) Umeyama alignment)"
    elif align and correct_scale:
        text += "\n(with Sim(3) Umeyama alignment)"
    elif correct_scale and not align:
        text += "\n(scale corrected)"
    elif not align_origin:
        text += "\n(not aligned)"
    if (align or correct_scale) and n_to_align != -1:
        text += f" (aligned poses: {n_to_align})"
    if align_origin:
        text += "\n(with origin alignment)"
    if project_to_plane:
        text += f"\n(projected to {project_to_plane.value} plane)"
    return text


def add_times(result, traj_ref: PosePath3D, traj_est: PosePath3D, skip_first: bool) -> None:
    """Seconds from the start, stamps and distances of each value (RPE: the first pose,
    kept for plots, has no value)."""
    if not isinstance(traj_est, PoseTrajectory3D):
        return
    cut = slice(1, None) if skip_first else slice(None)
    stamps = traj_est.timestamps
    result.add_np_array("seconds_from_start", (stamps - stamps[0])[cut])
    result.add_np_array("timestamps", stamps[cut])
    result.add_np_array("distances_from_start", traj_ref.distances[cut])
    result.add_np_array("distances", traj_est.distances[cut])
