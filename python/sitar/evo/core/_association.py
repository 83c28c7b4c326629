"""Associating two trajectories by their stamps: the machinery under ``sync`` (evo's
module) and ``PoseTrajectory3D.sync_with``, kept below both so that they import it one way.
It works on any trajectory object; the public functions check their types."""

import copy
import logging
import typing

import numpy as np

from sitar.evo import EvoException
from sitar.evo.core.sync_method import SyncMethod

logger = logging.getLogger("sitar.evo.core.sync")


class SyncException(EvoException):
    pass


MatchingIndices = typing.Tuple[typing.List[int], typing.List[int]]


def matching_time_indices(
    stamps_1: np.ndarray,
    stamps_2: np.ndarray,
    max_diff: float = 0.01,
    offset_2: float = 0.0,
) -> MatchingIndices:
    """For each stamp of ``stamps_1`` the nearest of ``stamps_2 + offset_2`` within
    ``max_diff``: the two index lists of the matches. Sorted ``stamps_2``: the nearer
    neighbour, the earlier one on a tie; unsorted: the first nearest (with a warning)."""
    first, second = _matching(stamps_1, stamps_2, max_diff, offset_2)
    return first.tolist(), second.tolist()


def _matching(
    stamps_1: np.ndarray, stamps_2: np.ndarray, max_diff: float, offset_2: float
) -> typing.Tuple[np.ndarray, np.ndarray]:
    """``matching_time_indices`` as two int64 index arrays (no Python lists)."""
    stamps_1 = np.asarray(stamps_1, dtype=float)
    stamps_2 = np.asarray(stamps_2, dtype=float) + offset_2
    none = np.zeros(0, dtype=np.int64)
    if len(stamps_1) == 0 or len(stamps_2) == 0:
        return none, none
    if not np.all(np.diff(stamps_2) >= 0):
        logger.warning("Timestamps aren't sorted, using slower linear matching.")
        first, second = [], []
        for index_1, stamp_1 in enumerate(stamps_1):
            diffs = np.abs(stamps_2 - stamp_1)
            index_2 = int(np.argmin(diffs))
            if diffs[index_2] <= max_diff:
                first.append(index_1)
                second.append(index_2)
        return np.array(first, dtype=np.int64), np.array(second, dtype=np.int64)
    # Vectorised: the insertion point on the right, its upper and lower neighbours.
    inside = ~((stamps_1 < stamps_2[0] - max_diff) | (stamps_1 > stamps_2[-1] + max_diff))
    upper = np.minimum(np.searchsorted(stamps_2, stamps_1, side="right"), len(stamps_2) - 1)
    diff_ub = stamps_2[upper] - stamps_1
    diff_lb = np.where(upper > 0, stamps_1 - stamps_2[np.maximum(upper - 1, 0)], np.inf)
    take_upper = (diff_ub <= max_diff) & (diff_ub < diff_lb)
    take_lower = ~take_upper & (diff_lb <= max_diff) & (diff_lb <= diff_ub)
    keep = inside & (take_upper | take_lower)
    best = np.where(take_upper, upper, upper - 1)
    return np.nonzero(keep)[0], best[keep]


# The attributes of a PoseTrajectory3D built from positions and quaternions, or from a
# file's rows (as the readers make them, see tools/_rows.py): such a one is reduced without
# deep-copying the poses it drops.
_PLAIN = {"_poses", "_derived", "meta", "name", "_projected", "timestamps"}
_POSES = {"_xyz", "_quat", "_rows"}


def _plain(traj) -> bool:
    held = set(vars(traj))
    return (
        getattr(traj, "_poses", 0) is None
        and held - _POSES == _PLAIN
        and ("_rows" in held or {"_xyz", "_quat"} <= held)
    )


def _reduced_copy(traj, ids: np.ndarray):
    """``copy.deepcopy(traj)`` reduced to ``ids``: for a plain trajectory of arrays or
    rows, the kept rows copied by indexing (new arrays) and ``meta`` deep-copied; anything
    else as evo does it."""
    if _plain(traj):
        out = copy.copy(traj)
        out.meta = copy.deepcopy(traj.meta)
        out.reduce_to_ids(ids)
        return out
    out = copy.deepcopy(traj)
    out.reduce_to_ids(ids)
    return out


def associate(
    traj_1,
    traj_2,
    max_diff: float = 0.01,
    offset_2: float = 0.0,
    first_name: typing.Optional[str] = None,
    snd_name: typing.Optional[str] = None,
    *,
    sync_method: SyncMethod = SyncMethod.nearest_time,
):
    """Copies of both trajectories (``PoseTrajectory3D``, checked by the callers) reduced
    to their associated poses (the same number, at matching stamps); the inputs are not
    changed. The shorter one is matched against the longer. ``first_name``/``snd_name``
    (evo < 1.30) name them in the error; by default their ``name`` as evo 1.38."""
    first_name = first_name or (traj_1.name if traj_1.name else "first trajectory")
    second_name = snd_name or (traj_2.name if traj_2.name else "second trajectory")
    second_longer = traj_2.num_poses > traj_1.num_poses
    traj_short = traj_1 if second_longer else traj_2
    traj_long = traj_2 if second_longer else traj_1
    max_pairs = traj_short.num_poses
    matching_short, matching_long = _matching(
        traj_short.timestamps,
        traj_long.timestamps,
        max_diff,
        offset_2 if second_longer else -offset_2,
    )
    num_matches = len(matching_short)
    if num_matches == 0:
        raise SyncException(
            f"found no matching timestamps between {first_name} and {second_name} with max. "
            f"time diff {max_diff} (s) and time offset {offset_2} (s)"
        )
    traj_short = _reduced_copy(traj_short, matching_short)
    if sync_method is SyncMethod.interpolation:
        traj_long = traj_long.interpolate(
            traj_short.timestamps + (-offset_2 if second_longer else offset_2)
        )
    else:
        traj_long = _reduced_copy(traj_long, matching_long)
    logger.debug(
        f"Found {num_matches} of max. {max_pairs} possible matching timestamps between...\n"
        f"\t{first_name}\nand:\t{second_name}\n..with max. time diff.: {max_diff} (s) "
        f"and time offset: {offset_2} (s)."
    )
    if second_longer:
        return traj_short, traj_long
    return traj_long, traj_short
