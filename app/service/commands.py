"""The behaviours' command interface (behaviors.base.Commands) as the robot host implements it: every
command is one of the operator service's own verbs applied through RobotHost.apply, so a behaviour is
refused exactly when the operator would be (e-stop, motion stop, a fall, the CollisionDetector)."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

import numpy as np

from app.service.errors import InvalidArgument, Refused
from app.service.verbs import (
    CloseStance,
    GetFootsteps,
    GoPos,
    Host,
    ResetOperationTargets,
    SequenceStatus,
    SetSomeJointAngles,
    Verb,
    WalkStop,
)
from behaviors.base import Capture, JointReading
from behaviors.preview import PlannedStep
from controller.balance.leg_odometry import control_to_world, world_to_control
from controller.walking.close_stance import closing_duration_s
from controller.walking.footsteps import Footstep
from controller.walking.footsteps import go_pos as plan_go_pos_footsteps
from robot.names import FORCE_SENSOR_NAMES, joint_index


class HostCommands:
    """behaviors.base.Commands over the robot host (a verbs.Host; called inside the loop, at a tick boundary). A
    command the behaviour computed that a verb finds invalid (a goal beyond goPos's 5 m) is refused (409, reason
    "state"): the request that started the behaviour was valid."""

    def __init__(self, host: Host) -> None:
        self.host = host

    def _apply(self, verb: Verb) -> Any:
        try:
            return self.host.apply(verb)
        except InvalidArgument as exc:
            raise Refused("state", f"the behaviour's {verb.name} was refused: {exc}") from None

    def go_pos(self, x_m: float, y_m: float, theta_rad: float) -> float:
        try:
            verb = GoPos(x_m, y_m, theta_rad)
        except InvalidArgument as exc:
            raise Refused("state", f"the behaviour's go_pos was refused: {exc}") from None
        self._apply(verb)
        _, footsteps = self._apply(GetFootsteps())
        return float(sum(f.step_time_s for f in footsteps))

    def plan_go_pos(self, x_m: float, y_m: float, theta_rad: float, soles: tuple | None = None
                    ) -> list[PlannedStep]:
        """The footsteps the AutoBalancer's goPos (its gait generator's planner, its footstep parameters and
        stride limits) would walk from standing, in the world of leg odometry, without walking."""
        gait = self.host.layer("abc").gait
        wfc = self.host.world_from_control() or (0.0, 0.0, 0.0, 0.0)
        if soles is None:
            T_r, T_l = gait.T_world_rfoot, gait.T_world_lfoot
        else:
            z = float(gait.T_world_rfoot[2, 3])
            T_r, T_l = (Footstep(leg, *world_to_control(wfc, (s.x_m, s.y_m, 0.0))[:2], z, s.yaw_rad - wfc[3]
                                 ).T_world_foot for leg, s in zip(("rleg", "lleg"), soles, strict=True))
        steps = plan_go_pos_footsteps(T_r, T_l, x_m, y_m, theta_rad, gait.footstep_params, gait.stride_limits)
        return [PlannedStep("right" if f.leg == "rleg" else "left", *control_to_world(wfc, (f.x, f.y, f.z))[:2],
                            f.yaw + wfc[3]) for f in steps]

    def walk_stop(self) -> None:
        self._apply(WalkStop())

    def walk_plan_version(self) -> int:
        return int(self.host.layer("abc").gait.plan_version)

    def close_stance(self) -> float:
        self._apply(CloseStance())
        return closing_duration_s(self.host.layer("abc").gait.params)

    def set_joint_angles(self, angles_rad: Mapping[str, float], time_s: float) -> None:
        try:
            verb = SetSomeJointAngles(tuple((n, float(v)) for n, v in angles_rad.items()), float(time_s))
            verb.check(self.host.cached_info())
        except InvalidArgument as exc:
            raise Refused("state", f"the behaviour's set_some_joint_angles was refused: {exc}") from None
        self._apply(verb)

    def is_interpolating(self) -> bool:
        return bool(self._apply(SequenceStatus()))

    def reset_operation_targets(self) -> float:
        self._apply(ResetOperationTargets())
        return float(self.host.layer("op").last_reset_s)  # the blend's own time (longer for a large offset)

    def joint(self, name: str) -> JointReading:
        i = joint_index(name)
        snap = self.host.loop.snapshot
        kin = self.host.system.kin
        return JointReading(float(snap.q_cmd_rad[i]), float(snap.q_meas_rad[i]), float(kin.q_lower[i]),
                            float(kin.q_upper[i]))

    def wrench(self, sensor: str) -> np.ndarray:
        if sensor not in FORCE_SENSOR_NAMES:
            raise Refused("state", f"unknown force sensor {sensor!r}; valid: {list(FORCE_SENSOR_NAMES)}")
        return np.array(self.host.loop.snapshot.wrenches_ext[FORCE_SENSOR_NAMES.index(sensor)])

    def capture(self, camera: str, analyse: tuple | None = None) -> Capture:
        host = self.host
        snap = host.loop.snapshot
        time_s, q, rpy, odometry = float(snap.time_s), snap.q_meas_rad, snap.base_rpy_est_rad, snap.odometry
        if odometry is None:  # no state estimator ran (a chain without one): no place in the world to see from
            raise Refused("state", "the robot has no estimate of its place in the world (no state estimator ran)")
        if analyse is not None:  # run where the image is rendered, with what the robot knew of itself now
            fn, args = analyse
            analyse = (fn, (camera, time_s, q, rpy, odometry, *args))
        frames = host.cameras().request_state_of(host.plant.data, cameras=(camera,), analyse=analyse)
        host.captures += 1
        return Capture(camera=camera, frames=frames, time_s=time_s, q_meas_rad=q, base_rpy_est_rad=rpy,
                       odometry=odometry, ready=functools.partial(host.capture_ready, host.captures, frames))

    def remember(self, object_name: str, recognition: Mapping[str, Any]) -> None:
        self.host.recognitions[object_name] = dict(recognition)

    def recalled(self, object_name: str) -> Mapping[str, Any] | None:
        return self.host.recognitions.get(object_name)
