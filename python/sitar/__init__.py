"""SiTAR's evo-compatible metrics in Python.

``sitar.evo`` is evo's Python API (file_interface, trajectory, sync, metrics, plot) on
the Rust library: change ``evo`` to ``sitar.evo`` in a script's imports.
``sitar.estimate(trajectories, ...)`` is SiTAR's estimate of repeated runs (numpy arrays).

``sitar.ape(fmt, ref, est, **options)``, ``sitar.rpe(...)`` and ``sitar.drift(...)`` take
evo's option names (``align=True``, ``correct_scale``, ``n_to_align``, ``pose_relation``,
``delta``, ``delta_unit``, ``all_pairs``, ``t_max_diff``, ``t_offset``, ...) and return the
dict that ``sitar ape|rpe|drift --format json`` prints. In it, the per-pose errors are numpy
arrays: ``"errors"`` (float64, the error of each row of the JSON's ``errors``; NaN where
the JSON has null); the keys are exactly the JSON's. With several estimates (a list: repeated runs) each of ``"trials"`` has
them. Warnings go to :mod:`warnings` as :class:`SitarWarning`; a bad file raises
:class:`SitarError` (a ValueError) or ``FileNotFoundError`` naming the file (and line);
an unknown option raises TypeError naming it.
"""

import json
import os
import warnings
from typing import Any, Dict, List, Sequence, Union

import numpy as np

from sitar._sitar import SitarError
from sitar import _sitar

__all__ = ["ape", "rpe", "drift", "estimate", "calibrate", "SitarError", "SitarWarning"]

PathLike = Union[str, "os.PathLike[str]"]

# evo's Python enums by member name, as the CLI spells them.
_EVO_RELATIONS = {
    "full_transformation": "full",
    "translation_part": "trans_part",
    "rotation_part": "rot_part",
    "rotation_angle_deg": "angle_deg",
    "rotation_angle_rad": "angle_rad",
    "point_distance": "point_distance",
    "point_distance_error_ratio": "point_distance_error_ratio",
}
_EVO_UNITS = {"frames": "f", "degrees": "d", "radians": "r", "meters": "m"}
_EVO_PLANES = {"XY": "xy", "XZ": "xz", "YZ": "yz"}


class SitarWarning(UserWarning):
    """A warning of the computation (dropped poses, repeated stamps, ...)."""


def _name(value: Any, table: Dict[str, str]) -> Any:
    """An evo enum member (``PoseRelation.translation_part``, ``Unit.meters``) as the CLI's
    name; strings and other values as given."""
    name = getattr(value, "name", None)
    if not isinstance(value, str) and isinstance(name, str):
        return table.get(name, name)
    return value


def _options(options: Dict[str, Any]) -> Dict[str, Any]:
    out = dict(options)
    if "pose_relation" in out:
        out["pose_relation"] = _name(out["pose_relation"], _EVO_RELATIONS)
    if "delta_unit" in out:
        out["delta_unit"] = _name(out["delta_unit"], _EVO_UNITS)
    if "project_to_plane" in out:
        out["project_to_plane"] = _name(out["project_to_plane"], _EVO_PLANES)
    if "change_unit" in out:
        unit = out["change_unit"]
        out["change_unit"] = getattr(unit, "value", unit)
    return out


def _estimates(est: Union[PathLike, Sequence[PathLike]]) -> List[str]:
    if isinstance(est, (str, os.PathLike)):
        return [os.fspath(est)]
    return [os.fspath(e) for e in est]


def _arrays(doc: Dict[str, Any]) -> Dict[str, Any]:
    """The JSON's per-pose ``errors`` rows as numpy arrays (in place; trials too)."""
    for trial in doc.get("trials", []):
        _arrays(trial)
    rows = doc.get("errors")
    if isinstance(rows, list):
        errors = [r["error"] for r in rows]
        doc["errors"] = np.array([np.nan if e is None else e for e in errors], dtype=np.float64)
    return doc


def _run(function: Any, fmt: str, ref: PathLike, est: Any, options: Dict[str, Any]) -> Dict[str, Any]:
    text, notes = function(fmt, os.fspath(ref), _estimates(est), _options(options))
    for note in notes:
        warnings.warn(note, SitarWarning, stacklevel=3)
    return _arrays(json.loads(text))


def ape(fmt: str, ref: PathLike, est: Any, **options: Any) -> Dict[str, Any]:
    """Absolute pose error, as ``sitar ape FMT REF EST --format json`` (and ``evo_ape``).

    ``fmt`` is ``"tum"``, ``"euroc"`` (EuRoC ground truth, TUM estimate) or ``"kitti"``;
    ``est`` a path or a list of paths (repeated runs). Options: evo's names and defaults
    (``pose_relation="trans_part"``, ``align``, ``correct_scale``, ``n_to_align=-1``,
    ``align_origin``, ``t_max_diff=0.01``, ``t_offset``, ...; SiTAR's ``yaw_only``,
    ``yaw_axis``, ``estimate_t_offset``).
    """
    return _run(_sitar.ape, fmt, ref, est, options)


def rpe(fmt: str, ref: PathLike, est: Any, **options: Any) -> Dict[str, Any]:
    """Relative pose error, as ``sitar rpe FMT REF EST --format json`` (and ``evo_rpe``):
    ``delta=1``, ``delta_unit="f"`` (f, d, r, m), ``delta_tol=0.1``, ``all_pairs``,
    ``pairs_from_reference``, and ``ape``'s alignment and sync options."""
    return _run(_sitar.rpe, fmt, ref, est, options)


def drift(fmt: str, ref: PathLike, est: Any, **options: Any) -> Dict[str, Any]:
    """KITTI drift over path length, as ``sitar drift FMT REF EST --format json``:
    ``lengths`` (m; KITTI's 100..800 by default), ``step=10``, ``speed_step=2``,
    ``align``, ``correct_scale``, ``n_to_align``, ``yaw_only``, ``yaw_axis`` and the sync
    options."""
    return _run(_sitar.drift, fmt, ref, est, options)


def _run_input(run: Any, index: int) -> Any:
    """A run as the extension takes it: a path, or (name, stamps, xyz, wxyz) as bytes."""
    if isinstance(run, (str, os.PathLike)):
        return os.fspath(run)
    stamps = getattr(run, "timestamps", None)
    if stamps is None or not hasattr(run, "positions_xyz"):
        raise TypeError(
            f"trajectories[{index}]: expected a path or a PoseTrajectory3D (with timestamps), "
            f"got {type(run).__name__}"
        )
    name = getattr(run, "name", None) or f"trajectories[{index}]"
    as_bytes = lambda a: np.ascontiguousarray(a, dtype=np.float64).tobytes()
    return (name, as_bytes(stamps), as_bytes(run.positions_xyz), as_bytes(run.orientations_quat_wxyz))


def estimate(
    trajectories: Sequence[Any],
    calibration: Union[PathLike, None] = None,
    setting: str = "trim_mean_30",
    delta: int = 10,
    t_max_diff: float = 0.01,
    pose_relation: str = "trans_part",
    thresholds: Sequence[float] = (0.05, 0.10),
) -> Dict[str, Any]:
    """SiTAR's estimate of repeated runs without ground truth, as ``sitar estimate``: for
    every pair of runs an all-pairs RPE over ``delta`` frames, and per window (keyed by the
    reference run's start stamp) the ``setting`` statistic of the pair values (``mean``,
    ``median``, ``trim_mean_10|20|30|40``, ``mean_inliers``).

    ``trajectories``: two or more runs, each a TUM path (integer stamps: nanoseconds) or a
    ``sitar.evo`` / evo ``PoseTrajectory3D`` (stamps in seconds). ``calibration``: a file
    from ``sitar calibrate``; then ``error`` is the calibrated error, ``raw`` the spread and
    ``[lower, upper]`` the interval. ``thresholds``: (medium, high) of ``class``.

    Returns numpy arrays, one entry per window: ``start`` and ``end`` (stamps, seconds),
    ``error``, ``raw``, ``lower``, ``upper`` (NaN without a calibration), ``spread``,
    ``pairs``, ``class`` ("low", "medium", "high"); and ``setting``, ``trials``,
    ``calibration`` (its path, or None).
    """
    runs = [_run_input(run, i) for i, run in enumerate(trajectories)]
    medium, high = (float(v) for v in thresholds)
    out = _sitar.estimate(
        runs,
        None if calibration is None else os.fspath(calibration),
        setting,
        int(delta),
        float(t_max_diff),
        _name(pose_relation, _EVO_RELATIONS),
        medium,
        high,
    )
    for key in ("start", "end", "error", "raw", "lower", "upper", "spread"):
        out[key] = np.array(out[key], dtype=np.float64)
    out["pairs"] = np.array(out["pairs"], dtype=np.int64)
    out["class"] = np.array(out["class"], dtype=str)
    return out


def calibrate(*args: Any, **kwargs: Any) -> Any:
    """Fitting a calibration needs runs with ground truth per sequence; it is the
    command ``sitar calibrate`` (not in the wheel's command, which has no analysis)."""
    raise NotImplementedError(
        "sitar.calibrate is not in the Python package yet: fit with the whole CLI, "
        "`sitar calibrate` (cargo build --release -p sitar-cli), then pass the file to "
        "sitar.estimate(..., calibration=PATH)"
    )
