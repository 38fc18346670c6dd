"""Fakes for behaviour unit tests: an operation layer that integrates the behaviours' twists into its view,
and a command interface that records what it was asked and moves joints like a perfect servo."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from behaviors.base import JointReading
from controller.core.errors import InvalidState
from controller.core.types import WalkCommand
from controller.operation.points import OperationView, PointPose, Twist


def _rot_z(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _exp(w: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(w))
    if angle < 1e-12:
        return np.eye(3)
    k = w / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


class FakeOp:
    """Integrates set_behavior's twists over one tick of `dt_s` when `tick()` is called (feet frame at the
    world origin unless moved)."""

    def __init__(self, dt_s: float = 0.005) -> None:
        self.dt_s = dt_s
        self.time_s = 0.0
        self.feet_p = np.zeros(3)
        self.feet_yaw = 0.0
        self.p = {"rhand": np.array([0.3, -0.25, 0.8]), "lhand": np.array([0.3, 0.25, 0.8]),
                  "head": np.array([0.0, 0.0, 1.4]), "waist": np.array([0.0, 0.0, 0.7])}
        self.R = {k: np.eye(3) for k in self.p}
        self.gaze = [0.0, 0.0]  # pitch, yaw
        self.walking = False
        self.motion_stopped = False
        self.collision_pairs: tuple[tuple[str, str], ...] = ()
        self.pending: tuple[dict[str, Twist], WalkCommand | None] = ({}, None)
        self.calls: list[tuple[dict[str, Twist], WalkCommand | None]] = []

    def set_behavior(self, twists: Mapping[str, Twist], walk: WalkCommand | None = None) -> None:
        self.pending = (dict(twists), walk)
        self.calls.append(self.pending)

    def tick(self) -> None:
        twists, _ = self.pending
        self.pending = ({}, None)
        dt = self.dt_s
        R_wf = _rot_z(self.feet_yaw)
        for point, tw in twists.items():
            if point in ("rhand", "lhand", "waist"):
                self.p[point] = self.p[point] + R_wf @ tw.linear_m_s * dt
                self.R[point] = _exp(R_wf @ tw.angular_rad_s * dt) @ self.R[point]
            if point == "head":
                self.gaze[0] += tw.angular_rad_s[1] * dt
                self.gaze[1] += tw.angular_rad_s[2] * dt
        self.time_s += dt

    def view(self) -> OperationView:
        R_wf = _rot_z(self.feet_yaw)
        points = {k: PointPose(self.p[k].copy(), self.R[k].copy(), R_wf.T @ (self.p[k] - self.feet_p),
                               R_wf.T @ self.R[k]) for k in self.p}
        return OperationView(time_s=self.time_s, feet_p_world_m=self.feet_p.copy(), feet_yaw_rad=self.feet_yaw,
                             points=points, gaze_rad=(self.gaze[0], self.gaze[1]),
                             waist_height_m=float(self.p["waist"][2] - self.feet_p[2]), walking=self.walking,
                             motion_stopped=self.motion_stopped, collision_pairs=self.collision_pairs)


class FakeCommands:
    """Records every command; joints follow their commands linearly over the given time (no load), or stop
    below `blocked` angles (an object in the jaws, closing = increasing angle);
    `refuse` makes every command raise InvalidState."""

    def __init__(self, op: FakeOp | None = None) -> None:
        self.op = op
        self.log: list[tuple] = []
        self.q: dict[str, float] = {}
        self.q_cmd: dict[str, float] = {}
        self.moves: dict[str, tuple[float, float, float, float]] = {}  # name -> (from, to, t0, duration)
        self.blocked: dict[str, float] = {}
        self.limits: dict[str, tuple[float, float]] = {}
        self.refuse: str | None = None
        self.now = 0.0
        self.walk_s = 0.0
        self.reset_time_s = 1.0  # [s] the operation layer's reset blend (its default reset_time_s)
        self.walk_gain = 1.0  # the fake's steps take the goal this many times (a real walk lands a little long)
        self.plan_version = 0  # the AutoBalancer's footstep list's version: each goPos, or a test's other walk

    def _check(self) -> None:
        if self.refuse:
            raise InvalidState(self.refuse)

    def advance(self, time_s: float) -> None:
        self.now = time_s
        for name, (q0, q1, t0, T) in self.moves.items():
            a = 1.0 if T <= 0 else min(1.0, max(0.0, (time_s - t0) / T))
            self.q_cmd[name] = q0 + (q1 - q0) * a
            q = self.q_cmd[name]
            if name in self.blocked:
                q = min(q, self.blocked[name])  # an object stops the closing (increasing) angle
            self.q[name] = q

    def go_pos(self, x_m: float, y_m: float, theta_rad: float) -> float:
        self._check()
        self.log.append(("go_pos", x_m, y_m, theta_rad))
        self.plan_version += 1
        if self.op is not None:  # the fake walks at once
            R = _rot_z(self.op.feet_yaw)
            self.op.feet_p = self.op.feet_p + R @ (self.walk_gain * np.array([x_m, y_m, 0.0]))
            self.op.feet_yaw += theta_rad
        return self.walk_s

    def walk_stop(self) -> None:
        self.log.append(("walk_stop",))

    def walk_plan_version(self) -> int:
        return self.plan_version

    def set_joint_angles(self, angles_rad: Mapping[str, float], time_s: float) -> None:
        self._check()
        self.log.append(("set_joint_angles", dict(angles_rad), time_s))
        for name, q in angles_rad.items():
            self.moves[name] = (self.q_cmd.get(name, self.q.get(name, 0.0)), q, self.now, time_s)

    def is_interpolating(self) -> bool:
        return any(self.now < t0 + T for _, _, t0, T in self.moves.values())

    def reset_operation_targets(self) -> float:
        self._check()
        self.log.append(("reset_operation_targets",))
        return self.reset_time_s

    def joint(self, name: str) -> JointReading:
        lo, hi = self.limits.get(name, (-math.pi, math.pi))
        return JointReading(self.q_cmd.get(name, self.q.get(name, 0.0)), self.q.get(name, 0.0), lo, hi)


class Harness:
    """A runner over the fakes, stepped tick by tick."""

    def __init__(self, runner, op: FakeOp, commands: FakeCommands) -> None:
        self.runner, self.op, self.commands = runner, op, commands

    def tick(self, n: int = 1) -> None:
        for _ in range(n):
            self.commands.advance(self.op.time_s)
            self.runner.step(self.op.time_s)
            self.op.tick()

    def run_until_done(self, run_id: int, timeout_s: float = 60.0):
        for _ in range(int(timeout_s / self.op.dt_s)):
            if self.runner.get(run_id).state != "running":
                break
            self.tick()
        return self.runner.get(run_id)


def harness(dt_s: float = 0.005, stops=None) -> Harness:
    """`stops`: the latched stops the runner sees (a callable, as the host's latched_stops), or None."""
    from behaviors.runner import BehaviorRunner

    op = FakeOp(dt_s)
    commands = FakeCommands(op)
    return Harness(BehaviorRunner(lambda: op, commands, dt_s, stops=stops), op, commands)
