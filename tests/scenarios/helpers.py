"""Shared scenario set-up: a simulated HRP-2 with the controller chain, and HRP-2 poses."""

from __future__ import annotations

import mujoco
import numpy as np

from controller.core.system import ControllerSystem
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


def make_system(scene: str = "default", auto_balancer: bool = True) -> ControllerSystem:
    """The simulated robot with the chain; `auto_balancer=False` plays the plan on the joints as is
    (the hrpsys SequencePlayer and EmergencyStopper samples run that way)."""
    return ControllerSystem(MujocoPlant(scene), start_auto_balancer=auto_balancer)


def seq_call(system: ControllerSystem, method: str, *args):
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
