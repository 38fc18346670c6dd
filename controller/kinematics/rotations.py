"""Small rotation helpers (roll-pitch-yaw = fixed-axis XYZ, as hrpsys)."""

from __future__ import annotations

import math

import numpy as np


def rpy_to_matrix(rpy: np.ndarray) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll)."""
    return np.array(rpy_to_rows(*np.asarray(rpy, dtype=float).tolist()))


def rpy_to_rows(r: float, p: float, y: float) -> tuple[tuple[float, float, float], ...]:
    """rpy_to_matrix as nested tuples of floats (rows), for scalar hot paths."""
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return (
        (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        (-sp, cp * sr, cp * cr),
    )


def matrix_to_rpy(R: np.ndarray) -> np.ndarray:
    """Inverse of rpy_to_matrix (pitch in [-pi/2, pi/2])."""
    pitch = np.arcsin(np.clip(-R[2, 0], -1.0, 1.0))
    roll = np.arctan2(R[2, 1], R[2, 2])
    yaw = np.arctan2(R[1, 0], R[0, 0])
    return np.array([roll, pitch, yaw])


def matrix_to_rpy_floats(R: np.ndarray) -> tuple[float, float, float]:
    """matrix_to_rpy as three floats (math on a 3x3 costs a fraction of numpy's per-call overhead)."""
    (r00, _, _), (r10, _, _), (r20, r21, r22) = np.asarray(R, dtype=float).tolist()
    return math.atan2(r21, r22), math.asin(max(-1.0, min(1.0, -r20))), math.atan2(r10, r00)


def quat_wxyz_to_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for 3-vectors, without np.cross's axis handling (10x faster on the hot path)."""
    return np.array((a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]))


# ---- on floats: rotations as 3 row tuples, vectors as 3-tuples. On 3x3 data plain floats are several times
# faster than numpy's per-call overhead (a (3, 3) @ (3,) costs ~1.5 us in numpy, ~0.3 us here).


def rows_mul(A, B):
    """A B."""
    (a0, a1, a2), (a3, a4, a5), (a6, a7, a8) = A
    (b0, b1, b2), (b3, b4, b5), (b6, b7, b8) = B
    return ((a0 * b0 + a1 * b3 + a2 * b6, a0 * b1 + a1 * b4 + a2 * b7, a0 * b2 + a1 * b5 + a2 * b8),
            (a3 * b0 + a4 * b3 + a5 * b6, a3 * b1 + a4 * b4 + a5 * b7, a3 * b2 + a4 * b5 + a5 * b8),
            (a6 * b0 + a7 * b3 + a8 * b6, a6 * b1 + a7 * b4 + a8 * b7, a6 * b2 + a7 * b5 + a8 * b8))


def rows_tmul(A, B):
    """A^T B."""
    (a0, a1, a2), (a3, a4, a5), (a6, a7, a8) = A
    (b0, b1, b2), (b3, b4, b5), (b6, b7, b8) = B
    return ((a0 * b0 + a3 * b3 + a6 * b6, a0 * b1 + a3 * b4 + a6 * b7, a0 * b2 + a3 * b5 + a6 * b8),
            (a1 * b0 + a4 * b3 + a7 * b6, a1 * b1 + a4 * b4 + a7 * b7, a1 * b2 + a4 * b5 + a7 * b8),
            (a2 * b0 + a5 * b3 + a8 * b6, a2 * b1 + a5 * b4 + a8 * b7, a2 * b2 + a5 * b5 + a8 * b8))


def rows_tmulv(A, v):
    """A^T v."""
    (a0, a1, a2), (a3, a4, a5), (a6, a7, a8) = A
    x, y, z = v
    return (a0 * x + a3 * y + a6 * z, a1 * x + a4 * y + a7 * z, a2 * x + a5 * y + a8 * z)


def rows_mulv(A, v):
    """A v."""
    (a0, a1, a2), (a3, a4, a5), (a6, a7, a8) = A
    x, y, z = v
    return (a0 * x + a1 * y + a2 * z, a3 * x + a4 * y + a5 * z, a6 * x + a7 * y + a8 * z)
