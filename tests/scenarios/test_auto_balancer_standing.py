"""AutoBalancer while standing: the COG stays over the feet as the upper body moves or is loaded."""

import numpy as np

from robot.names import FORCE_SENSOR_NAMES
from tests.scenarios.helpers import make_system, pose_deg, seq_call, tilt_deg

ARMS_FORWARD = np.deg2rad(pose_deg(RARM_JOINT0=-90, LARM_JOINT0=-90, RARM_JOINT3=-10, LARM_JOINT3=-10))


def feet_mid_xy(system) -> np.ndarray:
    gait = system.chain["abc"].last_gait
    return 0.5 * (gait.p_rsole_world[:2] + gait.p_lsole_world[:2])


def test_arms_forward_keeps_the_simulated_com_over_the_feet_only_with_the_auto_balancer():
    # 1. with the AutoBalancer: arms forward over 2 s; BODY moves back, the COM stays over the feet
    system = make_system()
    system.loop.run_for(2.5)  # blended in
    mid = feet_mid_xy(system)
    seq_call(system, "set_joint_angles", ARMS_FORWARD, 2.0)
    snap = system.loop.run_for(3.0)
    assert np.linalg.norm(snap.truth.com_world[:2] - mid) < 0.005
    assert snap.truth.base_pos_world[0] < -0.03
    assert tilt_deg(snap.truth.base_quat_wxyz) < 1.0
    # 2. without it, the same motion moves the COM forward by centimetres
    plain = make_system(auto_balancer=False)
    plain.loop.run_for(0.5)
    seq_call(plain, "set_joint_angles", ARMS_FORWARD, 2.0)
    snap = plain.loop.run_for(3.0)
    assert snap.truth.com_world[0] - mid[0] > 0.03


def test_a_50_newton_downward_pull_at_one_hand_is_balanced_by_offsetting_the_cog():
    # hrpsys BalanceAgainstHandForce: the planned wrench tells the AutoBalancer (Eq. 6), the
    # simulation applies the real force at the right hand; the robot stays upright.
    system = make_system()
    loop = system.loop
    loop.run_for(2.5)
    mid = feet_mid_xy(system)
    reach = np.deg2rad(pose_deg(RARM_JOINT0=-80, RARM_JOINT3=-10))
    seq_call(system, "set_joint_angles", reach, 1.5)
    loop.run_for(2.0)
    wrenches = np.zeros((4, 6))
    wrenches[FORCE_SENSOR_NAMES.index("rhsensor"), 2] = -50.0
    seq_call(system, "set_wrenches", wrenches, 1.0)
    worst = 0.0
    for _ in range(5):  # the pull is held 5 s, renewed each second (push() lasts at most 5 s)
        loop.call(lambda: loop.plant.push("RARM_LINK6", np.array([0.0, 0.0, -50.0]), 1.0))
        for _ in range(200):
            snap = loop.step()
            worst = max(worst, tilt_deg(snap.truth.base_quat_wxyz))
    gait = system.chain["abc"].last_gait
    # the COG target moved backward (away from the pulled hand, which is in front) by centimetres,
    # so the measured ZMP stays near the middle of the feet (without Eq. 6 it sits ~6 cm forward)
    assert mid[0] - gait.cog_world[0] > 0.02
    assert abs(snap.zmp_world[0] - mid[0]) < 0.02
    assert worst < 5.0
    assert not snap.fallen
