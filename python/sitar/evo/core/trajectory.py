"""evo.core.trajectory: PosePath3D and PoseTrajectory3D.

The poses are held as evo holds them: positions (n×3) and quaternions (n×4, w x y z) as
given or read, or SE(3) matrices once a transformation has been applied, each other form
derived on demand and cached. Conversions are vectorised over all poses (numpy), where evo
converts pose by pose; the values agree to rounding (1e-15).
"""

import copy
import logging
import typing
from enum import Enum, unique

import numpy as np

from sitar.evo import EvoException
from sitar.evo._missing import missing
from sitar.evo.core import _association, geometry
from sitar.evo.core import lie_algebra as lie
from sitar.evo.core.sync_method import SyncMethod

logger = logging.getLogger(__name__)


class TrajectoryException(EvoException):
    pass


class PoseCacheException(EvoException):
    pass


@unique
class Plane(Enum):
    """Planes for projections."""

    XY = "xy"
    XZ = "xz"
    YZ = "yz"


class PosePath3D:
    """Poses without time: ``positions_xyz``, ``orientations_quat_wxyz``, ``poses_se3``."""

    def __init__(
        self,
        positions_xyz: typing.Optional[np.ndarray] = None,
        orientations_quat_wxyz: typing.Optional[np.ndarray] = None,
        poses_se3: typing.Optional[typing.Sequence[np.ndarray]] = None,
        meta: typing.Optional[dict] = None,
        name: typing.Optional[str] = None,
    ):
        if (positions_xyz is None or orientations_quat_wxyz is None) and poses_se3 is None:
            raise PoseCacheException(
                "must provide at least positions_xyz & orientations_quat_wxyz, or poses_se3"
            )
        self._xyz = None if positions_xyz is None else np.array(positions_xyz)
        self._quat = None if orientations_quat_wxyz is None else np.array(orientations_quat_wxyz)
        self._poses = None if poses_se3 is None else list(poses_se3)
        self._derived = {}
        if self.num_poses == 0:
            raise TrajectoryException("pose data is empty")
        self.meta = {} if meta is None else meta
        self.name = name
        self._projected = False

    @classmethod
    def _from_rows(cls, rows, name: typing.Optional[str] = None, **attributes):
        """A path whose positions and quaternions are a file's rows, parsed when first
        used (see ``tools/_rows.py``); ``attributes`` set as given (``timestamps``)."""
        path = cls.__new__(cls)
        path.__dict__.update(
            _rows=rows, _poses=None, _derived={}, meta={}, name=name, _projected=False
        )
        path.__dict__.update(attributes)
        return path

    def __getattr__(self, name: str):
        # Only for attributes not set: the positions and quaternions of a path still held
        # as a file's rows, parsed now (both at once, for the rows kept).
        rows = self.__dict__.get("_rows") if name in ("_xyz", "_quat") else None
        if rows is None:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        xyz, quat = rows.values()
        # setdefault and pop: two threads may both have parsed (values() lets the GIL go).
        self.__dict__.setdefault("_xyz", xyz)
        self.__dict__.setdefault("_quat", quat)
        self.__dict__.pop("_rows", None)
        return self.__dict__[name]

    def __copy__(self):
        out = object.__new__(type(self))
        out.__dict__.update(self.__dict__)
        return out

    def __deepcopy__(self, memo: dict):
        out = object.__new__(type(self))
        memo[id(self)] = out
        for key, value in self.__dict__.items():
            # A file's rows are never changed (narrowing makes new ones): shared.
            out.__dict__[key] = value if key == "_rows" else copy.deepcopy(value, memo)
        return out

    def __getstate__(self) -> dict:
        # Pickled with its values: a file's rows are parsed first (into _xyz and _quat).
        if "_rows" in self.__dict__:
            self.__getattr__("_xyz")
        return self.__dict__

    # --- representations -----------------------------------------------------------------

    def _stacked(self) -> np.ndarray:
        """The poses as one n×4×4 array (from the matrices, or built from xyz and quat)."""
        if self._poses is not None:
            return np.array(self._poses, dtype=np.float64).reshape(-1, 4, 4)
        return lie.poses_from(self._xyz, self._quat)

    def _set_poses(self, stacked: np.ndarray) -> None:
        self.__dict__.pop("_rows", None)
        self._poses = list(stacked)
        self._xyz = None
        self._quat = None
        self._derived = {}

    @property
    def positions_xyz(self) -> np.ndarray:
        if self._xyz is None:
            self._xyz = self._stacked()[:, :3, 3].copy()
        return self._xyz

    @positions_xyz.setter
    def positions_xyz(self, value: np.ndarray) -> None:
        self._xyz = np.array(value)
        self._derived = {}

    @property
    def orientations_quat_wxyz(self) -> np.ndarray:
        if self._quat is None:
            self._quat = lie.quaternions_from_matrices(self._stacked())
        return self._quat

    @orientations_quat_wxyz.setter
    def orientations_quat_wxyz(self, value: np.ndarray) -> None:
        self._quat = np.array(value)
        self._derived = {}

    @property
    def poses_se3(self) -> typing.List[np.ndarray]:
        if self._poses is None:
            self._poses = list(self._stacked())
        return self._poses

    @property
    def num_poses(self) -> int:
        if self._poses is not None:
            return len(self._poses)
        xyz = self.__dict__.get("_xyz")
        if xyz is not None:
            return xyz.shape[0]
        rows = self.__dict__.get("_rows")
        return 0 if rows is None else len(rows)

    @property
    def distances(self) -> np.ndarray:
        if "distances" not in self._derived:
            self._derived["distances"] = geometry.accumulated_distances(self.positions_xyz)
        return self._derived["distances"]

    @property
    def path_length(self) -> float:
        """The length of the path through the positions (m)."""
        if "path_length" not in self._derived:
            self._derived["path_length"] = float(geometry.arc_len(self.positions_xyz))
        return self._derived["path_length"]

    def get_orientations_euler(self, axes: str = "sxyz") -> np.ndarray:
        """n×3 Euler angles; sitar.evo has evo's default axes ``sxyz`` only."""
        if axes != "sxyz":
            raise NotImplementedError(
                f"evo's get_orientations_euler(axes={axes!r}): sitar.evo has axes='sxyz' "
                "only; nearest sitar equivalent: scipy.spatial.transform.Rotation on poses_se3"
            )
        return lie.euler_sxyz(self._stacked())

    # --- comparison and text -------------------------------------------------------------

    def __str__(self) -> str:
        return f"{self.num_poses} poses, {self.path_length:.3f}m path length"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PosePath3D):
            return False
        if self.num_poses != other.num_poses:
            return False
        equal = all(
            np.allclose(a, b) for a, b in zip(self._stacked(), other._stacked())
        )
        q, r = self.orientations_quat_wxyz, other.orientations_quat_wxyz
        equal &= bool(np.allclose(q, r) or np.allclose(q, -r))
        equal &= bool(np.allclose(self.positions_xyz, other.positions_xyz))
        return equal

    def __ne__(self, other: object) -> bool:
        return not self == other

    # --- changes in place ----------------------------------------------------------------

    def transform(self, t: np.ndarray, right_mul: bool = False, propagate: bool = False) -> None:
        """Applies the 4×4 ``t`` to every pose: ``t·P`` (default), ``P·t`` (``right_mul``),
        or with ``propagate`` each relative motion ``P_i⁻¹·P_{i+1}`` right-multiplied by
        ``t`` and chained from the first pose."""
        t = np.asarray(t, dtype=np.float64)
        if not right_mul and self._poses is None and lie.is_se3(t):
            # A rigid transformation of positions and quaternions, without the n 4×4
            # matrices: q' = q_t·q (w ≥ 0, as evo's matrix-to-quaternion), p' = R_t·p + t.
            self._transform_rigid(t)
            return
        poses = self._stacked()
        if right_mul and not propagate:
            new = poses @ t
        elif right_mul and propagate:
            new = np.empty_like(poses)
            new[0] = poses[0]
            for i in range(len(poses) - 1):
                relative = lie.relative_se3(poses[i], poses[i + 1]).dot(t)
                new[i + 1] = new[i].dot(relative)
        else:
            new = np.asarray(t) @ poses
        self._set_poses(new)

    def _transform_rigid(self, t: np.ndarray) -> None:
        q_t = lie.quaternions_from_matrices(t[np.newaxis])[0]
        q = self.orientations_quat_wxyz.astype(np.float64)
        norms = np.linalg.norm(q, axis=1)
        q = q / np.where(norms > 0.0, norms, 1.0)[:, None]
        w0, x0, y0, z0 = q_t
        w, x, y, z = q.T
        product = np.stack(
            [
                w0 * w - x0 * x - y0 * y - z0 * z,
                w0 * x + x0 * w + y0 * z - z0 * y,
                w0 * y - x0 * z + y0 * w + z0 * x,
                w0 * z + x0 * y - y0 * x + z0 * w,
            ],
            axis=1,
        )
        product[product[:, 0] < 0.0] *= -1.0
        # Where w is ~0 the sign of q is rounding noise: take evo's route there (the matrix
        # t·P and its eigenvector), so that the quaternions equal evo's, sign included.
        unsure = np.abs(product[:, 0]) < 1e-6
        if np.any(unsure):
            poses = lie.poses_from(self.positions_xyz[unsure], q[unsure])
            product[unsure] = lie.quaternions_from_matrices(t @ poses)
        # einsum: no BLAS threads for an n×3 by 3×3 product (see geometry.umeyama_alignment).
        xyz = np.einsum("ij,kj->ik", self.positions_xyz, t[:3, :3]) + t[:3, 3]
        self._xyz, self._quat, self._poses = xyz, product, None
        self._derived = {}

    def scale(self, s: float) -> None:
        """Scales every translation by ``s``."""
        if self._poses is not None:
            stacked = self._stacked()
            stacked[:, :3, 3] *= s
            self._poses = list(stacked)
        if self._xyz is not None:
            self._xyz = s * self._xyz
        self._derived = {}

    def project(self, plane: Plane) -> None:
        """Projects the poses into ``plane``: the normal coordinate becomes 0 and each
        rotation the rotation about the normal by its Euler angle (sxyz) about that axis."""
        if self._projected:
            raise TrajectoryException("path was already projected once")
        if plane == Plane.XY:
            null_dim = 2
        elif plane == Plane.XZ:
            null_dim = 1
        elif plane == Plane.YZ:
            null_dim = 0
        else:
            raise TrajectoryException(f"unknown projection plane {plane}")
        poses = self._stacked()
        angles = lie.euler_sxyz(poses)[:, null_dim]
        vectors = np.zeros((len(poses), 3))
        vectors[:, null_dim] = angles
        poses[:, null_dim, 3] = 0
        from scipy.spatial.transform import Rotation

        poses[:, :3, :3] = Rotation.from_rotvec(vectors).as_matrix()
        self._set_poses(poses)
        self._projected = True

    def align(
        self,
        traj_ref: "PosePath3D",
        correct_scale: bool = False,
        correct_only_scale: bool = False,
        n: int = -1,
    ) -> geometry.UmeyamaResult:
        """Aligns this path to ``traj_ref`` in place (Umeyama on the positions, the first
        ``n`` or all) and returns ``(r, t, s)``, as evo's."""
        with_scale = correct_scale or correct_only_scale
        if n == -1:
            r_a, t_a, s = geometry.umeyama_alignment(
                self.positions_xyz.T, traj_ref.positions_xyz.T, with_scale
            )
        else:
            r_a, t_a, s = geometry.umeyama_alignment(
                self.positions_xyz[:n, :].T, traj_ref.positions_xyz[:n, :].T, with_scale
            )
        if correct_only_scale:
            self.scale(s)
        elif correct_scale:
            self.scale(s)
            self.transform(lie.se3(r_a, t_a))
        else:
            self.transform(lie.se3(r_a, t_a))
        return r_a, t_a, s

    def align_origin(self, traj_ref: "PosePath3D") -> np.ndarray:
        """Moves this path so that its first pose is ``traj_ref``'s; returns the transform."""
        if self.num_poses == 0 or traj_ref.num_poses == 0:
            raise TrajectoryException("can't align an empty trajectory...")
        to_ref_origin = np.dot(traj_ref.poses_se3[0], lie.se3_inverse(self.poses_se3[0]))
        self.transform(to_ref_origin)
        return to_ref_origin

    def reduce_to_ids(self, ids: typing.Union[typing.Sequence[int], np.ndarray]) -> None:
        """Keeps the poses at ``ids`` (indices or a boolean mask, as numpy indexing)."""
        held = self.__dict__
        if "_rows" in held:
            self._rows = self._rows.reduced(ids)
        if held.get("_xyz") is not None:
            self._xyz = self._xyz[ids]
        if held.get("_quat") is not None:
            self._quat = self._quat[ids]
        if self._poses is not None:
            self._poses = [self._poses[i] for i in ids]
        self._derived = {}

    def downsample(self, num_poses: int) -> None:
        """Keeps ``num_poses`` evenly spaced poses (numpy linspace, truncated)."""
        if self.num_poses <= num_poses:
            return
        if num_poses < 1:
            raise TrajectoryException("can't downsample to less than one pose")
        self.reduce_to_ids(np.linspace(0, self.num_poses - 1, num_poses, dtype=int))

    def _jumps(self, dist: float) -> np.ndarray:
        jumps = np.where(self.distances[1:] - self.distances[:-1] > dist)
        if len(jumps[0]) == 0:
            return np.array([0, self.num_poses])
        return np.concatenate([[0], jumps[0] + 1, [self.num_poses]])

    def split_distance_gaps(self, dist: float) -> typing.Sequence["PosePath3D"]:
        """The path cut where consecutive positions are more than ``dist`` apart."""
        if self.num_poses < 2:
            return [self]
        jumps = self._jumps(dist)
        return [
            PosePath3D(poses_se3=self.poses_se3[jumps[i] : jumps[i + 1]], name=self.name)
            for i in range(len(jumps) - 1)
        ]

    # --- information ---------------------------------------------------------------------

    def check(self) -> typing.Tuple[bool, dict]:
        """Whether the data is valid, with details, as evo's."""
        if self.num_poses == 0:
            return True, {}
        same_len = (
            self.positions_xyz.shape[0] == self.orientations_quat_wxyz.shape[0] == len(self.poses_se3)
        )
        se3_valid = all(lie.is_se3(p) for p in self.poses_se3)
        norms = np.linalg.norm(self.orientations_quat_wxyz, axis=1)
        quat_normed = bool(np.allclose(norms, np.ones(norms.shape)))
        details = {
            "array shapes": "ok" if same_len else "invalid (lists must have same length)",
            "SE(3) conform": "yes" if se3_valid else "no (poses are not valid SE(3) matrices)",
            "quaternions": "ok" if quat_normed else "invalid (must be unit quaternions)",
        }
        return same_len and se3_valid and quat_normed, details

    def get_infos(self) -> dict:
        return {
            "nr. of poses": self.num_poses,
            "path length (m)": self.path_length,
            "pos_start (m)": self.positions_xyz[0],
            "pos_end (m)": self.positions_xyz[-1],
        }

    def get_statistics(self) -> dict:
        return {}

    def motion_filter(self, distance_threshold: float, angle_threshold: float, degrees: bool = False):
        raise NotImplementedError(
            "evo's PosePath3D.motion_filter is not mirrored by sitar.evo; nearest sitar "
            "equivalent: sitar ape|rpe --motion_filter DISTANCE ANGLE_DEG"
        )


class PoseTrajectory3D(PosePath3D):
    """A PosePath3D with ``timestamps`` (seconds, float64)."""

    def __init__(
        self,
        positions_xyz: typing.Optional[np.ndarray] = None,
        orientations_quat_wxyz: typing.Optional[np.ndarray] = None,
        timestamps: typing.Optional[np.ndarray] = None,
        poses_se3: typing.Optional[typing.Sequence[np.ndarray]] = None,
        meta: typing.Optional[dict] = None,
        name: typing.Optional[str] = None,
    ):
        super().__init__(positions_xyz, orientations_quat_wxyz, poses_se3, meta, name)
        if timestamps is None:
            raise TrajectoryException("no timestamps provided")
        self.timestamps = np.array(timestamps)

    def __str__(self) -> str:
        s = super().__str__()
        return s + f", {self.timestamps[-1] - self.timestamps[0]:.3f}s duration"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PoseTrajectory3D):
            return False
        if self.num_poses != other.num_poses:
            return False
        return super().__eq__(other) and bool(np.allclose(self.timestamps, other.timestamps))

    def __ne__(self, other: object) -> bool:
        return not self == other

    @property
    def speeds(self) -> np.ndarray:
        """Speed between consecutive poses (m/s); non-increasing stamps are an error."""
        if "speeds" not in self._derived:
            if self.num_poses < 2:
                self._derived["speeds"] = np.array([])
            else:
                dt = self.timestamps[1:] - self.timestamps[:-1]
                bad = np.nonzero(dt <= 0)[0]
                if len(bad):
                    i = bad[0]
                    raise TrajectoryException(
                        f"bad timestamps: {self.timestamps[i]} & {self.timestamps[i + 1]}"
                    )
                steps = np.linalg.norm(self.positions_xyz[1:] - self.positions_xyz[:-1], axis=1)
                self._derived["speeds"] = steps / dt
        return self._derived["speeds"]

    def reduce_to_ids(self, ids: typing.Union[typing.Sequence[int], np.ndarray]) -> None:
        super().reduce_to_ids(ids)
        self.timestamps = self.timestamps[ids]

    def reduce_to_time_range(
        self,
        start_timestamp: typing.Optional[float] = None,
        end_timestamp: typing.Optional[float] = None,
    ) -> None:
        """Keeps the poses with ``start_timestamp <= t <= end_timestamp`` (None: this
        trajectory's own first or last stamp)."""
        if self.num_poses == 0:
            raise TrajectoryException("trajectory is empty")
        if start_timestamp is None:
            start_timestamp = self.timestamps[0]
        if end_timestamp is None:
            end_timestamp = self.timestamps[-1]
        if start_timestamp > end_timestamp:
            raise TrajectoryException(
                "start_timestamp is greater than end_timestamp "
                f"({start_timestamp} > {end_timestamp})"
            )
        ids = np.where(
            np.logical_and(self.timestamps >= start_timestamp, self.timestamps <= end_timestamp)
        )[0]
        self.reduce_to_ids(ids)

    def interpolate(self, timestamps: np.ndarray, extrapolate: bool = False) -> "PoseTrajectory3D":
        """Poses at ``timestamps``: positions linearly, orientations by slerp, between the
        two poses around each stamp (clamped to the ends unless ``extrapolate``)."""
        if self.num_poses < 2:
            raise TrajectoryException("can't interpolate a trajectory with less than two poses")
        timestamps = np.asarray(timestamps, dtype=float)
        if timestamps.ndim == 0:
            timestamps = timestamps.reshape(1)
        idx = np.clip(np.searchsorted(self.timestamps, timestamps, side="left"), 1, self.num_poses - 1)
        t_prev = self.timestamps[idx - 1]
        dt = self.timestamps[idx] - t_prev
        frac = np.where(dt > 0.0, (timestamps - t_prev) / np.where(dt > 0.0, dt, 1.0), 0.0)
        if not extrapolate:
            frac = np.clip(frac, 0.0, 1.0)
        xyz = self.positions_xyz[idx - 1] + frac[:, None] * (
            self.positions_xyz[idx] - self.positions_xyz[idx - 1]
        )
        quats = _slerp(self.orientations_quat_wxyz[idx - 1], self.orientations_quat_wxyz[idx], frac)
        return PoseTrajectory3D(xyz, quats, timestamps, meta=self.meta, name=self.name)

    def sync_with(
        self,
        other: "PoseTrajectory3D",
        *,
        sync_method: SyncMethod = SyncMethod.nearest_time,
        max_diff: float = 0.01,
        offset_2: float = 0.0,
    ) -> typing.Tuple["PoseTrajectory3D", "PoseTrajectory3D"]:
        """``sync.associate_trajectories(self, other, ...)``."""
        if not isinstance(other, PoseTrajectory3D):
            raise _association.SyncException("trajectories must be PoseTrajectory3D objects")
        return _association.associate(
            self, other, sync_method=sync_method, max_diff=max_diff, offset_2=offset_2
        )

    def _pieces(self, cuts: np.ndarray) -> typing.List["PoseTrajectory3D"]:
        return [
            PoseTrajectory3D(
                timestamps=self.timestamps[cuts[i] : cuts[i + 1]],
                poses_se3=self.poses_se3[cuts[i] : cuts[i + 1]],
                name=self.name,
            )
            for i in range(len(cuts) - 1)
        ]

    def split_time_gaps(self, dt: float) -> typing.Sequence["PoseTrajectory3D"]:
        """The trajectory cut where consecutive stamps are more than ``dt`` apart."""
        if self.num_poses < 2:
            return [self]
        gaps = np.where(self.timestamps[1:] - self.timestamps[:-1] > dt)[0]
        if len(gaps) == 0:
            return [self]
        return self._pieces(np.concatenate([[0], gaps + 1, [self.num_poses]]))

    def split_distance_gaps(self, dist: float) -> typing.Sequence["PoseTrajectory3D"]:
        if self.num_poses < 2:
            return [self]
        return self._pieces(self._jumps(dist))

    def split_speed_outliers(self, v_max: float) -> typing.Sequence["PoseTrajectory3D"]:
        """The trajectory cut after each step faster than ``v_max`` (m/s)."""
        if self.num_poses < 2:
            return [self]
        outliers = np.where(self.speeds > v_max)[0]
        if len(outliers) == 0:
            return [self]
        return self._pieces(np.concatenate([[0], outliers + 1, [self.num_poses]]))

    def check(self) -> typing.Tuple[bool, dict]:
        if self.num_poses == 0:
            return True, {}
        valid, details = super().check()
        len_stamps_valid = len(self.timestamps) == len(self.positions_xyz)
        valid &= len_stamps_valid
        details["nr. of stamps"] = "ok" if len_stamps_valid else "wrong"
        ascending = bool(np.all(np.sort(self.timestamps) == self.timestamps))
        ascending &= np.unique(self.timestamps).size == len(self.timestamps)
        valid &= ascending
        details["timestamps"] = "ok" if ascending else "wrong, not ascending or duplicates"
        return valid, details

    def get_infos(self) -> dict:
        infos = super().get_infos()
        infos["duration (s)"] = self.timestamps[-1] - self.timestamps[0]
        infos["t_start (s)"] = self.timestamps[0]
        infos["t_end (s)"] = self.timestamps[-1]
        return infos

    def get_statistics(self) -> dict:
        """Speeds (max, min, mean; m/s and km/h) and stamp steps (max, min, mean)."""
        if self.num_poses < 2:
            return {}
        stats = super().get_statistics()
        try:
            speeds = self.speeds
            vmax, vmin, vmean = speeds.max(), speeds.min(), speeds.mean()
            delta_ts = self.timestamps[1:] - self.timestamps[:-1]
            stats.update(
                {
                    "v_max (m/s)": vmax,
                    "v_min (m/s)": vmin,
                    "v_avg (m/s)": vmean,
                    "v_max (km/h)": vmax * 3.6,
                    "v_min (km/h)": vmin * 3.6,
                    "v_avg (km/h)": vmean * 3.6,
                    "dt_max (s)": delta_ts.max(),
                    "dt_min (s)": delta_ts.min(),
                    "dt_avg (s)": delta_ts.mean(),
                }
            )
        except TrajectoryException as error:
            logger.warning(f"Failed to compute all trajectory stats: {error}")
        return stats


class Trajectory(PoseTrajectory3D):
    """evo's old name of PoseTrajectory3D."""


def _slerp(q0: np.ndarray, q1: np.ndarray, fraction: np.ndarray) -> np.ndarray:
    """Spherical interpolation of unit quaternions row by row (the shorter arc)."""
    q0 = q0 / np.linalg.norm(q0, axis=1)[:, None]
    q1 = q1 / np.linalg.norm(q1, axis=1)[:, None]
    d = np.einsum("ij,ij->i", q0, q1)
    q1 = np.where((d < 0.0)[:, None], -q1, q1)
    d = np.abs(d)
    out = np.empty_like(q0)
    same = np.abs(np.abs(d) - 1.0) < np.finfo(float).eps * 4.0
    angle = np.arccos(np.clip(d, -1.0, 1.0))
    sin = np.sin(np.where(same, 1.0, angle))
    w0 = np.sin((1.0 - fraction) * angle) / sin
    w1 = np.sin(fraction * angle) / sin
    out[:] = w0[:, None] * q0 + w1[:, None] * q1
    out[same] = q0[same]
    out[fraction == 0.0] = q0[fraction == 0.0]
    out[fraction == 1.0] = q1[fraction == 1.0]
    return out


def calc_speed(xyz_1: np.ndarray, xyz_2: np.ndarray, t_1: float, t_2: float) -> float:
    """The speed (m/s) between two positions at two stamps."""
    if (t_2 - t_1) <= 0:
        raise TrajectoryException("bad timestamps: " + str(t_1) + " & " + str(t_2))
    return float(np.linalg.norm(xyz_2 - xyz_1) / (t_2 - t_1))


def merge(trajectories: typing.Sequence[PoseTrajectory3D]) -> PoseTrajectory3D:
    """One trajectory of all poses, sorted by stamp."""
    stamps = np.concatenate([t.timestamps for t in trajectories])
    xyz = np.concatenate([t.positions_xyz for t in trajectories])
    quat = np.concatenate([t.orientations_quat_wxyz for t in trajectories])
    order = stamps.argsort()
    return PoseTrajectory3D(xyz[order], quat[order], stamps[order])


def align_trajectory(
    traj: PosePath3D,
    traj_ref: PosePath3D,
    correct_scale: bool = False,
    correct_only_scale: bool = False,
    n: int = -1,
    return_parameters: bool = False,
    discard_n_start_poses: int = 0,
):
    """Older evo's function (evo < 1.19): an aligned copy of ``traj`` (``traj.align`` on a
    deep copy; with ``discard_n_start_poses`` the first poses are left out of the fit);
    with ``return_parameters`` also ``(r, t, s)``."""
    aligned = copy.deepcopy(traj)
    if discard_n_start_poses:
        fit, fit_ref = copy.deepcopy(traj), copy.deepcopy(traj_ref)
        ids = np.arange(discard_n_start_poses, traj.num_poses)
        fit.reduce_to_ids(ids)
        fit_ref.reduce_to_ids(ids)
        r, t, s = fit.align(fit_ref, correct_scale, correct_only_scale, n)
        if correct_only_scale or correct_scale:
            aligned.scale(s)
        if not correct_only_scale:
            aligned.transform(lie.se3(r, t))
    else:
        r, t, s = aligned.align(traj_ref, correct_scale, correct_only_scale, n)
    if return_parameters:
        return aligned, r, t, s
    return aligned


__getattr__ = missing(
    "evo.core.trajectory",
    {"xyz_quat_wxyz_to_se3_poses": "PosePath3D(positions_xyz, orientations_quat_wxyz).poses_se3",
     "se3_poses_to_xyz_quat_wxyz": "PosePath3D(poses_se3=...).positions_xyz / .orientations_quat_wxyz"},
)
