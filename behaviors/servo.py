"""Small pure pieces the behaviours share: a rate-limited proportional approach to a goal, the rotation
vector between two orientations, angle wrapping, the yaw rotation."""

from __future__ import annotations

import math

import numpy as np

from controller.kinematics.rotations import wrap_rad  # noqa: F401 (behaviours import it from here)


def toward(error: np.ndarray, gain_1_s: float, max_speed: float) -> np.ndarray:
    """Velocity that closes `error` at `gain_1_s` times the error, its norm capped at `max_speed` (the
    direction kept); units: those of the error, per second."""
    e = np.asarray(error, dtype=float)
    v = gain_1_s * e
    n = float(np.linalg.norm(v))
    return v * (max_speed / n) if n > max_speed > 0.0 else v


def rotation_vector(R_from: np.ndarray, R_to: np.ndarray) -> np.ndarray:
    """The rotation vector w [rad] (axis times angle, in the frame both are expressed in) with
    exp([w]) @ R_from = R_to."""
    R = np.asarray(R_to, dtype=float) @ np.asarray(R_from, dtype=float).T
    cos = max(-1.0, min(1.0, (float(np.trace(R)) - 1.0) / 2.0))
    angle = math.acos(cos)
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if angle < 1e-9:
        return 0.5 * axis
    s = math.sin(angle)
    if s > 1e-6:
        return axis * (angle / (2.0 * s))
    # angle near pi: the axis from the symmetric part
    k = np.sqrt(np.maximum((np.diag(R) + 1.0) / 2.0, 0.0))
    i = int(np.argmax(k))
    k[(i + 1) % 3] = math.copysign(k[(i + 1) % 3], R[i, (i + 1) % 3] + R[(i + 1) % 3, i])
    k[(i + 2) % 3] = math.copysign(k[(i + 2) % 3], R[i, (i + 2) % 3] + R[(i + 2) % 3, i])
    return k / np.linalg.norm(k) * angle


def rot_z(yaw_rad: float) -> np.ndarray:
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])



MIN_JERK_PEAK = 1.875  # peak rate of the minimum-jerk ratio 10 s^3 - 15 s^4 + 6 s^5 over its mean


def min_jerk_duration_s(distance: float, max_speed: float, dt_s: float) -> float:
    """The shortest minimum-jerk move over `distance` whose peak speed is `max_speed` (same units) [s]."""
    return max(MIN_JERK_PEAK * abs(distance) / max_speed, 2.0 * dt_s)


def min_jerk_rate(t_s: float, dt_s: float, duration_s: float) -> float:
    """The ratio's increase over the tick [t, t + dt] divided by dt [1/s]: summed over the ticks of a plan,
    times dt, exactly 1 (a feed-forward velocity that integrates to the whole move)."""
    from controller.interpolation.hoff_arbib import min_jerk

    return float(min_jerk((t_s + dt_s) / duration_s) - min_jerk(t_s / duration_s)) / dt_s


#: [s] after a minimum-jerk plan, for the IK to catch up before a move checks where its point ended
MOVE_SETTLE_S = 0.3


class MinJerkMove:
    """The timing a behaviour moving one point along a minimum-jerk plan of `plan_s` [s] shares (reach, follow_arc):
    its nominal duration, its progress, and whether it is still moving or settling."""

    plan_s: float

    def nominal_duration_s(self) -> float:
        return getattr(self, "plan_s", 1.0) + MOVE_SETTLE_S + 0.5

    def progress(self, ctx) -> float:
        from controller.interpolation.hoff_arbib import min_jerk

        return float(min_jerk(ctx.elapsed_s / self.plan_s))

    def settled(self, t_s: float) -> bool:
        """The plan and the settle after it are over at `t_s` [s] of the behaviour's time: check the result."""
        return t_s >= self.plan_s + MOVE_SETTLE_S
