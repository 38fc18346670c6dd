"""Per-point speed limits (one scale factor that keeps the direction) and the reach clamp of the targets."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from controller.core.errors import InvalidCommand
from controller.operation.points import Twist

#: Why a point did less than it was asked (the status' `limited`).
REACH = "reach"  # the IK cannot get there (workspace, singularity, balance, another point)
JOINT_LIMIT = "joint_limit"  # a joint of the point's limb brakes at its position limit
VELOCITY = "velocity"  # the commanded speed is over the point's limit (or a joint runs at its velocity limit)
MOTION_STOP = "motion_stop"  # the EmergencyStopper holds the motion: nothing integrates until it is released
BALANCING = "balancing"  # a foot waits on the floor while the AutoBalancer brings the COM over the other foot
LIMIT_REASONS = (REACH, JOINT_LIMIT, VELOCITY, MOTION_STOP)


class Limited(NamedTuple):
    """A twist after the speed limits: `twist` = the input times `scale` in [0, 1] (same direction)."""

    twist: Twist
    scale: float


def speed_scale(speed: float, limit: float) -> float:
    """The factor [0, 1] that brings `speed` (>= 0) down to `limit` (> 0); 1 when it is under it."""
    if not limit > 0.0:
        raise InvalidCommand(f"speed limit {limit!r}: must be > 0")
    return 1.0 if speed <= limit else limit / speed


def limit_twist(twist: Twist, max_linear_m_s: float, max_angular_rad_s: float) -> Limited:
    """One scale factor for the whole twist: the smaller of the linear and the angular ones, so the point
    slows down along the direction it was asked to go (linear [m/s] and angular [rad/s] norms)."""
    lin = math.hypot(*twist.linear_m_s.tolist())  # floats: several times cheaper than numpy on 3-vectors
    ang = math.hypot(*twist.angular_rad_s.tolist())
    scale = min(speed_scale(lin, max_linear_m_s), speed_scale(ang, max_angular_rad_s))
    return Limited(twist if scale == 1.0 else twist.scaled(scale), scale)


def clamp_to_achieved(target, achieved, limited: str | None):
    """The target for the next tick: the achieved pose when the IK could not follow (`limited` is REACH,
    JOINT_LIMIT or VELOCITY from the IK), so the integrated target never runs away from the robot; else the
    target itself. Works on any pose representation (the caller's)."""
    if limited is None:
        return target
    if limited not in LIMIT_REASONS:
        raise InvalidCommand(f"limit reason {limited!r}; valid: {list(LIMIT_REASONS)} or None")
    return achieved if limited in (REACH, JOINT_LIMIT, VELOCITY) else target


#: [m] the length that weighs a rotation [rad] against a translation [m] in a hand's step (a hand's reach)
HAND_STEP_LENGTH_M = 0.1


def share_along(step: np.ndarray, achieved_step: np.ndarray) -> float:
    """The share s in [0, 1] of an asked step (n,) that an achieved step (n,) made along it: the projection of
    the achieved onto the asked, so that a target advanced by s of its step keeps the asked direction (0 for
    no step asked)."""
    n2 = float(step @ step)
    if not n2 > 0.0:
        return 0.0
    return min(1.0, max(0.0, float(achieved_step @ step) / n2))


def ramp_twist(previous: Twist, goal: Twist, max_linear_step_m_s: float, max_angular_step_rad_s: float) -> Twist:
    """One tick of an acceleration limit: `previous` moved toward `goal` by at most `max_linear_step_m_s`
    (linear norm) and `max_angular_step_rad_s` (angular norm), one factor for the whole change so the twist
    turns along the straight line between the two (the goal itself once it is within reach)."""
    if not (max_linear_step_m_s > 0.0 and max_angular_step_rad_s > 0.0):
        raise InvalidCommand(f"ramp steps {max_linear_step_m_s!r}, {max_angular_step_rad_s!r}: must be > 0")
    (a, b, c), (d, e, f) = previous.linear_m_s.tolist(), previous.angular_rad_s.tolist()
    (g, h, i), (j, k, m) = goal.linear_m_s.tolist(), goal.angular_rad_s.tolist()
    dl, da = (g - a, h - b, i - c), (j - d, k - e, m - f)
    scale = min(speed_scale(math.hypot(*dl), max_linear_step_m_s), speed_scale(math.hypot(*da), max_angular_step_rad_s))
    if scale == 1.0:
        return goal
    return Twist.of((a + scale * dl[0], b + scale * dl[1], c + scale * dl[2]),
                    (d + scale * da[0], e + scale * da[1], f + scale * da[2]))
