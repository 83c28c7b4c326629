"""evo.core.result: the Result a metric's ``get_result`` returns."""

import numpy as np

from sitar.evo import EvoException
from sitar.evo._missing import missing


class ResultException(EvoException):
    pass


class Result:
    """``info`` (title, ref_name, est_name, label), ``stats``, ``np_arrays``
    (``error_array``, ...) and ``trajectories``, as evo's."""

    def __init__(self):
        self.info = {}
        self.stats = {}
        self.np_arrays = {}
        self.trajectories = {}

    def __str__(self) -> str:
        return self.pretty_str(stats=True)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Result):
            return False
        if (self.info, self.stats, self.trajectories) != (
            other.info,
            other.stats,
            other.trajectories,
        ):
            return False
        return all(
            k in other.np_arrays and np.array_equal(v, other.np_arrays[k])
            for k, v in self.np_arrays.items()
        )

    def __ne__(self, other: object) -> bool:
        return not self == other

    def pretty_str(self, title=True, stats=True, info=False) -> str:
        """The title, then the statistics sorted by name (``{name:>10}\\t{value:.6f}``)."""
        text = ""
        if title and "title" in self.info:
            text += f"{self.info['title']}\n\n"
        if stats:
            for name, value in sorted(self.stats.items()):
                text += f"{name:>10}\t{value:.6f}\n"
        if info:
            for name, value in sorted(self.info.items()):
                text += f"{name:>10}\t{value}\n"
        return text

    def add_np_array(self, name: str, array: np.ndarray) -> None:
        self.np_arrays[name] = array

    def add_info(self, info_dict: dict) -> None:
        self.info.update(info_dict)

    def add_stats(self, stats_dict: dict) -> None:
        self.stats.update(stats_dict)

    def add_trajectory(self, name: str, traj) -> None:
        self.trajectories[name] = traj


__getattr__ = missing(
    "evo.core.result",
    {"merge_results": "sitar ape|rpe with several estimates (repeated runs) or sitar res"},
)
