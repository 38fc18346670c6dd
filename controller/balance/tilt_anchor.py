"""The plan seen from a robot resting tipped: a rigid rotation of the plan about a pivot on the ground, from
the measured tilt back to level over a stated time (the plan's own levelling motion)."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from controller.interpolation.hoff_arbib import min_jerk


def _min_jerk_rate(s: float) -> float:
    """d/ds of min_jerk at s in [0, 1]."""
    return 30.0 * s * s * (1.0 - s) * (1.0 - s)


class TiltAnchor:
    """A robot held still mid-step (the hard e-stop) can tip onto its swing foot and rest there, tilted by the
    rotation that takes the planned BODY z axis onto the estimated one. Seen from that robot, the plan is
    rotated by the same tilt about the support sole (`pivot_world`, the point the state estimate anchors the
    robot at). While the plan lands the swing foot, the robot levels with it: this rotation goes from the
    measured tilt to none along a minimum-jerk profile over `duration_s`, so that references built from the
    plan (COG, capture point, soles) agree with the measured robot throughout instead of differing by the tilt.
    """

    def __init__(self, R_body_plan: np.ndarray, R_body_est: np.ndarray, pivot_world: np.ndarray,
                 duration_s: float) -> None:
        z_plan = np.asarray(R_body_plan, dtype=float)[:, 2]
        z_est = np.asarray(R_body_est, dtype=float)[:, 2]
        axis = np.cross(z_plan, z_est)
        sin_a, cos_a = float(np.linalg.norm(axis)), float(z_plan @ z_est)
        self.angle0_rad = math.atan2(sin_a, cos_a)
        self.axis = axis / sin_a if sin_a > 1e-12 else np.array([1.0, 0.0, 0.0])
        self.pivot_world = np.array(pivot_world, dtype=float)
        self.duration_s = max(float(duration_s), 1e-9)
        self.elapsed_s = 0.0
        self.R = np.eye(3)
        self.omega_rad_s = np.zeros(3)  # (3,) angular velocity of the rotation, world
        self._update()

    @property
    def done(self) -> bool:
        return self.elapsed_s >= self.duration_s

    def step(self, dt_s: float) -> None:
        """Advance by one tick."""
        self.elapsed_s = min(self.elapsed_s + dt_s, self.duration_s)
        self._update()

    def _update(self) -> None:
        s = self.elapsed_s / self.duration_s
        angle = self.angle0_rad * (1.0 - float(min_jerk(s)))
        self.R = pin.exp3(self.axis * angle)
        self.omega_rad_s = self.axis * (-self.angle0_rad * _min_jerk_rate(s) / self.duration_s)

    def point(self, p_world: np.ndarray) -> np.ndarray:
        """A point of the plan (3,) as the tipped robot sees it [m]."""
        return self.pivot_world + self.R @ (np.asarray(p_world, dtype=float) - self.pivot_world)

    def velocity(self, p_world: np.ndarray, v_world: np.ndarray) -> np.ndarray:
        """The velocity (3,) [m/s] of the plan's point `p_world` moving at `v_world`, as the tipped robot sees it."""
        r = self.R @ (np.asarray(p_world, dtype=float) - self.pivot_world)
        return self.R @ np.asarray(v_world, dtype=float) + np.cross(self.omega_rad_s, r)

    def rotation(self, R_world: np.ndarray) -> np.ndarray:
        """An orientation (3, 3) of the plan as the tipped robot sees it."""
        return self.R @ np.asarray(R_world, dtype=float)
