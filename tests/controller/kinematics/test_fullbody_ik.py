"""Whole-body IK: COG on target, soles on target, upper body untouched."""

import numpy as np

from controller.kinematics.fullbody_ik import FullbodyIK
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import rpy_to_matrix
from robot.generate import half_sitting_deg

HALF = np.deg2rad(half_sitting_deg())


def soles(kin, base, R, q):
    kin.update(base, R, q)
    return kin.frame_pose("rleg_end"), kin.frame_pose("lleg_end")


def test_cog_and_soles_reach_their_targets_and_the_arms_keep_their_angles():
    kin = RobotKinematics()
    ik = FullbodyIK(RobotKinematics())
    rs, ls = soles(kin, np.array([0, 0, 0.648702]), np.eye(3), HALF)
    q_upper = HALF.copy()
    q_upper[16] = np.deg2rad(-60)  # right arm forward: the COG moves, the base must compensate
    for target in ([0.0, 0.0], [0.03, -0.05], [-0.02, 0.08]):
        res = ik.solve(q_upper, 0.62, rpy_to_matrix([0, 0.05, 0]), np.array(target), rs, ls)
        assert res.reachable
        assert np.linalg.norm(res.com_world[:2] - target) < 1e-4
        (pr, Rr), (pl, Rl) = soles(kin, res.base_pos_world, rpy_to_matrix([0, 0.05, 0]), res.q_rad)
        assert np.linalg.norm(pr - rs[0]) < 1e-9 and np.linalg.norm(pl - ls[0]) < 1e-9
        assert np.linalg.norm(Rr - rs[1]) < 1e-9
        assert np.array_equal(res.q_rad[12:], q_upper[12:])
        assert abs(res.base_pos_world[2] - 0.62) < 1e-12


def test_warm_started_solve_converges_in_one_or_two_iterations():
    ik = FullbodyIK(RobotKinematics())
    rs, ls = soles(RobotKinematics(), np.array([0, 0, 0.648702]), np.eye(3), HALF)
    ik.solve(HALF, 0.64, np.eye(3), np.array([0.0, 0.0]), rs, ls)
    iters = []
    for k in range(100):
        res = ik.solve(HALF, 0.64, np.eye(3), np.array([0.0, 0.04 * np.sin(0.05 * k)]), rs, ls)
        iters.append(res.iterations)
    assert max(iters) <= 3


def test_the_leg_joint_nearest_its_limit_is_found_and_a_margin_checked():
    from controller.kinematics.fullbody_ik import legs_within_limits, nearest_leg_limit
    from robot.names import JOINT_NAMES

    kin = RobotKinematics()
    lo, hi = kin.q_lower.tolist(), kin.q_upper.tolist()
    q = HALF.copy()
    i = JOINT_NAMES.index("LLEG_JOINT1")
    q[i] = hi[i] - np.deg2rad(2.0)  # the hip roll 2 deg from its upper limit
    q[0] = lo[0] - 1.0  # RLEG_JOINT0 past its lower limit by 1 rad
    j, margin = nearest_leg_limit(q, lo, hi)
    assert JOINT_NAMES[j] == "RLEG_JOINT0" and np.isclose(margin, -1.0)
    q[0] = HALF[0]
    j, margin = nearest_leg_limit(q, lo, hi)
    assert JOINT_NAMES[j] == "LLEG_JOINT1" and np.isclose(np.rad2deg(margin), 2.0)
    assert legs_within_limits(q, lo, hi, np.deg2rad(1.9)) and not legs_within_limits(q, lo, hi, np.deg2rad(2.1))
    q[i] = hi[i] + 0.5
    assert not legs_within_limits(q, lo, hi, 0.0)
    q[i] = HALF[i]
    k = JOINT_NAMES.index("RARM_JOINT0")
    q[k] = hi[k] + 0.5  # an arm joint past its limit is not the legs' business
    assert legs_within_limits(q, lo, hi, np.deg2rad(5.0))
