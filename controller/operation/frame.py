"""The feet frame F as a planar frame (origin, yaw): points and rotations between the world and F, on floats."""

from __future__ import annotations

import math

import numpy as np

from controller.kinematics.rotations import rpy_to_rows, wrap_rad
from controller.operation.targets import yaw_rotation


class PlanarFrame:
    """A planar frame (origin p (3,) [m] in the world, yaw [rad] about the world's z) with the world <-> frame
    maps for points and rotations."""

    __slots__ = ("p", "yaw", "_R", "cos_sin")

    def __init__(self, p: np.ndarray, yaw: float) -> None:
        self.p, self.yaw, self._R = np.asarray(p, dtype=float), float(yaw), None
        self.cos_sin = (math.cos(self.yaw), math.sin(self.yaw))  # (cos yaw, sin yaw)

    def __repr__(self) -> str:
        return f"PlanarFrame(p={self.p.tolist()}, yaw={self.yaw})"

    @property
    def R(self) -> np.ndarray:
        """Rz(yaw) (3, 3), built on first use (most ticks need only to_local_rpy)."""
        if self._R is None:
            self._R = yaw_rotation(self.yaw)
        return self._R

    def to_local_rpy(self, p_world: np.ndarray, rpy_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """to_local(p_world, rpy_to_matrix(rpy_world)) on floats (Rz^T: a planar turn), once per tick."""
        p, R = self.to_local_rpy_rows(p_world, rpy_world)
        return np.array(p), np.array(R)

    def to_local_rpy_rows(self, p_world: np.ndarray, rpy_world: np.ndarray) -> tuple[tuple, tuple]:
        """to_local_rpy as floats: the position (3 floats [m]) and the rotation's rows."""
        c, s = self.cos_sin
        (x, y, z), (fx, fy, fz) = np.asarray(p_world, dtype=float).tolist(), self.p.tolist()
        x, y, z = x - fx, y - fy, z - fz
        r0, r1, r2 = rpy_to_rows(*np.asarray(rpy_world, dtype=float).tolist())
        return ((c * x + s * y, c * y - s * x, z),
                ((c * r0[0] + s * r1[0], c * r0[1] + s * r1[1], c * r0[2] + s * r1[2]),
                 (c * r1[0] - s * r0[0], c * r1[1] - s * r0[1], c * r1[2] - s * r0[2]),
                 tuple(r2)))

    def to_local(self, p_world, R_world=None):
        p = self.R.T @ (np.asarray(p_world, dtype=float) - self.p)
        return p if R_world is None else (p, self.R.T @ R_world)

    def to_world(self, p_local, R_local=None):
        p = self.p + self.R @ np.asarray(p_local, dtype=float)
        return p if R_local is None else (p, self.R @ R_local)

    def to_world_rows(self, p_local, R_rows):
        """to_world on floats: p_w = p + Rz p_local (3 floats [m]), R_w = Rz R_local (rows of 3 floats)."""
        c, s = self.cos_sin
        fx, fy, fz = self.p.tolist()
        x, y, z = p_local
        (a0, a1, a2), (a3, a4, a5), (a6, a7, a8) = R_rows
        return ((fx + c * x - s * y, fy + s * x + c * y, fz + z),
                ((c * a0 - s * a3, c * a1 - s * a4, c * a2 - s * a5),
                 (s * a0 + c * a3, s * a1 + c * a4, s * a2 + c * a5), (a6, a7, a8)))


def sole_from_sole(p_from_world: np.ndarray, R_from_world: np.ndarray, p_to_world: np.ndarray,
                   R_to_world: np.ndarray) -> tuple[float, float, float]:
    """The `to` sole in the `from` sole's planar frame: (x [m], y [m], yaw [rad] wrapped)."""
    (r00, _, _), (r10, _, _), _ = R_from_world.tolist()
    (l00, _, _), (l10, _, _), _ = R_to_world.tolist()
    yaw_r = math.atan2(r10, r00)
    dx, dy = (float(p_to_world[i] - p_from_world[i]) for i in (0, 1))
    c, s = math.cos(yaw_r), math.sin(yaw_r)
    return (c * dx + s * dy, -s * dx + c * dy, wrap_rad(math.atan2(l10, l00) - yaw_r))


def sub3(a, b) -> tuple[float, float, float]:
    """a - b for two 3-vectors of floats."""
    return a[0] - b[0], a[1] - b[1], a[2] - b[2]
