"""BODY in the feet frame F, and the targets and poses between F and BODY (unit)."""

import numpy as np

from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import rpy_to_matrix
from controller.operation.body_frame import BodyInFeet, achieved_pose, ik_targets
from controller.operation.targets import GazeAngles, HandPose
from controller.system import initial_reference
from robot.generate import half_sitting_deg

REF = initial_reference(RobotKinematics(), np.deg2rad(half_sitting_deg()))


def test_without_a_gait_F_is_the_references_own_soles_and_is_cached():
    frames = BodyInFeet()
    F, p_body, R_body = frames.of(REF, None)
    kin = RobotKinematics()
    kin.update_rpy(REF.base_pos_world, REF.base_rpy_rad, REF.q_rad)
    (pr, _), (pl, _) = kin.frame_pose("rleg_end"), kin.frame_pose("lleg_end")
    assert np.allclose(F.p, (pr + pl) / 2) and abs(F.yaw) < 1e-12
    assert np.allclose(p_body, REF.base_pos_world - F.p) and np.allclose(R_body, rpy_to_matrix(REF.base_rpy_rad))
    assert frames.reference_frame(REF) is F  # the same reference: not computed again


def test_a_hand_target_taken_to_BODY_and_back_is_itself_and_a_gaze_keeps_its_angles():
    R_body = rpy_to_matrix((0.05, -0.1, 0.3))
    p_body = [0.01, -0.02, 0.65]
    R_rows = R_body.tolist()
    hand = HandPose.of((0.35, -0.2, 0.9), rpy_to_matrix((0.2, 0.1, -0.4)))
    gaze = GazeAngles(0.3, -0.2)
    t = ik_targets({"rhand": hand, "head": gaze}, np.array((0.0, 0.0, 0.0)), p_body, R_rows)
    assert t.lhand is None and t.rhand is not None and t.head is not None
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = t.rhand.R_world, t.rhand.p_world
    back = achieved_pose("rhand", T, p_body, R_rows)
    assert np.allclose(back.p_feet_m, hand.p_feet_m) and np.allclose(back.R_feet_hand, hand.R_feet_hand)
    look = gaze.direction_feet()
    T_head = np.eye(4)
    T_head[:3, 0] = R_body.T @ look  # the head's x axis along the gaze, in BODY
    seen = achieved_pose("head", T_head, p_body, R_rows)
    assert np.allclose((seen.pitch_rad, seen.yaw_rad), (0.3, -0.2))
