"""One tick of an operated point after the Eq. 5 sum: its twist limited in speed, ramped in acceleration from
the last tick's, and integrated into its target in the feet frame F."""

from __future__ import annotations

import math
from typing import NamedTuple

from controller.core.errors import InvalidCommand
from controller.operation.limits import speed_scale
from controller.operation.points import Twist

_ZERO_FLOATS = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))  # a point at rest


class PointStep(NamedTuple):
    """A point's tick: its new target, the twist it integrated (its rate, kept for the next tick's ramp; None when
    it is zero: the point came to rest) and whether the speed limit scaled the asked twist down."""

    target: object  # HandPose | GazeAngles | WaistPose (controller.operation.targets), in F
    rate: Twist | None
    velocity_limited: bool


def integrate_point(target, twist: Twist, previous: Twist | None, speed_limits: tuple[float, float],
                    accel_steps: tuple[float, float], dt_s: float) -> PointStep:
    """`target` moved by `twist` for dt_s [s]: at most `speed_limits` (linear [m/s], angular [rad/s]), changed
    by at most `accel_steps` (linear [m/s], angular [rad/s] per tick) from `previous` (None: from rest).
    limits.limit_twist then limits.ramp_twist, on the twists' floats read once (this runs per point and tick)."""
    lin, ang = twist.linear_m_s.tolist(), twist.angular_rad_s.tolist()
    scale = min(speed_scale(math.hypot(*lin), speed_limits[0]), speed_scale(math.hypot(*ang), speed_limits[1]))
    if scale != 1.0:
        twist = twist.scaled(scale)
        lin, ang = twist.linear_m_s.tolist(), twist.angular_rad_s.tolist()
    max_linear_step, max_angular_step = accel_steps
    if not (max_linear_step > 0.0 and max_angular_step > 0.0):
        raise InvalidCommand(f"ramp steps {max_linear_step!r}, {max_angular_step!r}: must be > 0")
    if previous is None:
        (a, b, c), (d, e, f) = _ZERO_FLOATS
    else:
        (a, b, c), (d, e, f) = previous.linear_m_s.tolist(), previous.angular_rad_s.tolist()
    (g, h, i), (j, k, m) = lin, ang
    dl, da = (g - a, h - b, i - c), (j - d, k - e, m - f)
    ramp = min(speed_scale(math.hypot(*dl), max_linear_step), speed_scale(math.hypot(*da), max_angular_step))
    if ramp == 1.0:  # the goal is within this tick's step
        rate, at_rest = twist, not (g or h or i or j or k or m)
    else:
        lin = (a + ramp * dl[0], b + ramp * dl[1], c + ramp * dl[2])
        ang = (d + ramp * da[0], e + ramp * da[1], f + ramp * da[2])
        rate, at_rest = Twist.of(lin, ang), not (any(lin) or any(ang))
    return PointStep(target.integrated(rate, dt_s), None if at_rest else rate, scale < 1.0)


class PointLimits:
    """Each IK point's speed limits and acceleration steps, from the OperationParams (controller.layers.operation;
    the tables are rebuilt only when the parameters or the tick change)."""

    __slots__ = ("_speed_of", "_accel_of")

    def __init__(self) -> None:
        self._speed_of: tuple = (None, None)  # (params, speed limits per IK point)
        self._accel_of: tuple = (None, None)  # ((params, dt), twist change per tick per IK point)

    def speed(self, p, point: str) -> tuple[float, float]:
        """(linear [m/s], angular [rad/s]) speed limit of an IK point under the parameters `p`."""
        if self._speed_of[0] is not p:
            self._speed_of = (p, {"rhand": (p.hand_speed_m_s, p.hand_angular_speed_rad_s),
                                  "lhand": (p.hand_speed_m_s, p.hand_angular_speed_rad_s),
                                  "head": (1.0, p.head_angular_speed_rad_s),
                                  "waist": (p.waist_speed_m_s, p.waist_angular_speed_rad_s)})
        return self._speed_of[1][point]

    def accel_steps(self, p, point: str, dt_s: float) -> tuple[float, float]:
        """(linear [m/s], angular [rad/s]) change of an IK point's twist allowed in one tick of dt_s [s]."""
        key = (p, dt_s)
        if self._accel_of[0] != key:
            self._accel_of = (key, {"rhand": (p.hand_accel_m_s2 * dt_s, p.hand_angular_accel_rad_s2 * dt_s),
                                    "lhand": (p.hand_accel_m_s2 * dt_s, p.hand_angular_accel_rad_s2 * dt_s),
                                    "head": (1.0, p.head_angular_accel_rad_s2 * dt_s),  # (no linear part)
                                    "waist": (p.waist_accel_m_s2 * dt_s, p.waist_angular_accel_rad_s2 * dt_s)})
        return self._accel_of[1][point]
