"""RobotKinematics: limb_ik reaches a reachable target; an unreachable one raises, or in best-effort mode
returns the closest posture it found; the joint below each force sensor carries the mass below it."""

import numpy as np
import pytest

from controller.core.errors import InvalidCommand
from controller.kinematics.model import RobotKinematics
from robot.generate import half_sitting_deg

HALF = np.deg2rad(half_sitting_deg())
BASE = np.array([0.0, 0.0, 0.648702])


def hand(kin, q):
    kin.update_rpy(BASE, np.zeros(3), q)
    return kin.frame_pose("rarm_end")


def test_a_reachable_target_is_reached():
    kin = RobotKinematics()
    p0, R0 = hand(kin, HALF)
    q = kin.limb_ik("rarm", HALF, BASE, np.zeros(3), p0 + [0.05, 0.0, 0.05], R0)
    assert np.linalg.norm(hand(kin, q)[0] - (p0 + [0.05, 0.0, 0.05])) < 1e-4


def test_an_unreachable_target_raises_or_gives_the_closest_posture_in_best_effort_mode():
    kin = RobotKinematics()
    forward = HALF.copy()
    forward[16], forward[19] = np.deg2rad(-70), np.deg2rad(-40)  # right arm forward, elbow bent
    p0, R0 = hand(kin, forward)
    far = p0 + np.array([0.25, 0.0, 0.0])  # beyond the stretched arm (the ImpedanceController's case)
    with pytest.raises(InvalidCommand, match="cannot reach"):
        kin.limb_ik("rarm", forward, BASE, np.zeros(3), far, R0)
    q = kin.limb_ik("rarm", forward, BASE, np.zeros(3), far, R0, best_effort=True)
    assert np.all(q >= kin.q_lower - 1e-12) and np.all(q <= kin.q_upper + 1e-12)
    closer = np.linalg.norm(hand(kin, q)[0] - far)
    assert closer < np.linalg.norm(p0 - far) - 0.02  # closer than where it started (the last iterate need not be)
    assert np.array_equal(np.delete(q, range(16, 23)), np.delete(forward, range(16, 23)))  # only the arm moved


def test_the_joint_below_a_sensor_carries_the_mass_below_it():
    from robot.names import FORCE_SENSOR_NAMES

    kin = RobotKinematics()
    kin.update_rpy(BASE, np.zeros(3), HALF)
    for sensor in FORCE_SENSOR_NAMES:
        mass, com = kin.mass_below(sensor)
        j = kin.joint_below(sensor)
        M = kin.data.oMi[j]  # pinocchio's subtree COM is in the joint's frame; mass_below gives it in the world
        assert mass > 0.0 and float(kin.data.mass[j]) == mass
        np.testing.assert_allclose(com, M.rotation @ kin.data.com[j] + M.translation, atol=1e-12)


def test_the_configuration_quaternion_is_pinocchios_for_every_rotation_also_when_kept():
    import pinocchio as pin

    from controller.kinematics.rotations import rpy_to_matrix

    kin = RobotKinematics()
    for rpy in ((0.0, 0.0, 0.0), (0.1, -0.2, 0.3), (0.1, -0.2, 0.3), (0.0, 0.0, 3.0), (0.0, 0.0, 0.0)):
        R = rpy_to_matrix(np.array(rpy))
        q = kin.configuration((0.1, 0.2, 0.6), R, HALF)
        assert np.array_equal(q[3:7], pin.Quaternion(R).coeffs())  # bit for bit, kept or converted
        assert np.array_equal(q[kin.idx_q], HALF)
    ints = kin.configuration((0.0, 0.0, 0.0), np.eye(3, dtype=int), HALF)  # another dtype: converted, not kept
    assert np.array_equal(ints[3:7], [0.0, 0.0, 0.0, 1.0])
