"""CollisionDetector at the layer level (a stand-in checker: one arm joint against one leg joint): it holds an arm
motion into a collision, and when the legs (which it lets through) move into the held arm, a free input brings it
out instead of a hold that never ends (soak seed 10192)."""

import numpy as np
import pytest

from controller.kinematics.model import RobotKinematics
from controller.layers.collision_detector import CollisionDetector, CollisionDetectorParams
from controller.system import initial_reference
from robot.names import JOINT_NAMES
from tests.controller.fakes import make_ctx

ARM, LEG = JOINT_NAMES.index("LARM_JOINT2"), JOINT_NAMES.index("LLEG_JOINT3")
PAIR = ("LLEG_LINK2", "LARM_LINK5")
DT = 0.005
REF = initial_reference(RobotKinematics(), np.zeros(len(JOINT_NAMES)))


class ArmAgainstThigh:
    """Collides when the arm joint is past 0.5 rad with the knee past 1.0 rad (the forearm on a raised thigh)."""

    def colliding_pairs(self, q_rad):
        return [PAIR] if q_rad[ARM] > 0.5 and q_rad[LEG] > 1.0 else []


def posture(arm_rad: float, leg_rad: float):
    q = np.zeros(len(JOINT_NAMES))
    q[ARM], q[LEG] = arm_rad, leg_rad
    return REF.with_(q_rad=q)


def run(co, ref, seconds: float, t0: float):
    out = None
    for k in range(int(round(seconds / DT))):
        out = co.tick(make_ctx(t=t0 + k * DT, tick=k), ref)
    return out


def held_arm_after_a_squat(recover_s: float = 0.5) -> CollisionDetector:
    co = CollisionDetector(np.zeros(len(JOINT_NAMES)), CollisionDetectorParams(recover_time_s=recover_s),
                           checker=ArmAgainstThigh())
    run(co, posture(0.8, 0.5), 0.1, 0.0)  # the arm out, the knee bent a little: free
    out = run(co, posture(0.8, 1.2), 0.5, 0.1)  # a squat raises the thigh into the held arm
    assert co.in_collision and out.q_rad[ARM] == pytest.approx(0.8) and out.q_rad[LEG] == pytest.approx(1.2)
    return co


def test_an_arm_motion_into_a_collision_never_passes_the_last_free_posture():
    co = CollisionDetector(np.zeros(len(JOINT_NAMES)), checker=ArmAgainstThigh())
    run(co, posture(0.0, 1.2), 0.1, 0.0)
    arm = [co.tick(make_ctx(t=0.1 + k * DT, tick=k), posture(0.9, 1.2)).q_rad[ARM] for k in range(400)]
    assert co.collision_ticks > 0 and max(arm) <= 0.5  # it creeps up to the contact and stays there
    assert arm[-1] == pytest.approx(0.5, abs=0.01)


def test_with_the_legs_moved_into_the_held_arm_a_free_input_brings_it_out():
    co = held_arm_after_a_squat(recover_s=0.5)
    out = run(co, posture(0.0, 1.2), 0.6, 0.6)  # the arm asked back out (stand's half-sitting)
    assert not co.in_collision and out.q_rad[ARM] == pytest.approx(0.0)


@pytest.mark.parametrize("arm_rad", [0.8, 0.9])
def test_with_the_legs_moved_into_the_held_arm_an_input_still_colliding_keeps_it_held(arm_rad):
    co = held_arm_after_a_squat()
    out = run(co, posture(arm_rad, 1.2), 1.0, 0.6)
    assert co.in_collision and out.q_rad[ARM] == pytest.approx(0.8)
