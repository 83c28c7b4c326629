"""evo.core.lie_algebra's pose helpers (SE(3) matrices), and the vectorised conversions
``sitar.evo`` builds on: quaternions (w x y z) to and from rotation matrices, Euler angles
(static x-y-z), for stacks of poses at once."""

import numpy as np

from sitar.evo import EvoException
from sitar.evo._missing import missing


class LieAlgebraException(EvoException):
    pass


def se3(r: np.ndarray = np.eye(3), t: np.ndarray = np.array([0, 0, 0])) -> np.ndarray:
    """The 4×4 pose of rotation ``r`` and translation ``t``."""
    pose = np.eye(4)
    pose[:3, :3] = r
    pose[:3, 3] = t
    return pose


def so3_from_se3(p: np.ndarray) -> np.ndarray:
    """The rotation block of a pose."""
    return p[:3, :3]


def se3_inverse(p: np.ndarray) -> np.ndarray:
    """The inverse of a rigid pose."""
    r_inv = p[:3, :3].transpose()
    return se3(r_inv, -r_inv.dot(p[:3, 3]))


def relative_se3(p1: np.ndarray, p2: np.ndarray) -> np.ndarray:
    """``p1⁻¹ · p2``."""
    return np.dot(se3_inverse(p1), p2)


def sim3(r: np.ndarray, t: np.ndarray, s: float) -> np.ndarray:
    """The 4×4 similarity ``x ↦ s r x + t``."""
    pose = np.eye(4)
    pose[:3, :3] = s * r
    pose[:3, 3] = t
    return pose


def is_so3(r: np.ndarray) -> bool:
    """Orthonormal with determinant +1 (numpy's allclose)."""
    return bool(np.isclose(np.linalg.det(r), 1.0) and np.allclose(r.dot(r.T), np.eye(3)))


def is_se3(p: np.ndarray) -> bool:
    """A rotation block and a last row of (0, 0, 0, 1)."""
    return is_so3(p[:3, :3]) and bool(np.allclose(p[3, :], np.array([0, 0, 0, 1])))


def so3_exp(rotation_vector: np.ndarray) -> np.ndarray:
    """The rotation matrix of an axis-angle vector (scipy)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_rotvec(rotation_vector).as_matrix()


def so3_log(r: np.ndarray, return_skew: bool = False) -> np.ndarray:
    """The axis-angle vector of a rotation matrix (or its skew matrix; scipy)."""
    from scipy.spatial.transform import Rotation

    vector = Rotation.from_matrix(r).as_rotvec()
    if return_skew:
        x, y, z = vector
        return np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return vector


def so3_log_angle(r: np.ndarray, degrees: bool = False) -> float:
    """The rotation angle of a rotation matrix (radians, or degrees)."""
    angle = np.linalg.norm(so3_log(r))
    return float(np.rad2deg(angle) if degrees else angle)


# --- Vectorised conversions (not evo API) -------------------------------------------------


def matrices_from_quaternions(wxyz: np.ndarray) -> np.ndarray:
    """n×3×3 rotation matrices of n quaternions (w x y z), each normalised first; a
    quaternion of (near) zero norm gives the identity."""
    q = np.asarray(wxyz, dtype=np.float64)
    n = np.einsum("ij,ij->i", q, q)
    small = n < np.finfo(float).eps * 4.0
    scaled = q * np.sqrt(2.0 / np.where(small, 1.0, n))[:, None]
    w, x, y, z = scaled.T
    m = np.empty((len(q), 3, 3))
    m[:, 0, 0] = 1.0 - y * y - z * z
    m[:, 0, 1] = x * y - z * w
    m[:, 0, 2] = x * z + y * w
    m[:, 1, 0] = x * y + z * w
    m[:, 1, 1] = 1.0 - x * x - z * z
    m[:, 1, 2] = y * z - x * w
    m[:, 2, 0] = x * z - y * w
    m[:, 2, 1] = y * z + x * w
    m[:, 2, 2] = 1.0 - x * x - y * y
    m[small] = np.eye(3)
    return m


def poses_from(xyz: np.ndarray, wxyz: np.ndarray) -> np.ndarray:
    """n×4×4 poses of positions and quaternions (w x y z)."""
    poses = np.zeros((len(xyz), 4, 4))
    poses[:, :3, :3] = matrices_from_quaternions(wxyz)
    poses[:, :3, 3] = xyz
    poses[:, 3, 3] = 1.0
    return poses


def quaternions_from_matrices(m: np.ndarray) -> np.ndarray:
    """n×4 unit quaternions (w x y z, w ≥ 0) of the upper-left 3×3 blocks of ``m``: the
    eigenvector of the largest eigenvalue of Bar-Itzhack's symmetric 4×4 matrix, the
    quaternion of the nearest rotation for blocks that are not exactly one."""
    m = np.asarray(m, dtype=np.float64)
    m00, m01, m02 = m[:, 0, 0], m[:, 0, 1], m[:, 0, 2]
    m10, m11, m12 = m[:, 1, 0], m[:, 1, 1], m[:, 1, 2]
    m20, m21, m22 = m[:, 2, 0], m[:, 2, 1], m[:, 2, 2]
    k = np.empty((len(m), 4, 4))
    k[:, 0, 0] = m00 - m11 - m22
    k[:, 1, 0] = k[:, 0, 1] = m01 + m10
    k[:, 1, 1] = m11 - m00 - m22
    k[:, 2, 0] = k[:, 0, 2] = m02 + m20
    k[:, 2, 1] = k[:, 1, 2] = m12 + m21
    k[:, 2, 2] = m22 - m00 - m11
    k[:, 3, 0] = k[:, 0, 3] = m21 - m12
    k[:, 3, 1] = k[:, 1, 3] = m02 - m20
    k[:, 3, 2] = k[:, 2, 3] = m10 - m01
    k[:, 3, 3] = m00 + m11 + m22
    k /= 3.0
    _, vectors = np.linalg.eigh(k)
    xyzw = vectors[:, :, -1]  # the eigenvalues ascend
    q = xyzw[:, [3, 0, 1, 2]]
    q[q[:, 0] < 0.0] *= -1.0
    return q


def euler_sxyz(m: np.ndarray) -> np.ndarray:
    """n×3 Euler angles (roll, pitch, yaw; static axes x, y, z) of the rotation blocks."""
    m = np.asarray(m, dtype=np.float64)
    cy = np.sqrt(m[:, 0, 0] ** 2 + m[:, 1, 0] ** 2)
    regular = cy > np.finfo(float).eps * 4.0
    ax = np.where(regular, np.arctan2(m[:, 2, 1], m[:, 2, 2]), np.arctan2(-m[:, 1, 2], m[:, 1, 1]))
    ay = np.arctan2(-m[:, 2, 0], cy)
    az = np.where(regular, np.arctan2(m[:, 1, 0], m[:, 0, 0]), 0.0)
    return np.stack([ax, ay, az], axis=1)


__getattr__ = missing(
    "evo.core.lie_algebra",
    {
        name: "numpy/scipy (scipy.spatial.transform.Rotation) on the poses_se3 matrices"
        for name in (
            "hat",
            "vee",
            "sim3_scale",
            "sim3_inverse",
            "se3_poses_to_xyz_quat_wxyz",
            "random_so3",
            "random_se3",
            "random_sim3",
        )
    },
)
