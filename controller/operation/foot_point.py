"""The foot operational points (`rfoot`, `lfoot`; [OP] II-A's leg): the summed twist integrated into the swing
sole's offset from its rest place in F, held inside the foot's reach and handed to the AutoBalancer, which owns
the legs and the balance (it brings the COM over the other foot first). A foot is held up while its point is
driven (a streamed setpoint, zero included, or a behaviour's twist) and put down when nothing drives it."""

from __future__ import annotations

import math
from dataclasses import dataclass

from controller.core.errors import InvalidCommand
from controller.core.types import FootCommand
from controller.operation.limits import BALANCING, REACH, VELOCITY, speed_scale
from controller.operation.points import Twist
from controller.walking.foot_lift import CLEARANCE_M

FEET = ("rfoot", "lfoot")
#: [m] the right sole's offset from its rest place in F: (lower, upper) per axis x, y, z (the left foot's y is
#: mirrored): 0.2 m forward is a walk's half stride; across, 3 cm inward at most (the soles 0.118 m apart at
#: their inner edges stay clear) and 0.15 m outward; up to 0.15 m, never lower than the lift's clearance: a sole
#: pressed onto the floor while lifted loads a foot the balance counts as in the air (soak seed 10712: the right
#: sole driven down 0.16 m out from its rest place, the robot tipped over the left sole's outer edge); releasing
#: the point puts it down over its rest place
RFOOT_REACH_M = ((-0.15, 0.20), (-0.15, 0.03), (CLEARANCE_M, 0.15))


@dataclass(frozen=True, slots=True)
class FootOffset:
    """A foot point's target or achieved pose: its sole's offset from the rest place, in F's axes [m]."""

    offset_m: tuple[float, float, float]


def reach_of(foot: str) -> tuple[tuple[float, float], ...]:
    """The offset's (lower, upper) bounds [m] per axis for `foot`."""
    (x, (ylo, yhi), z) = RFOOT_REACH_M
    return (x, (ylo, yhi) if foot == "rfoot" else (-yhi, -ylo), z)


def integrate_foot(foot: str, offset_m: tuple, twist: Twist, speed_m_s: float,
                   dt_s: float) -> tuple[tuple[float, float, float], str | None]:
    """One tick of the foot's linear velocity (F, [m/s]) at most `speed_m_s`, the result clamped into its reach;
    (the new offset [m], why it did less than asked: limits.VELOCITY, limits.REACH or None)."""
    v = twist.linear_m_s.tolist()
    scale = speed_scale(math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]), speed_m_s)
    moved = [o + scale * vi * dt_s for o, vi in zip(offset_m, v, strict=True)]
    clamped = tuple(min(hi, max(lo, m)) for m, (lo, hi) in zip(moved, reach_of(foot), strict=True))
    if clamped != tuple(moved):
        return clamped, REACH
    return clamped, VELOCITY if scale < 1.0 else None


class PointRefused(InvalidCommand):
    """A valid setpoint for a point that may not be driven now (the console acknowledges it as ignored: 'state')."""


def check_foot_allowed(point: str, twist: Twist, walking: bool, targets) -> None:
    """Raise PointRefused naming the point when a foot (or the walking point) may not be driven now: no foot
    while walking, one foot at a time, no walking while a foot is operated."""
    if point in FEET:
        if walking:
            raise PointRefused(f"{point}: refused while walking (the gait owns the feet); stop the walk first")
        other = FEET[1 - FEET.index(point)]
        if other in targets:
            raise PointRefused(f"{point}: the {other} is operated; one foot at a time (release it first)")
    elif point == "walk" and not twist.is_zero:
        lifted = [f for f in FEET if f in targets]
        if lifted:
            raise PointRefused(f"walk: refused while the {lifted[0]} is operated; release it (it is put down) "
                                 "first")


class FootPoints:
    """Per tick: the feet's targets (FootOffset in PointTargets.targets, so the release history keeps them)
    integrated from the summed twists, dropped when nothing drives them, and the command for the AutoBalancer."""

    @staticmethod
    def integrate(total: dict, points, speed_m_s: float, dt_s: float, gait) -> None:
        """`total` the summed twists, `points` the PointTargets, `gait` the AutoBalancer's last GaitState: a
        foot's target waits at its rest place (limited 'balancing') until the AutoBalancer has the COM over the
        other foot and the foot in the air (else the target would run ahead of the foot)."""
        targets, limited = points.targets, points.limited
        for foot in FEET:
            twist = total.get(foot)
            if twist is None:  # nothing drives it: put down
                if foot in targets:
                    del targets[foot]
                    points.achieved.pop(foot, None)
                    limited.pop(foot, None)
                continue
            start = targets.get(foot)
            if start is None:
                if twist.is_zero:
                    continue
                start = FootOffset((0.0, 0.0, 0.0))
            if gait is None or gait.foot_lift is None or gait.foot_lift[0] != foot or gait.support == "both":
                targets[foot], limited[foot] = start, BALANCING
                continue
            offset, limited[foot] = integrate_foot(foot, start.offset_m, twist, speed_m_s, dt_s)
            targets[foot] = FootOffset(offset)

    @staticmethod
    def command(targets: dict) -> FootCommand | None:
        """The operated foot's command (None: the feet stand)."""
        for foot in FEET:
            target = targets.get(foot)
            if target is not None:
                return FootCommand(foot, target.offset_m)
        return None

    @staticmethod
    def settle(points, gait, yaw_rad: float) -> None:
        """The achieved offsets from the AutoBalancer's gait port (its lifted sole, back in F's axes)."""
        lift = None if gait is None else gait.foot_lift
        for foot in FEET:
            if foot not in points.targets:
                continue
            if lift is None or lift[0] != foot:
                points.achieved[foot] = FootOffset((0.0, 0.0, 0.0))
                continue
            c, s = math.cos(yaw_rad), math.sin(yaw_rad)
            x, y, z = lift[1]
            points.achieved[foot] = FootOffset((c * x + s * y, -s * x + c * y, z))
