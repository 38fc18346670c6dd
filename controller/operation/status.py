"""The operation layer's status: per operational point its target, achieved pose, why it was limited and the
two twists summed (Eq. 5)."""

from __future__ import annotations

from dataclasses import dataclass, field

from controller.core.layer import Status, described, plain
from controller.operation.command_sum import CommandSum
from controller.operation.point_targets import PointTargets
from controller.operation.points import POINTS, ZERO_TWIST, Twist
from controller.operation.walk_point import WalkPoint


@dataclass(frozen=True, slots=True)
class PointStatus:
    """One operational point in the status (all in the feet frame F)."""

    target: tuple[float, ...] | None = field(metadata=described(
        "target in F: hands (x, y, z [m], roll, pitch, yaw [rad]); head (pitch, yaw [rad]); waist (height [m], "
        "roll, pitch, yaw [rad]); walk (vx, vy [m/s], vtheta [rad/s]); null: not operated"))
    achieved: tuple[float, ...] | None = field(metadata=described("the IK's pose, same layout as target"))
    limited: str | None = field(metadata=described(
        "why the point did less than asked: null, 'reach', 'joint_limit', 'velocity' or 'motion_stop'"))
    motion: tuple[float, ...] = field(metadata=described(
        "operator twist after the dead-man (vx, vy, vz [m/s], wx, wy, wz [rad/s]) in F"))
    behavior: tuple[float, ...] = field(metadata=described("the behaviours' summed twist, same layout"))


@dataclass(frozen=True, slots=True)
class OperationStatus(Status):
    active: bool = field(metadata=described("some point holds a target: the IK runs"))
    motion_stopped: bool = field(metadata=described("the EmergencyStopper holds the motion: nothing integrates"))
    points: dict[str, PointStatus] = field(metadata=described("per operational point (POINTS order)"))

    def to_dict(self) -> dict:
        return {"enabled": self.enabled, "active": self.active, "motion_stopped": self.motion_stopped,
                "points": {name: plain(ps) for name, ps in self.points.items()}}


def _six(t: Twist) -> tuple[float, ...]:
    """(vx, vy, vz [m/s], wx, wy, wz [rad/s])."""
    return (*t.linear_m_s.tolist(), *t.angular_rad_s.tolist())


_ZERO_SIX = _six(ZERO_TWIST)


def operation_status(enabled: bool, stopped: bool, commands: CommandSum, points: PointTargets,
                     walk: WalkPoint) -> OperationStatus:
    """The status of the layer's state after a tick."""
    pts = {}
    for point in POINTS:
        motion = commands.motion.get(point, ZERO_TWIST)
        behavior = commands.behavior.get(point, ZERO_TWIST)
        if point == "walk":
            target, achieved, limited = walk.status_target(), None, None
        else:
            target, achieved, limited = points.status_of(point)
        pts[point] = PointStatus(target=target, achieved=achieved, limited=limited,
                                 motion=_ZERO_SIX if motion is ZERO_TWIST else _six(motion),
                                 behavior=_ZERO_SIX if behavior is ZERO_TWIST else _six(behavior))
    return OperationStatus(enabled=enabled, active=bool(points.targets), motion_stopped=stopped, points=pts)
