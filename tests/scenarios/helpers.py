"""Shared scenario set-up: a simulated HRP-2 with the controller chain, and HRP-2 poses."""

from __future__ import annotations

import mujoco
import numpy as np

from app.service.local import LocalRobot
from robot.generate import half_sitting_deg
from robot.names import JOINT_NAMES, joint_index
from robot.plant import MujocoPlant

HALF_SITTING_DEG = np.array(half_sitting_deg(), dtype=float)


def pose_deg(**changes: float) -> np.ndarray:
    """Half-sitting with some joints changed, e.g. pose_deg(RARM_JOINT0=-60)."""
    q = HALF_SITTING_DEG.copy()
    for name, value in changes.items():
        q[joint_index(name)] = value
    return q


#: Arms forward and elbows bent, chest and head pitched: a posture that moves the COG but stays balanced.
MOVE_POSE_DEG = pose_deg(RARM_JOINT0=-50, RARM_JOINT3=-70, LARM_JOINT0=-50, LARM_JOINT3=-70,
                         CHEST_JOINT1=8, HEAD_JOINT1=15, HEAD_JOINT0=20)


class ObservedLoop:
    """The control loop as the scenarios drive it: step, run_for and run_until give Observations (the
    snapshot, and the simulator's ground truth beside it, which the controller never sees); `snapshot` is
    the latest Observation; everything else is the loop's own."""

    def __init__(self, robot: LocalRobot) -> None:
        self._robot = robot

    def step(self):
        return self._robot.step()

    def run_for(self, seconds: float):
        return self._robot.run_for(seconds)

    def run_until(self, predicate, timeout_s: float):
        return self._robot.run_until(predicate, timeout_s)

    @property
    def snapshot(self):
        return self._robot.host.observation

    def __getattr__(self, name: str):
        return getattr(self._robot.loop, name)


class SimulatedRobot:
    """The simulated HRP-2 with its chain (the robot host the console runs), for scenario tests."""

    def __init__(self, scene: str = "default", auto_balancer: bool = True) -> None:
        self.robot = LocalRobot(scene, start_auto_balancer=auto_balancer)
        self.loop = ObservedLoop(self.robot)

    @property
    def chain(self):
        return self.robot.chain

    @property
    def kin(self):
        return self.robot.kin

    @property
    def plant(self):
        return self.robot.plant


def make_system(scene: str = "default", auto_balancer: bool = True) -> SimulatedRobot:
    """The simulated robot with the chain; `auto_balancer=False` plays the plan on the joints as is
    (the hrpsys SequencePlayer and EmergencyStopper samples run that way)."""
    return SimulatedRobot(scene, auto_balancer)


def seq_call(system: SimulatedRobot, method: str, *args):
    """Call a SequencePlayer operation through the loop's command queue."""
    loop = system.loop
    return loop.call(lambda: getattr(loop.chain["seq"], method)(*args))


def tilt_deg(quat_wxyz: np.ndarray) -> float:
    """Angle between BODY's z axis and the vertical [deg]."""
    w, x, y, z = quat_wxyz
    return float(np.rad2deg(np.arccos(np.clip(1.0 - 2.0 * (x * x + y * y), -1.0, 1.0))))


def robot_contacts(plant: MujocoPlant, bodies_a: set[str], bodies_b: set[str]) -> list[tuple[str, str]]:
    """Active MuJoCo contacts between a body in set a and a body in set b."""
    m, d = plant.model, plant.data
    out = []
    for c in d.contact[: d.ncon]:
        b1 = m.body(m.geom_bodyid[c.geom1]).name
        b2 = m.body(m.geom_bodyid[c.geom2]).name
        if (b1 in bodies_a and b2 in bodies_b) or (b2 in bodies_a and b1 in bodies_b):
            out.append((b1, b2))
    return out


__all__ = ["HALF_SITTING_DEG", "JOINT_NAMES", "MOVE_POSE_DEG", "make_system", "mujoco", "pose_deg",
           "robot_contacts", "seq_call", "tilt_deg"]
