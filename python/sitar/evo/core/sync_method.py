"""evo.core.sync_method: how associate_trajectories pairs poses."""

from enum import Enum, unique


@unique
class SyncMethod(Enum):
    """Nearest stamp within max_diff, or interpolation of the denser trajectory at the
    matched stamps of the sparser one."""

    nearest_time = "nearest_time"
    interpolation = "interpolation"
