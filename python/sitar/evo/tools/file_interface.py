"""evo.tools.file_interface: reading and writing TUM, KITTI and EuRoC files (parsed in
Rust), and trajectories from ROS bags.

Files are read by evo's rules: ``#`` lines skipped, fields split at each delimiter, every
field a float; values are kept as written (quaternions too; evo normalises them only when
it builds ``poses_se3``). Errors are FileInterfaceException with evo's message, prefixed by
the file, line and column of the first bad field. TUM and EuRoC poses are parsed when first
used, for the rows still kept then (``_rows.py``); their stamps and every row's shape are
checked on reading, as evo checks them.
"""

import io
import logging
import os
import typing
from pathlib import Path

import numpy as np

from sitar import _sitar
from sitar.evo import EvoException
from sitar.evo._missing import missing
from sitar.evo.tools._rows import FileRows
from sitar.evo.core.trajectory import PosePath3D, PoseTrajectory3D

logger = logging.getLogger(__name__)

PathStr = typing.Union[str, Path]
PathStrHandle = typing.Union[str, Path, typing.IO]


class FileInterfaceException(EvoException):
    pass


_TUM_RULE = (
    "TUM trajectory files must have 8 entries per row "
    "and no trailing delimiter at the end of the rows (space)"
)
_KITTI_RULE = (
    "KITTI pose files must have 12 entries per row "
    "and no trailing delimiter at the end of the rows (space)"
)
_EUROC_RULE = (
    "EuRoC format ground truth must have at least 8 entries per row "
    "and no trailing delimiter at the end of the rows (comma)"
)


def name_from_file(file_path: PathStrHandle) -> typing.Optional[str]:
    """The path as given, a handle's ``name``, or None."""
    if hasattr(file_path, "read"):
        name = getattr(file_path, "name", None)
        return name if isinstance(name, str) else None
    return str(file_path)


def _source(file_path: PathStrHandle, from_text, from_path):
    """``from_text(text, source)`` on a handle's content, or ``from_path(path)``; errors as
    FileInterfaceException."""
    if hasattr(file_path, "read"):
        text = file_path.read()
        if isinstance(text, bytes):
            text = text.decode("utf-8")
        call = lambda: from_text(text, name_from_file(file_path) or "<stream>")
    elif isinstance(file_path, (str, Path)):
        if not os.path.isfile(file_path):
            raise FileInterfaceException("csv file " + str(file_path) + " does not exist")
        call = lambda: from_path(os.fspath(file_path))
    else:
        raise FileInterfaceException(f"not a path or file handle: {file_path!r}")
    try:
        return call()
    except ValueError as error:
        raise FileInterfaceException(str(error)) from None


def _matrix(file_path: PathStrHandle, delimiter: str, columns: int, at_least: bool, rule: str):
    """Every field of a matrix file, parsed now: an n×columns float64 array."""
    data, rows, cols = _source(
        file_path,
        lambda text, source: _sitar.parse_matrix_text(
            text, source, delimiter, columns, at_least, rule
        ),
        lambda path: _sitar.read_matrix(path, delimiter, columns, at_least, rule),
    )
    return np.frombuffer(data, dtype=np.float64).reshape(rows, cols)


def _rows(file_path: PathStrHandle, delimiter: str, columns: int, at_least: bool, rule: str,
          xyz: typing.Sequence[int], quat: typing.Sequence[int]):
    """A matrix file's stamps (the first column, parsed now) and its poses as FileRows
    (parsed when first used)."""
    matrix, stamps = _source(
        file_path,
        lambda text, source: _sitar.matrix_rows_of_text(
            text, source, delimiter, columns, at_least, rule
        ),
        lambda path: _sitar.read_matrix_rows(path, delimiter, columns, at_least, rule),
    )
    rows = FileRows(matrix, xyz, quat, FileInterfaceException)
    return np.frombuffer(stamps, dtype=np.float64), rows


def read_tum_trajectory_file(file_path: PathStrHandle) -> PoseTrajectory3D:
    """A TUM file (``timestamp tx ty tz qx qy qz qw``) as a PoseTrajectory3D."""
    stamps, rows = _rows(file_path, " ", 8, False, _TUM_RULE, [1, 2, 3], [7, 4, 5, 6])
    return PoseTrajectory3D._from_rows(rows, name_from_file(file_path), timestamps=stamps)


def write_tum_trajectory_file(
    file_path: PathStrHandle, traj: PoseTrajectory3D, confirm_overwrite: bool = False
) -> None:
    """Writes ``traj`` as a TUM file (numpy's ``savetxt``, ``%.18e``, as evo).
    ``confirm_overwrite`` (evo asks on the terminal) is refused with NotImplementedError."""
    if confirm_overwrite:
        raise NotImplementedError(
            "evo's write_tum_trajectory_file(confirm_overwrite=True) asks on the terminal; "
            "sitar.evo does not ask: check the path yourself"
        )
    if not isinstance(traj, PoseTrajectory3D):
        raise FileInterfaceException("trajectory must be a PoseTrajectory3D object")
    quat = np.roll(traj.orientations_quat_wxyz, -1, axis=1)
    np.savetxt(file_path, np.column_stack((traj.timestamps, traj.positions_xyz, quat)), delimiter=" ")
    if isinstance(file_path, str):
        logger.info("Trajectory saved to: " + file_path)


def read_kitti_poses_file(file_path: PathStrHandle) -> PosePath3D:
    """A KITTI pose file (the first 3 rows of each 4×4 pose) as a PosePath3D."""
    mat = _matrix(file_path, " ", 12, False, _KITTI_RULE)
    poses = np.zeros((len(mat), 4, 4))
    poses[:, :3, :] = mat.reshape(-1, 3, 4)
    poses[:, 3, 3] = 1.0
    return PosePath3D(poses_se3=list(poses), name=name_from_file(file_path))


def write_kitti_poses_file(
    file_path: PathStrHandle, traj: PosePath3D, confirm_overwrite: bool = False
) -> None:
    """Writes ``traj``'s poses as a KITTI file (numpy's ``savetxt``, as evo)."""
    if confirm_overwrite:
        raise NotImplementedError(
            "evo's write_kitti_poses_file(confirm_overwrite=True) asks on the terminal; "
            "sitar.evo does not ask: check the path yourself"
        )
    poses = np.array(traj.poses_se3, dtype=np.float64).reshape(-1, 16)[:, :12]
    np.savetxt(file_path, poses, delimiter=" ")
    if isinstance(file_path, str):
        logger.info("Poses saved to: " + file_path)


def read_euroc_csv_trajectory(file_path: PathStrHandle) -> PoseTrajectory3D:
    """A EuRoC ground-truth CSV (``ns, px, py, pz, qw, qx, qy, qz, ...``) as a
    PoseTrajectory3D, stamps ``float(ns) / 1e9``."""
    stamps, rows = _rows(file_path, ",", 8, True, _EUROC_RULE, [1, 2, 3], [4, 5, 6, 7])
    stamps = np.divide(stamps, 1e9)
    return PoseTrajectory3D._from_rows(rows, name_from_file(file_path), timestamps=stamps)


def read_bag_trajectory(reader, topic: str, cache_tf_tree: bool = False,
                        cache_hash_source=None) -> PoseTrajectory3D:
    """A pose topic of a bag as a PoseTrajectory3D (header stamps, ``meta["frame_id"]``,
    ``name`` the topic), as evo's. ``reader``: an opened ``rosbags`` reader (rosbag1 or
    rosbag2; its ``path`` is read, in Rust) or a bag path: ROS 1 ``.bag``, ROS 2 ``.mcap``
    or a bag directory holding one. TF ids (``/tf:a.b``) and ``.db3`` bags raise
    NotImplementedError naming ``sitar traj bag|bag2``."""
    path = reader if isinstance(reader, (str, Path)) else getattr(reader, "path", None)
    if path is None:
        raise FileInterfaceException(
            "reader must be a rosbags.rosbag1 or rosbags.rosbag2 Reader, or a bag path"
        )
    if ":" in topic:
        raise NotImplementedError(
            f"evo's read_bag_trajectory of a TF id ({topic}) is not mirrored by sitar.evo; "
            "nearest sitar equivalent: `sitar traj bag|bag2 BAG '/tf:parent.child' --save_as_tum`"
        )
    if str(path).endswith(".db3"):
        raise NotImplementedError(
            "evo's read_bag_trajectory of a ROS 2 .db3 bag is not mirrored by sitar.evo (no "
            f"SQLite in the extension); nearest sitar equivalent: `sitar traj bag2 {path} "
            f"{topic} --save_as_tum`"
        )
    try:
        stamps, xyz, wxyz, frame_id = _sitar.read_bag_topic(os.fspath(path), topic)
    except ValueError as error:
        raise FileInterfaceException(str(error)) from None
    return PoseTrajectory3D(
        np.frombuffer(xyz, dtype=np.float64).reshape(-1, 3).copy(),
        np.frombuffer(wxyz, dtype=np.float64).reshape(-1, 4).copy(),
        np.frombuffer(stamps, dtype=np.float64).copy(),
        meta={"frame_id": frame_id},
        name=topic,
    )


__getattr__ = missing(
    "evo.tools.file_interface",
    {
        "save_res_file": "sitar ape|rpe --save_results FILE.zip (evo's archive)",
        "load_res_file": "sitar res FILE.zip",
        "write_bag_trajectory": "sitar traj ... --save_as_bag",
        "load_transform_json": "sitar ape|rpe --transform_left/--transform_right",
        "load_transform": "sitar ape|rpe --transform_left/--transform_right",
        "get_supported_topics": "sitar traj bag BAG --all_topics",
        "csv_read_matrix": "numpy.loadtxt",
    },
)
