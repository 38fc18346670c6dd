"""Small rotation helpers (roll-pitch-yaw = fixed-axis XYZ, as hrpsys)."""

from __future__ import annotations

import math

import numpy as np


def wrap_rad(angle: float) -> float:
    """`angle` [rad] in [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


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
    """Rotation matrix (3, 3) of the quaternion q = (w, x, y, z) (MuJoCo's order), normalised first."""
    w, x, y, z = np.asarray(q, dtype=float).tolist()
    return np.array(quat_xyzw_to_rows(x, y, z, w))


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


def rows_log3(R) -> tuple[float, float, float]:
    """Rotation vector [rad] (axis * angle, angle in [0, pi]) of the rotation R; inverse of rows_exp3."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R
    c = max(-1.0, min(1.0, 0.5 * (r00 + r11 + r22 - 1.0)))
    vx, vy, vz = r21 - r12, r02 - r20, r10 - r01  # 2 sin(angle) axis
    angle = math.acos(c)
    s = math.sin(angle)
    if s > 1e-6:
        k = angle / (2.0 * s)
        return vx * k, vy * k, vz * k
    if c > 0.0:  # near identity: first order
        return 0.5 * vx, 0.5 * vy, 0.5 * vz
    # near a half turn: the axis from the diagonal (R = c I + (1 - c) a a^T + s [a]x)
    d = (r00, r11, r22)
    i = max(range(3), key=d.__getitem__)
    a = [0.0, 0.0, 0.0]
    a[i] = math.sqrt(max(0.0, (d[i] - c) / (1.0 - c)))
    for j in range(3):
        if j != i:
            a[j] = (R[i][j] + R[j][i]) / (2.0 * (1.0 - c) * a[i])
    if a[0] * vx + a[1] * vy + a[2] * vz < 0.0:
        a = [-x for x in a]
    return a[0] * angle, a[1] * angle, a[2] * angle


def rows_small_log3(R) -> tuple[float, float, float]:
    """Rotation vector [rad] of R to first order (the antisymmetric part): error ~ angle^3 / 6, enough for
    the few-mrad rotation an operational point makes in one tick."""
    return 0.5 * (R[2][1] - R[1][2]), 0.5 * (R[0][2] - R[2][0]), 0.5 * (R[1][0] - R[0][1])


def rows_exp3(w_rad):
    """Rotation (rows) of the rotation vector w_rad = axis * angle [rad] (Rodrigues); inverse of rows_log3."""
    x, y, z = w_rad
    t2 = x * x + y * y + z * z
    if t2 < 1e-18:
        return ((1.0, -z, y), (z, 1.0, -x), (-y, x, 1.0))
    t = math.sqrt(t2)
    s, c = math.sin(t) / t, (1.0 - math.cos(t)) / t2
    return ((1.0 - c * (y * y + z * z), c * x * y - s * z, c * x * z + s * y),
            (c * x * y + s * z, 1.0 - c * (x * x + z * z), c * y * z - s * x),
            (c * x * z - s * y, c * y * z + s * x, 1.0 - c * (x * x + y * y)))


def rows_angle_between(A, B) -> float:
    """Angle [rad] in [0, pi] of the rotation A^T B that takes A to B, from its trace (the sum of the
    element-wise products of A and B)."""
    (a0, a1, a2), (a3, a4, a5), (a6, a7, a8) = A
    (b0, b1, b2), (b3, b4, b5), (b6, b7, b8) = B
    t = a0 * b0 + a1 * b1 + a2 * b2 + a3 * b3 + a4 * b4 + a5 * b5 + a6 * b6 + a7 * b7 + a8 * b8
    return math.acos(max(-1.0, min(1.0, 0.5 * (t - 1.0))))


def quat_xyzw_to_rows(x: float, y: float, z: float, w: float):
    """Rotation (rows) of the quaternion (x, y, z, w) (pinocchio's order in a configuration), normalised first."""
    n = 1.0 / math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x * n, y * n, z * n, w * n
    return ((1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)),
            (2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)),
            (2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)))


def quat_xyzw_to_rpy(x: float, y: float, z: float, w: float) -> tuple[float, float, float]:
    """(roll, pitch, yaw) [rad] (R = Rz(yaw) Ry(pitch) Rx(roll), as rpy_to_rows) of the quaternion (x, y, z, w),
    normalised first."""
    n2 = x * x + y * y + z * z + w * w
    return (math.atan2(2.0 * (w * x + y * z), n2 - 2.0 * (x * x + y * y)),
            math.asin(max(-1.0, min(1.0, 2.0 * (w * y - x * z) / n2))),
            math.atan2(2.0 * (w * z + x * y), n2 - 2.0 * (y * y + z * z)))


def homogeneous(p: np.ndarray, R: np.ndarray) -> np.ndarray:
    """(4, 4) transform of position `p` (3,) [m] and rotation `R` (3, 3)."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T
