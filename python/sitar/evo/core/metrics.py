"""evo.core.metrics: APE and RPE, computed by SiTAR's Rust library (sitar-estimator).

``process_data`` sends the poses (positions and quaternions) to Rust once and gets the error
array back; RPE's pairs (by frames, metres or angle, consecutive or all pairs) are chosen
there too. Statistics are numpy's, as evo's. What differs from evo: ``E`` (the list of error
poses) is computed only when read (it is for plots and custom relations), and RPE's
``delta_ids`` come from the same pairs.
"""

import abc
import itertools
import logging
import math
import typing
from enum import Enum, unique

import numpy as np

from sitar import _sitar
from sitar.evo import EvoException
from sitar.evo.core import lie_algebra as lie
from sitar.evo.core import trajectory
from sitar.evo.core.result import Result
from sitar.evo.core.units import ANGLE_UNITS, LENGTH_UNITS, METER_SCALE_FACTORS, Unit

logger = logging.getLogger(__name__)

PathPair = typing.Tuple[trajectory.PosePath3D, trajectory.PosePath3D]


class MetricsException(EvoException):
    pass


class FilterException(EvoException):
    """evo.core.filters.FilterException: no pairs for an RPE delta."""


@unique
class StatisticsType(Enum):
    rmse = "rmse"
    mean = "mean"
    median = "median"
    std = "std"
    min = "min"
    max = "max"
    sse = "sse"


@unique
class PoseRelation(Enum):
    full_transformation = "full transformation"
    translation_part = "translation part"
    rotation_part = "rotation part"
    rotation_angle_rad = "rotation angle in radians"
    rotation_angle_deg = "rotation angle in degrees"
    point_distance = "point distance"
    point_distance_error_ratio = "point distance error ratio"


# The relation by the Rust library's (and the sitar command's) name.
_RELATION = {
    PoseRelation.full_transformation: "full",
    PoseRelation.translation_part: "trans_part",
    PoseRelation.rotation_part: "rot_part",
    PoseRelation.rotation_angle_rad: "angle_rad",
    PoseRelation.rotation_angle_deg: "angle_deg",
    PoseRelation.point_distance: "point_distance",
    PoseRelation.point_distance_error_ratio: "point_distance_error_ratio",
}
_DELTA_UNIT = {Unit.frames: "f", Unit.meters: "m", Unit.degrees: "d", Unit.radians: "r"}


def _arrays(traj: trajectory.PosePath3D) -> typing.Tuple[bytes, bytes]:
    xyz = np.ascontiguousarray(traj.positions_xyz, dtype=np.float64)
    wxyz = np.ascontiguousarray(traj.orientations_quat_wxyz, dtype=np.float64)
    if xyz.ndim != 2 or xyz.shape[1] != 3 or wxyz.ndim != 2 or wxyz.shape[1] != 4:
        raise MetricsException(
            f"poses must be n×3 positions and n×4 quaternions, got {xyz.shape} and {wxyz.shape}"
        )
    return xyz.tobytes(), wxyz.tobytes()


def _pair(data) -> PathPair:
    if len(data) != 2:
        raise MetricsException("please provide data tuple as: (traj_ref, traj_est)")
    traj_ref, traj_est = data
    if traj_ref.num_poses != traj_est.num_poses:
        raise MetricsException("trajectories must have same number of poses")
    return traj_ref, traj_est


class Metric(abc.ABC):
    @abc.abstractmethod
    def process_data(self, data):
        return

    @abc.abstractmethod
    def get_statistic(self, statistics_type):
        return

    @abc.abstractmethod
    def get_all_statistics(self):
        return

    @abc.abstractmethod
    def get_result(self):
        return


class PE(Metric):
    """A pose error metric: ``error`` (numpy array), ``unit``, statistics, result."""

    def __init__(self):
        self.unit: Unit = Unit.none
        self.error: np.ndarray = np.array([])

    def __str__(self) -> str:
        return "PE metric base class"

    @abc.abstractmethod
    def process_data(self, data):
        return

    def change_unit(self, new_unit: Unit) -> None:
        """Converts ``error`` between length units, or between degrees and radians."""
        if self.unit is new_unit:
            return
        if self.unit in (Unit.none, Unit.frames, Unit.percent, Unit.seconds):
            raise MetricsException(f"{self.unit} does not support conversions")
        bad = list(itertools.product(ANGLE_UNITS, LENGTH_UNITS))
        if any(c in bad for c in itertools.permutations((self.unit, new_unit))):
            raise MetricsException(f"cannot convert {self.unit} to {new_unit}")
        if len(self.error) == 0:
            raise MetricsException(
                "error array is empty - please process data before changing the unit"
            )
        if self.unit in LENGTH_UNITS and new_unit in LENGTH_UNITS:
            self.error *= METER_SCALE_FACTORS[self.unit] / METER_SCALE_FACTORS[new_unit]
        elif self.unit is Unit.radians and new_unit is Unit.degrees:
            self.error = np.rad2deg(self.error)
        elif self.unit is Unit.degrees and new_unit is Unit.radians:
            self.error = np.deg2rad(self.error)
        else:
            raise MetricsException(f"unknown unit combination {(self.unit, new_unit)}")
        self.unit = new_unit

    def get_statistic(self, statistics_type: StatisticsType) -> float:
        """rmse, sse, mean, median, max, min or std (population) of ``error``."""
        if statistics_type == StatisticsType.rmse:
            return math.sqrt(np.mean(np.power(self.error, 2)))
        if statistics_type == StatisticsType.sse:
            return np.sum(np.power(self.error, 2))
        if statistics_type == StatisticsType.mean:
            return float(np.mean(self.error))
        if statistics_type == StatisticsType.median:
            return np.median(self.error)
        if statistics_type == StatisticsType.max:
            return np.max(self.error)
        if statistics_type == StatisticsType.min:
            return np.min(self.error)
        if statistics_type == StatisticsType.std:
            return float(np.std(self.error))
        raise MetricsException("unsupported statistics_type")

    def get_all_statistics(self) -> typing.Dict[str, float]:
        """``{StatisticsType.value: statistic}`` for every statistics type."""
        return {s.value: self.get_statistic(s) for s in StatisticsType}

    def get_result(self, ref_name: str = "reference", est_name: str = "estimate") -> Result:
        """The Result: info (title, names, label), stats and ``error_array``."""
        result = Result()
        result.add_info(
            {
                "title": str(self),
                "ref_name": ref_name,
                "est_name": est_name,
                "label": f"{self.__class__.__name__} ({self.unit.value})",
            }
        )
        result.add_stats(self.get_all_statistics())
        if hasattr(self, "error"):
            result.add_np_array("error_array", self.error)
        return result


def _unit_of(relation: PoseRelation, rpe: bool) -> Unit:
    if relation in (PoseRelation.translation_part, PoseRelation.point_distance):
        return Unit.meters
    if rpe and relation == PoseRelation.point_distance_error_ratio:
        return Unit.percent
    if relation == PoseRelation.rotation_angle_deg:
        return Unit.degrees
    if relation == PoseRelation.rotation_angle_rad:
        return Unit.radians
    return Unit.none


class RPE(PE):
    """Relative pose error: ``E_i = (Q_i⁻¹ Q_j)⁻¹ (P_i⁻¹ P_j)`` for the pairs ``(i, j)`` at
    ``delta`` (``delta_unit`` frames, meters, degrees or radians; consecutive pairs or
    ``all_pairs``; chosen on the estimate or with ``pairs_from_reference`` the reference)."""

    def __init__(
        self,
        pose_relation: PoseRelation = PoseRelation.translation_part,
        delta: float = 1.0,
        delta_unit: Unit = Unit.frames,
        rel_delta_tol: float = 0.1,
        all_pairs: bool = False,
        pairs_from_reference: bool = False,
    ):
        if delta < 0:
            raise MetricsException("delta must be a positive number")
        if delta_unit == Unit.frames and not isinstance(delta, int) and not delta.is_integer():
            raise MetricsException(f"delta must be integer for delta unit {delta_unit}")
        self.delta = int(delta) if delta_unit == Unit.frames else delta
        self.delta_unit = delta_unit
        self.rel_delta_tol = rel_delta_tol
        self.pose_relation = pose_relation
        self.all_pairs = all_pairs
        self.pairs_from_reference = pairs_from_reference
        self._E = None
        self._data = None
        self.error = np.array([])
        self.delta_ids: typing.List[int] = []
        self.unit = _unit_of(pose_relation, rpe=True)

    def __str__(self) -> str:
        title = (
            f"RPE w.r.t. {self.pose_relation.value} ({self.unit.value})"
            f"\nfor delta = {self.delta} ({self.delta_unit.value})"
        )
        return title + (" using all pairs" if self.all_pairs else " using consecutive pairs")

    @staticmethod
    def rpe_base(Q_i, Q_i_delta, P_i, P_i_delta) -> np.ndarray:
        """The relative SE(3) error pose of one pair (TUM RGB-D notation)."""
        return lie.relative_se3(lie.relative_se3(Q_i, Q_i_delta), lie.relative_se3(P_i, P_i_delta))

    @property
    def E(self) -> typing.List[np.ndarray]:
        """The error poses (4×4) of the pairs (computed when first read)."""
        if self._E is None:
            self._E = []
            if self._data is not None and self.pose_relation not in (
                PoseRelation.point_distance,
                PoseRelation.point_distance_error_ratio,
            ):
                (traj_ref, traj_est), pairs = self._data
                q, p = traj_ref.poses_se3, traj_est.poses_se3
                self._E = [self.rpe_base(q[i], q[j], p[i], p[j]) for i, j in pairs]
        return self._E

    @E.setter
    def E(self, value) -> None:
        self._E = value

    def process_data(self, data: PathPair) -> None:
        """Computes ``error`` (and ``delta_ids``) for ``(traj_ref, traj_est)``."""
        traj_ref, traj_est = _pair(data)
        if self.delta_unit not in _DELTA_UNIT:
            raise FilterException(f"unsupported delta unit: {self.delta_unit}")
        ref_xyz, ref_q = _arrays(traj_ref)
        est_xyz, est_q = _arrays(traj_est)
        delta = float(self.delta)
        if delta == 0:
            raise FilterException(
                f"delta = {self.delta} ({self.delta_unit.value}) produced an empty index list - "
                "try lower values or a less strict tolerance"
            )
        try:
            errors, pairs = _sitar.rpe_errors(
                ref_xyz,
                ref_q,
                est_xyz,
                est_q,
                _RELATION[self.pose_relation],
                delta,
                _DELTA_UNIT[self.delta_unit],
                float(self.rel_delta_tol),
                bool(self.all_pairs),
                bool(self.pairs_from_reference),
            )
        except ValueError as error:
            text = str(error)
            if "no pose pairs" in text and "empty index list" in text:
                raise FilterException(
                    f"delta = {self.delta} ({self.delta_unit.value}) produced an empty index "
                    "list - try lower values or a less strict tolerance"
                ) from None
            raise MetricsException(text) from None
        self.error = np.frombuffer(errors, dtype=np.float64).copy()
        pairs = np.frombuffer(pairs, dtype=np.int64).reshape(-1, 2)
        self.delta_ids = pairs[:, 1].tolist()
        self._data = ((traj_ref, traj_est), pairs.tolist())
        self._E = None


class APE(PE):
    """Absolute pose error: ``E_i = P_i⁻¹ Q_i`` (estimate P, reference Q) for every pose."""

    def __init__(self, pose_relation: PoseRelation = PoseRelation.translation_part):
        self.pose_relation = pose_relation
        self._E = None
        self._data = None
        self.error = np.array([])
        self.unit = _unit_of(pose_relation, rpe=False)

    def __str__(self) -> str:
        return (
            "APE w.r.t. "
            + str(self.pose_relation.value)
            + " "
            + ("(" + self.unit.value + ")" if self.unit else "")
        )

    @staticmethod
    def ape_base(x_t: np.ndarray, x_t_star: np.ndarray) -> np.ndarray:
        """The error pose of one estimated pose and its reference."""
        return lie.relative_se3(x_t, x_t_star)

    @property
    def E(self):
        """The error poses (4×4; for the translation part and point distance, the position
        differences n×3), computed when first read."""
        if self._E is None:
            self._E = []
            if self._data is not None:
                traj_ref, traj_est = self._data
                if self.pose_relation in (
                    PoseRelation.translation_part,
                    PoseRelation.point_distance,
                ):
                    self._E = traj_est.positions_xyz - traj_ref.positions_xyz
                else:
                    self._E = [
                        self.ape_base(x, x_star)
                        for x, x_star in zip(traj_est.poses_se3, traj_ref.poses_se3)
                    ]
        return self._E

    @E.setter
    def E(self, value) -> None:
        self._E = value

    def process_data(self, data: PathPair) -> None:
        """Computes ``error`` for ``(traj_ref, traj_est)``."""
        traj_ref, traj_est = _pair(data)
        if self.pose_relation == PoseRelation.point_distance_error_ratio:
            raise MetricsException("unsupported pose_relation")
        ref_xyz, ref_q = _arrays(traj_ref)
        est_xyz, est_q = _arrays(traj_est)
        try:
            errors = _sitar.ape_errors(
                ref_xyz, ref_q, est_xyz, est_q, _RELATION[self.pose_relation]
            )
        except ValueError as error:
            raise MetricsException(str(error)) from None
        self.error = np.frombuffer(errors, dtype=np.float64).copy()
        self._data = (traj_ref, traj_est)
        self._E = None


def id_pairs_from_delta(
    poses: typing.Sequence[np.ndarray],
    delta: float,
    delta_unit: Unit,
    rel_tol: float = 0.1,
    all_pairs: bool = False,
) -> typing.List[typing.Tuple[int, int]]:
    """The index pairs of ``poses`` at ``delta`` (as RPE chooses them)."""
    path = trajectory.PosePath3D(poses_se3=poses)
    rpe = RPE(PoseRelation.point_distance, delta, delta_unit, rel_tol, all_pairs)
    rpe.process_data((path, path))
    return [tuple(p) for p in rpe._data[1]]
