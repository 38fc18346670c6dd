"""The operation layer's status: per operational point its target, achieved pose, why it was limited and the
two twists summed (Eq. 5)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from controller.core.layer import Status, described, plain
from controller.operation.command_sum import CommandSum
from controller.operation.point_targets import PointTargets
from controller.operation.points import POINTS, ZERO_TWIST, Twist
from controller.operation.targets import status_layout
from controller.operation.walk_point import WalkPoint


@dataclass(frozen=True, slots=True)
class PointStatus:
    """One operational point in the status (all in the feet frame F)."""

    target: tuple[float, ...] | None = field(metadata=described(
        "target in F: hands (x, y, z [m], roll, pitch, yaw [rad]); head (pitch, yaw [rad]); waist (height [m], "
        "roll, pitch, yaw [rad]); walk (vx, vy [m/s], vtheta [rad/s]); feet (the sole's offset from its rest place "
        "x, y, z [m]); null: not operated"))
    achieved: tuple[float, ...] | None = field(metadata=described("the IK's pose, same layout as target"))
    limited: str | None = field(metadata=described(
        "why the point did less than asked: null, 'reach', 'joint_limit', 'velocity', 'motion_stop' or "
        "'balancing' (a foot)"))
    motion: tuple[float, ...] = field(metadata=described(
        "operator twist after the dead-man (vx, vy, vz [m/s], wx, wy, wz [rad/s]) in F"))
    behavior: tuple[float, ...] = field(metadata=described("the behaviours' summed twist, same layout"))
    deadman: str = field(default="stopped", metadata=described(
        "the operator's stream at this point under the dead-man: 'streaming' (its setpoint counts in full), "
        "'ramping' (older than deadman_timeout_s [s], fading to zero over deadman_ramp_s [s]) or 'stopped' "
        "(no streamed setpoint counts)"))


class BuildLater:
    """A value to be computed on first read (see BuiltWhenRead)."""

    __slots__ = ("build",)

    def __init__(self, build: Callable[[], Any]) -> None:
        self.build = build


class BuiltWhenRead:
    """A dataclass field set either to its value or to a BuildLater, which is called on the field's first read
    (and its value kept): readers only ever see the value. The field has no default."""

    def __set_name__(self, owner, name: str) -> None:
        self._key = f"_{name}_value"

    def __get__(self, obj, owner=None):
        if obj is None:
            raise AttributeError(self._key)  # (to dataclasses: no default)
        value = obj.__dict__[self._key]
        if type(value) is BuildLater:
            value = obj.__dict__[self._key] = value.build()
        return value

    def __set__(self, obj, value) -> None:
        obj.__dict__[self._key] = value


@dataclass(frozen=True)  # (no slots: `points` is a descriptor)
class OperationStatus(Status):
    active: bool = field(metadata=described("some point holds a target: the IK runs"))
    motion_stopped: bool = field(metadata=described("the EmergencyStopper holds the motion: nothing integrates"))
    #: built when first read: the loop takes every layer's status each tick for its snapshot, and most ticks
    #: nobody reads the operation's (the state is published at 50 Hz)
    points: dict[str, PointStatus] = field(default=BuiltWhenRead(),
                                           metadata=described("per operational point (POINTS order)"))

    def to_dict(self) -> dict:
        return {"enabled": self.enabled, "active": self.active, "motion_stopped": self.motion_stopped,
                "points": {name: plain(ps) for name, ps in self.points.items()}}


def _six(t: Twist) -> tuple[float, ...]:
    """(vx, vy, vz [m/s], wx, wy, wz [rad/s])."""
    return (*t.linear_m_s.tolist(), *t.angular_rad_s.tolist())


_ZERO_SIX = _six(ZERO_TWIST)


def _points_status(motion: dict, behavior: dict, targets: dict, achieved: dict, limited: dict, anchor: np.ndarray,
                   walk_target: tuple | None, ramping: frozenset[str]) -> dict[str, PointStatus]:
    pts = {}
    for point in POINTS:
        m = motion.get(point, ZERO_TWIST)
        b = behavior.get(point, ZERO_TWIST)
        if point == "walk":
            target, achieved_pose, why = walk_target, None, None
        else:
            target = status_layout(targets.get(point), anchor)
            achieved_pose = status_layout(achieved.get(point), anchor)
            why = limited.get(point) if point in targets else None
        pts[point] = PointStatus(target=target, achieved=achieved_pose, limited=why,
                                 motion=_ZERO_SIX if m is ZERO_TWIST else _six(m),
                                 behavior=_ZERO_SIX if b is ZERO_TWIST else _six(b),
                                 deadman=_deadman(point, motion, ramping))
    return pts


def _deadman(point: str, motion: dict, ramping: frozenset[str]) -> str:
    if point not in motion:  # (the last take's streamed twists: a faded-out setpoint is not in it)
        return "stopped"
    return "ramping" if point in ramping else "streaming"


def operation_status(enabled: bool, stopped: bool, commands: CommandSum, points: PointTargets,
                     walk: WalkPoint) -> OperationStatus:
    """The status of the layer's state after a tick; its points are built when first read, from copies of the
    state taken now (the targets' poses are immutable; the twists' dicts are replaced, never changed, by a take)."""
    captured = (commands.motion, commands.behavior, dict(points.targets), dict(points.achieved), dict(points.limited),
                points.anchor, walk.status_target(), commands.streamed.ramping)
    return OperationStatus(enabled=enabled, active=bool(points.targets), motion_stopped=stopped,
                           points=BuildLater(lambda: _points_status(*captured)))
