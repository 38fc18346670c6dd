"""The behaviours' command interface (behaviors.base.Commands) as the robot host implements it: every
command is one of the operator service's own verbs applied through RobotHost.apply, so a behaviour is
refused exactly when the operator would be (e-stop, motion stop, a fall, the CollisionDetector)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from app.service.verbs import GetFootsteps, GoPos, ResetOperationTargets, SequenceStatus, SetSomeJointAngles, WalkStop
from behaviors.base import JointReading
from robot.names import joint_index

if TYPE_CHECKING:
    from app.service.host import RobotHost


class HostCommands:
    """behaviors.base.Commands over a RobotHost (called inside the loop, at a tick boundary)."""

    def __init__(self, host: RobotHost) -> None:
        self.host = host

    def go_pos(self, x_m: float, y_m: float, theta_rad: float) -> float:
        self.host.apply(GoPos(x_m, y_m, theta_rad))
        _, footsteps = self.host.apply(GetFootsteps())
        return float(sum(f.step_time_s for f in footsteps))

    def walk_stop(self) -> None:
        self.host.apply(WalkStop())

    def set_joint_angles(self, angles_rad: Mapping[str, float], time_s: float) -> None:
        verb = SetSomeJointAngles(tuple((n, float(v)) for n, v in angles_rad.items()), float(time_s))
        verb.check(self.host.cached_info())
        self.host.apply(verb)

    def is_interpolating(self) -> bool:
        return bool(self.host.apply(SequenceStatus()))

    def reset_operation_targets(self) -> None:
        self.host.apply(ResetOperationTargets())

    def joint(self, name: str) -> JointReading:
        i = joint_index(name)
        snap = self.host.loop.snapshot
        kin = self.host.system.kin
        return JointReading(float(snap.q_cmd_rad[i]), float(snap.q_meas_rad[i]), float(kin.q_lower[i]),
                            float(kin.q_upper[i]))
