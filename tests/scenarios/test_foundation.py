"""Foundation scenarios in simulation: standing with the chain, sensing, e-stop, self-collision, tracking."""

import numpy as np
import pytest

from robot.names import FORCE_SENSOR_NAMES, JOINT_GROUPS, joint_index
from tests.scenarios.helpers import (
    HALF_SITTING_DEG,
    MOVE_POSE_DEG,
    make_system,
    pose_deg,
    robot_contacts,
    seq_call,
    tilt_deg,
)

G = 9.80665


def test_standing_with_the_chain_the_estimates_match_the_simulation():
    # 1. start in half-sitting, the chain running, nothing commanded, for 5 s
    system = make_system()
    snap = system.loop.run_for(5.0)
    truth = snap.truth
    # 2. the robot stands
    assert not snap.fallen and snap.fault is None
    assert tilt_deg(truth.base_quat_wxyz) < 1.0
    # 3. KalmanFilter attitude agrees with the simulated BODY attitude
    w, x, y, z = truth.base_quat_wxyz
    roll_true = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch_true = np.arcsin(np.clip(2 * (w * y - z * x), -1, 1))
    assert abs(np.rad2deg(snap.base_rpy_est_rad[0] - roll_true)) < 0.2
    assert abs(np.rad2deg(snap.base_rpy_est_rad[1] - pitch_true)) < 0.2
    # 4. RemoveForceOffset: the feet carry the whole 58 kg, the hands nothing
    fz = snap.wrenches_ext[:, 2]
    feet = [FORCE_SENSOR_NAMES.index("rfsensor"), FORCE_SENSOR_NAMES.index("lfsensor")]
    hands = [FORCE_SENSOR_NAMES.index("rhsensor"), FORCE_SENSOR_NAMES.index("lhsensor")]
    assert abs(fz[feet].sum() - 58.0 * G) < 0.02 * 58.0 * G
    assert np.all(np.abs(snap.wrenches_ext[hands, :3]) < 1.0)
    # 5. the estimated COG is the simulated COM within 1 cm; the ZMP lies under it (static)
    assert np.linalg.norm(snap.cog_world[:2] - truth.com_world[:2]) < 0.01
    assert np.linalg.norm(snap.zmp_world[:2] - snap.cog_world[:2]) < 0.015


def test_sequence_motion_is_tracked_by_the_simulated_joints():
    # 1. play the move pose over 2 s, then settle 1 s (plan played as is: no AutoBalancer)
    system = make_system(auto_balancer=False)
    seq_call(system, "set_joint_angles", np.deg2rad(MOVE_POSE_DEG), 2.0)
    snap = system.loop.run_for(3.0)
    # 2. the reference is exactly the target; the joints follow within 0.5 deg
    assert np.allclose(snap.q_seq_rad, np.deg2rad(MOVE_POSE_DEG), atol=1e-7)
    assert np.max(np.abs(np.rad2deg(snap.q_meas_rad - snap.q_cmd_rad))) < 0.5
    assert np.max(np.abs(np.rad2deg(snap.q_meas_rad) - MOVE_POSE_DEG)) < 0.5
    # 3. a group motion (left arm) overrides only that group, then back to half-sitting
    larm = list(JOINT_GROUPS["larm"])
    target = np.deg2rad(pose_deg(LARM_JOINT3=-100.0))[larm]
    seq_call(system, "set_joint_angles_of_group", "larm", target, 1.0)
    snap = system.loop.run_for(1.5)
    assert np.allclose(snap.q_seq_rad[larm], target, atol=1e-7)
    assert np.allclose(snap.q_seq_rad[joint_index("RARM_JOINT0")], np.deg2rad(-50.0), atol=1e-7)
    assert np.max(np.abs(snap.q_meas_rad[larm] - target)) < np.deg2rad(0.5)
    seq_call(system, "set_joint_angles", np.deg2rad(HALF_SITTING_DEG), 2.0)
    snap = system.loop.run_for(3.0)
    assert np.max(np.abs(np.rad2deg(snap.q_meas_rad) - HALF_SITTING_DEG)) < 0.5
    assert not snap.fallen


def test_hard_estop_freezes_a_playing_motion_holds_the_plan_and_release_stays_where_the_robot_is():
    # hrpsys-notes 3.1 demoEmergencyStopJointAngle, with this console's semantics: everything upstream of the
    # hard e-stop holds too, so release blends to where the robot is and nothing sent before runs after it
    system = make_system(auto_balancer=False)
    loop = system.loop
    target = np.deg2rad(MOVE_POSE_DEG)
    # 1. a 10 s setJointAngles; after 4 s the pose has changed
    seq_call(system, "set_joint_angles", target, 10.0)
    first = loop.run_for(4.0).q_cmd_rad.copy()
    assert np.max(np.abs(first - np.deg2rad(HALF_SITTING_DEG))) > np.deg2rad(5.0)
    # 2. e-stop: the command does not move over 3 s, and neither does the plan behind it
    loop.call(lambda: loop.safe_stop("operator"))
    loop.run_for(0.1)
    a = loop.snapshot.q_cmd_rad.copy()
    commands = [loop.step().q_cmd_rad for _ in range(600)]
    assert loop.snapshot.safety.hard_stop is True
    assert np.max(np.abs(np.array(commands) - a)) < 1e-6
    one_tick = np.max(np.abs(target - np.deg2rad(HALF_SITTING_DEG))) / 10.0 * 0.005 * 1.9  # max min-jerk speed
    assert np.max(np.abs(loop.snapshot.q_seq_rad - a)) < one_tick  # the plan stopped (one tick after)
    assert not loop.snapshot.layers["seq"].interpolating
    # 3. release: the command blends to the held plan and the robot stays there
    loop.call(lambda: loop.chain["hes"].release())

    def settled(s):
        return not s.layers["hes"].recovering and not s.layers["seq"].interpolating

    loop.run_until(settled, timeout_s=10.0)
    snap = loop.run_for(2.0)
    assert np.max(np.abs(snap.q_cmd_rad - a)) < one_tick
    assert np.max(np.abs(snap.q_meas_rad - a)) < np.deg2rad(0.5)
    # 4. the command never jumped on release (velocity limit never hit); a new motion then goes through
    assert snap.layers["el"].limited_ticks == 0
    seq_call(system, "set_joint_angles", target, 3.0)
    snap = loop.run_for(3.5)
    assert np.allclose(snap.q_cmd_rad, target, atol=1e-7)
    assert not snap.fallen


def test_collision_detector_stops_an_arm_motion_through_the_torso():
    # the right forearm swung inward across the chest: RARM_JOINT2 turns the elbow axis, the elbow flexes
    system = make_system()
    loop = system.loop
    arm = {f"RARM_LINK{i}" for i in range(7)}
    torso = {"BODY", "CHEST_LINK0", "CHEST_LINK1"}
    target = np.deg2rad(pose_deg(RARM_JOINT0=-20, RARM_JOINT1=0, RARM_JOINT2=80, RARM_JOINT3=-120))
    seq_call(system, "set_joint_angles", target, 3.0)
    hits, contacts, shown, prev_pairs = 0, [], 0, ()
    for _ in range(int(4.0 / loop.dt_control_s)):
        snap = loop.step()
        hits += snap.layers["co"].collision
        contacts += robot_contacts(system.loop.plant, arm, torso)
        # the hold reaches the behaviours' view on the next tick, with the pairs the status names
        view_pairs = loop.chain["op"].view().collision_pairs
        if view_pairs:
            shown += 1
            assert set(view_pairs) <= {tuple(p) for p in prev_pairs}
        prev_pairs = snap.layers["co"].pairs
    # 1. the planned motion would go through the torso; the detector held the arm, and said so to behaviours
    assert hits > 0
    assert shown >= hits - 1
    assert np.max(np.abs(snap.q_cmd_rad - target)) > np.deg2rad(5.0)
    # 2. MuJoCo saw no arm-torso contact at any physics tick we sampled
    assert contacts == []
    assert not snap.fallen


@pytest.mark.slow
def test_standing_thirty_seconds_with_the_chain_does_not_drift():
    system = make_system()
    start = system.loop.snapshot.truth.base_pos_world.copy()
    worst_tilt = 0.0
    for _ in range(30):
        snap = system.loop.run_for(1.0)
        worst_tilt = max(worst_tilt, tilt_deg(snap.truth.base_quat_wxyz))
    assert worst_tilt < 1.0
    assert np.linalg.norm(snap.truth.base_pos_world[:2] - start[:2]) < 0.005


def test_set_target_pose_reaches_the_joint_angles_that_produced_the_pose():
    # hrpsys-notes 3.5 case 11: read LARM's end pose at two elbow angles, command those poses back
    from controller.kinematics.model import RobotKinematics
    from controller.kinematics.rotations import matrix_to_rpy

    system = make_system()
    loop = system.loop
    kin = RobotKinematics()
    larm = list(JOINT_GROUPS["larm"])
    ref = loop.snapshot.reference
    for elbow_deg in (-90.0, -45.0):
        q_goal = np.deg2rad(pose_deg(LARM_JOINT3=elbow_deg))
        kin.update_rpy(ref.base_pos_world, ref.base_rpy_rad, q_goal)
        body_pos, body_R = kin.frame_pose("BODY")
        pos, R = kin.frame_pose("larm_end")
        pos_in_body = body_R.T @ (pos - body_pos)
        rpy_in_body = matrix_to_rpy(body_R.T @ R)
        seq_call(system, "set_target_pose", "larm:BODY", pos_in_body, rpy_in_body, 2.0)
        snap = loop.run_for(2.5)
        assert np.max(np.abs(snap.q_seq_rad[larm] - q_goal[larm])) < 0.01
        assert np.max(np.abs(snap.q_meas_rad[larm] - q_goal[larm])) < 0.01
    assert not snap.fallen
