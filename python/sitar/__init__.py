"""SiTAR's evo-compatible metrics in Python.

``sitar.evo`` is evo's Python API (file_interface, trajectory, sync, metrics, plot) on
the Rust library: change ``evo`` to ``sitar.evo`` in a script's imports.
``sitar.estimate(trajectories, ...)`` is SiTAR's estimate of a run's error without ground
truth (numpy arrays); ``sitar.calibrate(sequences, ...)`` fits its calibration on runs with
ground truth.

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


def _run_input(run: Any, label: str) -> Any:
    """A run as the extension takes it: a path, or (name, stamps, xyz, wxyz) as bytes;
    ``label`` names it in errors (``trajectories[1]``)."""
    if isinstance(run, (str, os.PathLike)):
        return os.fspath(run)
    stamps = getattr(run, "timestamps", None)
    if stamps is None or not hasattr(run, "positions_xyz"):
        raise TypeError(
            f"{label}: expected a path or a PoseTrajectory3D (with timestamps), "
            f"got {type(run).__name__}"
        )
    name = getattr(run, "name", None) or label
    as_bytes = lambda a: np.ascontiguousarray(a, dtype=np.float64).tobytes()
    return (name, as_bytes(stamps), as_bytes(run.positions_xyz), as_bytes(run.orientations_quat_wxyz))


def _calibration_args(calibration: Any) -> Any:
    """(path, JSON text) of a calibration given as a path or as the dict sitar.calibrate returns."""
    if calibration is None:
        return None, None
    if isinstance(calibration, dict):
        return None, json.dumps(calibration)
    if isinstance(calibration, (str, os.PathLike)):
        return os.fspath(calibration), None
    raise TypeError(
        f"calibration: expected a path or the dict sitar.calibrate returns, got {type(calibration).__name__}"
    )


def _warn(notes: Sequence[str]) -> None:
    for note in notes:
        warnings.warn(note, SitarWarning, stacklevel=3)


def estimate(
    trajectories: Sequence[Any],
    calibration: Union[PathLike, Dict[str, Any], None] = None,
    setting: str = "trim_mean_30",
    delta: int = 10,
    t_max_diff: float = 0.01,
    pose_relation: str = "trans_part",
    thresholds: Sequence[float] = (0.05, 0.10),
    live: Any = None,
) -> Dict[str, Any]:
    """SiTAR's estimate of a run's pose error without ground truth, as ``sitar estimate``:
    for every pair of runs an all-pairs RPE over ``delta`` frames, and per window (keyed by
    the reference run's start stamp) the ``setting`` statistic of the pair values (``mean``,
    ``median``, ``trim_mean_10|20|30|40``, ``mean_inliers``).

    ``trajectories``: runs of one recording, each a TUM path (integer stamps above 10^11:
    nanoseconds) or a ``sitar.evo`` / evo ``PoseTrajectory3D`` (stamps in seconds).
    ``calibration``: a file from ``sitar calibrate`` or the dict ``sitar.calibrate``
    returns; then ``error`` is the calibrated error, ``raw`` the spread and ``[lower,
    upper]`` the interval. ``thresholds``: (medium, high) of ``class``.

    Which error: several runs give the error expected at each place (``target``
    "expected"); one run with a calibration gives that run's own error from its own motion
    (``target`` "live", ``runs`` 1); ``live=RUN`` gives the error of RUN with
    ``trajectories`` as its replays (``target`` "live" with a calibration; without one the
    spread between RUN and its replays). One run without a calibration raises ValueError:
    one run has no spread to measure.

    Returns numpy arrays, one entry per window: ``start`` and ``end`` (stamps, seconds),
    ``error``, ``raw``, ``lower``, ``upper`` (NaN without a calibration), ``spread``,
    ``pairs``, ``class`` ("low", "medium", "high"); and ``setting``, ``trials`` and
    ``runs`` (the runs used), ``calibration`` (its name, or None), ``target`` ("expected",
    "live", or None without a calibration) and ``informative`` (False: the calibration's
    runs did not predict this error, the values are a guess; None without a calibration).
    """
    if isinstance(trajectories, (str, os.PathLike)) or hasattr(trajectories, "positions_xyz"):
        trajectories = [trajectories]
    runs = [_run_input(run, f"trajectories[{i}]") for i, run in enumerate(trajectories)]
    live_run = None if live is None else _run_input(live, "live")
    medium, high = (float(v) for v in thresholds)
    path, text = _calibration_args(calibration)
    out = _sitar.estimate(
        runs,
        live_run,
        path,
        text,
        setting,
        int(delta),
        float(t_max_diff),
        _name(pose_relation, _EVO_RELATIONS),
        medium,
        high,
    )
    _warn(out.pop("warnings"))
    for key in ("start", "end", "error", "raw", "lower", "upper", "spread"):
        out[key] = np.array(out[key], dtype=np.float64)
    out["pairs"] = np.array(out["pairs"], dtype=np.int64)
    out["class"] = np.array(out["class"], dtype=str)
    return out


# The fewest runs a runs/ folder may hold (two for the truth, two for the estimate).
_MIN_RUNS = 4


def _digits_key(name: str) -> List[Any]:
    """The CLI's natural order of files: text and number runs (run2 before run10)."""
    key: List[Any] = []
    i = 0
    while i < len(name):
        j = i
        while j < len(name) and not name[j].isdigit():
            j += 1
        k = j
        while k < len(name) and name[k].isdigit():
            k += 1
        key.append((name[i:j], int(name[j:k]) if k > j else 0))
        i = k
    return key


def _trial_files(folder: str) -> List[str]:
    """The ``*.txt`` files of a folder in natural order, as the CLI lists them."""
    try:
        names = os.listdir(folder)
    except OSError as e:
        raise type(e)(e.errno, f"{folder}: cannot list ({e.strerror})") from None
    files = [os.path.join(folder, n) for n in names
             if n.endswith(".txt") and os.path.isfile(os.path.join(folder, n))]
    files.sort(key=lambda p: _digits_key(os.path.basename(p)))
    if not files:
        raise ValueError(f"{folder}: no trial files (*.txt)")
    return files


def _sequence_key(path: str) -> Any:
    """The CLI's order of sequences in a folder: name without its trailing digits, then them."""
    name = os.path.basename(path)
    stem = name.rstrip("0123456789")
    digits = name[len(stem):]
    return (stem, int(digits) if digits else 0)


def _folder_sequence(folder: str, split: Union[int, None]) -> Any:
    """One sequence folder (ground_truth.txt with runs/, or trials/ + trials-b/)."""
    name = os.path.basename(os.path.normpath(folder)) or folder
    gt = os.path.join(folder, "ground_truth.txt")
    runs = os.path.join(folder, "runs")
    if os.path.isdir(runs):
        files = _trial_files(runs)
        n = len(files)
        if n < _MIN_RUNS:
            raise ValueError(
                f"{runs}: {n} runs, at least {_MIN_RUNS} are needed (set A for the truth, "
                f"set B for the estimate, two each)"
            )
        k = (n + 1) // 2 if split is None else int(split)
        if k < 1 or k + 2 > n:
            raise ValueError(
                f"split={k}: set A needs at least 1 of the {n} runs of {runs} and set B at least 2"
            )
        return (name, f"{folder} (set A and B from {runs})", gt, files[:k], files[k:])
    dir_a, dir_b = os.path.join(folder, "trials"), os.path.join(folder, "trials-b")
    if not os.path.isdir(dir_a) or not os.path.isdir(dir_b):
        raise ValueError(f"{folder}: has ground_truth.txt but neither runs/ nor trials/ and trials-b/")
    if split is not None:
        raise ValueError(
            f"{folder}: split applies to a runs/ folder; this sequence has trials/ and trials-b/"
        )
    return (name, f"{folder} (set A from {dir_a}, set B from {dir_b})", gt,
            _trial_files(dir_a), _trial_files(dir_b))


def _sequences(given: Any, split: Union[int, None]) -> List[Any]:
    """The sequences as the extension takes them: (name, origin, gt, set A, set B)."""
    if isinstance(given, (str, os.PathLike)):
        given = [given]
    out = []
    for index, item in enumerate(given):
        if isinstance(item, (str, os.PathLike)):
            folder = os.fspath(item)
            if os.path.isfile(os.path.join(folder, "ground_truth.txt")):
                out.append(_folder_sequence(folder, split))
                continue
            if not os.path.isdir(folder):
                raise FileNotFoundError(f"{folder}: no such sequence folder")
            subdirs = [os.path.join(folder, n) for n in os.listdir(folder)
                       if os.path.isfile(os.path.join(folder, n, "ground_truth.txt"))]
            if not subdirs:
                raise ValueError(
                    f"{folder}: neither a sequence (no ground_truth.txt) nor a folder of sequences"
                )
            subdirs.sort(key=_sequence_key)
            out.extend(_folder_sequence(s, split) for s in subdirs)
            continue
        try:
            name, gt, set_a, set_b = item
        except (TypeError, ValueError):
            raise TypeError(
                f"sequences[{index}]: expected a sequence folder or (name, ground_truth, set_a, "
                f"set_b), got {type(item).__name__}"
            ) from None
        name = str(name)
        if isinstance(set_a, (str, os.PathLike)) or hasattr(set_a, "positions_xyz"):
            raise TypeError(f"sequences[{index}] ({name}): set_a must be a list of runs")
        if isinstance(set_b, (str, os.PathLike)) or hasattr(set_b, "positions_xyz"):
            raise TypeError(f"sequences[{index}] ({name}): set_b must be a list of runs")
        if len(set_a) < 1 or len(set_b) < 2:
            raise ValueError(
                f"sequences[{index}] ({name}): set A needs at least 1 run and set B at least 2 "
                f"(got {len(set_a)} and {len(set_b)})"
            )
        out.append((
            name,
            name,
            _run_input(gt, f"{name} ground_truth"),
            [_run_input(r, f"{name} set_a[{i}]") for i, r in enumerate(set_a)],
            [_run_input(r, f"{name} set_b[{i}]") for i, r in enumerate(set_b)],
        ))
    if not out:
        raise ValueError("sequences: a calibration needs at least one sequence with ground truth")
    return out


def calibrate(
    sequences: Any,
    output: Union[PathLike, None] = None,
    coverage: float = 0.8,
    setting: str = "trim_mean_30",
    delta: int = 10,
    pose_relation: str = "trans_part",
    split: Union[int, None] = None,
    t_max_diff: float = 0.01,
    spread_match: float = 0.45,
    smoothing: int = 3,
    thresholds: Sequence[float] = (0.05, 0.10),
) -> Dict[str, Any]:
    """Fits a calibration of the estimate on sequences with ground truth, as ``sitar
    calibrate SEQUENCE... -o OUTPUT`` (the same JSON for the same options).

    ``sequences``: each a folder with ``ground_truth.txt`` and ``runs/`` (natural order: the
    first ``split`` runs, half rounded up by default, are set A, the truth; the rest set B,
    the estimate) or ``trials/`` + ``trials-b/``; or a folder of such folders; or a tuple
    ``(name, ground_truth, set_a, set_b)`` of runs, each a TUM path or a ``PoseTrajectory3D``
    (stamps in seconds). Options by the CLI's names: ``coverage`` (share of windows the
    interval should hold), ``setting``, ``delta`` (frames), ``pose_relation`` (trans_part or
    angle_deg), ``t_max_diff``, ``spread_match``, ``smoothing`` (neighbouring windows on each
    side), ``thresholds`` (medium, high) of the scores.

    Returns the calibration as a dict (the file's JSON) and writes it to ``output`` when
    given; pass either to ``sitar.estimate(..., calibration=...)``. A model whose runs do not
    predict the error (``"informative": false``) is warned about as :class:`SitarWarning`.
    """
    given = _sequences(sequences, split)
    medium, high = (float(v) for v in thresholds)
    text, notes = _sitar.calibrate(
        given, setting, int(delta), float(t_max_diff), _name(pose_relation, _EVO_RELATIONS),
        float(coverage), float(spread_match), int(smoothing), medium, high,
    )
    _warn(notes)
    out = json.loads(text)
    for model in out.get("models", []):
        if model.get("informative") is False:
            warnings.warn(
                f"calibration: the {model.get('target')} error ({model.get('runs')} run(s)) "
                f"cannot be told from the runs (held-out Spearman's rho below 0.3): its values "
                f"are a guess",
                SitarWarning,
                stacklevel=2,
            )
    if output is not None:
        with open(os.fspath(output), "w") as f:
            f.write(text)
    return out
