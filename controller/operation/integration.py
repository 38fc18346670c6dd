"""One tick of an operated point after the Eq. 5 sum: its twist limited in speed, ramped in acceleration from
the last tick's, and integrated into its target in the feet frame F."""

from __future__ import annotations

from typing import NamedTuple

from controller.operation.limits import limit_twist, ramp_twist
from controller.operation.points import ZERO_TWIST, Twist


class PointStep(NamedTuple):
    """A point's tick: its new target, the twist it integrated (its rate, kept for the next tick's ramp) and
    whether the speed limit scaled the asked twist down."""

    target: object  # HandPose | GazeAngles | WaistPose (controller.operation.targets), in F
    rate: Twist
    velocity_limited: bool


def integrate_point(target, twist: Twist, previous: Twist | None, speed_limits: tuple[float, float],
                    accel_steps: tuple[float, float], dt_s: float) -> PointStep:
    """`target` moved by `twist` for dt_s [s]: at most `speed_limits` (linear [m/s], angular [rad/s]), changed
    by at most `accel_steps` (linear [m/s], angular [rad/s] per tick) from `previous` (None: from rest)."""
    limited = limit_twist(twist, *speed_limits)
    ramped = ramp_twist(previous or ZERO_TWIST, limited.twist, *accel_steps)
    return PointStep(target.integrated(ramped, dt_s), ramped, limited.scale < 1.0)


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
