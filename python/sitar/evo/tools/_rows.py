"""The poses of a TUM or EuRoC file, read and checked but parsed when first used.

A script that associates a 200 Hz ground truth with a 20 Hz estimate needs every stamp
but one pose in ten: the readers give a trajectory whose positions and quaternions are
these rows until something asks for them (``positions_xyz``, ``poses_se3``, a metric, a
plot), then are parsed at once for the rows still kept. ``reduce_to_ids`` (and so the
association) only narrows the rows. What evo checks on reading is checked on reading;
see ``python/README.md`` for the one kind of bad field reported later.
"""

import typing

import numpy as np


class FileRows:
    """Rows of one file (the extension's ``MatrixRows``) narrowed to ``ids`` (None: all),
    and the columns of the positions (x y z) and quaternions (w x y z) in each row."""

    __slots__ = ("_matrix", "_xyz", "_quat", "_ids", "_error")

    def __init__(
        self,
        matrix,
        xyz_columns: typing.Sequence[int],
        quat_columns: typing.Sequence[int],
        error: typing.Type[Exception],
        ids: typing.Optional[np.ndarray] = None,
    ):
        self._matrix = matrix
        self._xyz = list(xyz_columns)
        self._quat = list(quat_columns)
        self._error = error
        self._ids = ids

    def __len__(self) -> int:
        return len(self._matrix) if self._ids is None else len(self._ids)

    def reduced(self, ids) -> "FileRows":
        """These rows narrowed as numpy narrows an array by ``ids`` (indices, a boolean
        mask or a slice, with numpy's errors)."""
        current = np.arange(len(self._matrix)) if self._ids is None else self._ids
        kept = np.asarray(current[ids], dtype=np.int64).reshape(-1)
        return FileRows(self._matrix, self._xyz, self._quat, self._error, kept)

    def values(self) -> typing.Tuple[np.ndarray, np.ndarray]:
        """The positions (n×3) and quaternions (n×4, w x y z): new writable arrays."""
        ids = None if self._ids is None else np.ascontiguousarray(self._ids).tobytes()
        try:
            data = self._matrix.values(ids, self._xyz + self._quat)
        except ValueError as error:
            raise self._error(str(error)) from None
        both = np.frombuffer(data, dtype=np.float64).reshape(len(self), 7)
        return np.ascontiguousarray(both[:, :3]), np.ascontiguousarray(both[:, 3:])
