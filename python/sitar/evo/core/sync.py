"""evo.core.sync: associating two trajectories by their stamps."""

import typing

from sitar.evo.core._association import (  # noqa: F401 (evo's names)
    MatchingIndices,
    SyncException,
    associate,
    matching_time_indices,
)
from sitar.evo.core.sync_method import SyncMethod
from sitar.evo.core.trajectory import PoseTrajectory3D

TrajectoryPair = typing.Tuple[PoseTrajectory3D, PoseTrajectory3D]


def associate_trajectories(
    traj_1: PoseTrajectory3D,
    traj_2: PoseTrajectory3D,
    max_diff: float = 0.01,
    offset_2: float = 0.0,
    first_name: typing.Optional[str] = None,
    snd_name: typing.Optional[str] = None,
    *,
    sync_method: SyncMethod = SyncMethod.nearest_time,
) -> TrajectoryPair:
    """Copies of both trajectories reduced to their associated poses (the same number, at
    matching stamps); the inputs are not changed. The shorter one is matched against the
    longer. ``first_name``/``snd_name`` (evo < 1.30) name them in the error; by default
    their ``name`` as evo 1.38."""
    if not isinstance(traj_1, PoseTrajectory3D) or not isinstance(traj_2, PoseTrajectory3D):
        raise SyncException("trajectories must be PoseTrajectory3D objects")
    return associate(
        traj_1, traj_2, max_diff, offset_2, first_name, snd_name, sync_method=sync_method
    )
