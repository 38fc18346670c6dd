"""The one limb IK: the damped least-squares step, the two task kinds (their errors and Jacobians against finite
differences) and the solver on the model (pose and point-axis targets, posture, step limit, joint limits)."""

import math

import numpy as np
import pinocchio as pin
import pytest

from controller.kinematics.limb_ik import (
    LimbIkParams,
    PointAxisTarget,
    PoseTarget,
    damped_least_squares_step_rad,
    point_axis_task_world,
    pose_error_local,
    solve_limb_ik,
)
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import rpy_to_matrix
from robot.generate import half_sitting_deg
from robot.names import JOINT_GROUPS

KIN = RobotKinematics()
HALF = np.deg2rad(half_sitting_deg())
BASE = np.array([0.0, 0.0, 0.648702])
ARM = np.array(JOINT_GROUPS["larm"][:6])
FID = KIN.frame_ids["larm_end"]
#: a bent left arm, away from the joint limits and singularities
BENT = HALF.copy()
BENT[ARM] = np.radians((-30.0, 20.0, 10.0, -70.0, 20.0, -20.0))


def hand(q, base_R=None):
    KIN.update(BASE, np.eye(3) if base_R is None else base_R, q)
    return KIN.frame_pose("larm_end")


# ---- the step --------------------------------------------------------------------------------------------
def test_the_step_solves_a_square_task_exactly_without_damping_and_shorter_with_it():
    rng = np.random.default_rng(0)
    J = rng.normal(size=(6, 6))
    e = rng.normal(size=6)
    np.testing.assert_allclose(J @ damped_least_squares_step_rad(J, e, 0.0), e, atol=1e-9)
    damped = damped_least_squares_step_rad(J, e, 0.1)
    assert np.linalg.norm(damped) < np.linalg.norm(np.linalg.solve(J, e))


def test_the_posture_step_stays_in_the_null_space_of_the_task():
    rng = np.random.default_rng(1)
    J = rng.normal(size=(4, 6))
    e = rng.normal(size=4)
    posture = rng.normal(size=6)
    plain = damped_least_squares_step_rad(J, e, 1e-9)
    with_posture = damped_least_squares_step_rad(J, e, 1e-9, posture)
    np.testing.assert_allclose(J @ (with_posture - plain), 0.0, atol=1e-7)
    assert np.linalg.norm(with_posture - plain) > 0.1  # and it does move the joints


def test_a_long_step_is_scaled_down_whole_to_the_largest_joint_change():
    rng = np.random.default_rng(2)
    J = rng.normal(size=(6, 6))
    e = 10.0 * rng.normal(size=6)
    free = damped_least_squares_step_rad(J, e, 1e-4)
    limited = damped_least_squares_step_rad(J, e, 1e-4, max_step_rad=0.1)
    assert np.abs(limited).max() == pytest.approx(0.1)
    np.testing.assert_allclose(limited / np.linalg.norm(limited), free / np.linalg.norm(free), atol=1e-12)
    short = damped_least_squares_step_rad(J, 1e-4 * e, 1e-4, max_step_rad=0.1)
    np.testing.assert_array_equal(short, damped_least_squares_step_rad(J, 1e-4 * e, 1e-4))


# ---- the tasks ---------------------------------------------------------------------------------------------
def test_the_pose_error_is_the_twist_in_the_frame():
    M = pin.SE3(rpy_to_matrix([0.3, -0.2, 1.0]), np.array([0.1, 0.2, 0.3]))
    np.testing.assert_allclose(pose_error_local(M, M), 0.0, atol=1e-15)
    moved = M * pin.SE3(np.eye(3), np.array([0.0, 0.02, 0.0]))  # 2 cm along the frame's own y axis
    np.testing.assert_allclose(pose_error_local(M, moved), [0.0, 0.02, 0.0, 0.0, 0.0, 0.0], atol=1e-15)


def finite_difference_jacobian(error_of, q, joints, h=1e-7):
    return np.column_stack([(error_of(q + h * np.eye(len(q))[j]) - error_of(q - h * np.eye(len(q))[j])) / (2 * h)
                            for j in joints])


def test_the_point_axis_task_has_the_jacobian_of_its_error():
    point_in_frame_m = np.array([0.01, -0.02, 0.03])
    axis_in_frame, normal_world = np.array([1.0, 0.0, 0.0]), np.array([0.6, 0.8, 0.0])
    p_target_m = np.array([0.4, 0.3, 0.9])

    def task(q):
        M, J = KIN.frame_jacobian(FID, BASE, np.eye(3), q, pin.LOCAL_WORLD_ALIGNED)
        return point_axis_task_world(M.translation, M.rotation, J[:, KIN.idx_v[ARM]], p_target_m, point_in_frame_m,
                                     axis_in_frame, normal_world)

    error, jacobian = task(BENT)
    p, R = hand(BENT)
    np.testing.assert_allclose(error[:3], p_target_m - p - R @ point_in_frame_m, atol=1e-15)
    assert error[3] == pytest.approx(-(R[:, 0] @ normal_world))
    # the task error falls as its Jacobian says: d(error) = -jacobian dq
    np.testing.assert_allclose(-jacobian, finite_difference_jacobian(lambda q: task(q)[0], BENT, ARM), atol=1e-6)


def test_the_pose_task_has_the_jacobian_of_its_error_near_the_target():
    p, R = hand(BENT)
    target = PoseTarget(p + [0.001, 0.0, 0.0], R)

    def error_of(q):
        M, J = KIN.frame_jacobian(FID, BASE, np.eye(3), q, target.reference_frame)
        return target.task(M, J[:, KIN.idx_v[ARM]])[0]

    M, J = KIN.frame_jacobian(FID, BASE, np.eye(3), BENT, pin.LOCAL)
    _, jacobian = target.task(M, J[:, KIN.idx_v[ARM]])
    # log6 is only linear at the target, so the match is to the (1 mm) distance from it
    np.testing.assert_allclose(-jacobian, finite_difference_jacobian(error_of, BENT, ARM), atol=2e-3)


# ---- the solver --------------------------------------------------------------------------------------------
def test_a_pose_target_is_reached_with_only_the_joints_given_moving_and_steps_limited():
    base_R = rpy_to_matrix([0.0, 0.05, 0.1])
    p0, R0 = hand(BENT, base_R)
    R_goal = R0 @ rpy_to_matrix([0.2, 0.0, -0.1])
    params = LimbIkParams(max_iterations=300, damping=1e-2, max_step_rad=0.1, pos_tol_m=2e-4, rot_tol_rad=2e-3)
    sol = solve_limb_ik(KIN, ARM, FID, PoseTarget(p0 + [0.05, 0.03, 0.04], R_goal), BENT, BASE, base_R, params)
    assert sol.reached and sol.pos_error_m < 2e-4 and sol.rot_error_rad < 2e-3 and sol.iterations > 1
    p, R = hand(sol.q_rad, base_R)
    assert np.linalg.norm(p - (p0 + [0.05, 0.03, 0.04])) < 2e-4
    assert np.linalg.norm(pin.log3(R.T @ R_goal)) < 2e-3
    assert np.array_equal(np.delete(sol.q_rad, ARM), np.delete(BENT, ARM))


def test_a_point_axis_target_is_held_and_the_free_turn_drawn_toward_the_posture():
    point_in_frame_m = np.array([0.0, 0.0, 0.02])
    normal_world = np.array([1.0, 0.0, 0.0])
    p0, R0 = hand(BENT)
    target = PointAxisTarget(p0 + R0 @ point_in_frame_m + [0.03, 0.02, 0.0], point_in_frame_m,
                             np.array([0.0, 1.0, 0.0]), normal_world)
    params = LimbIkParams(max_iterations=300, max_step_rad=0.05, pos_tol_m=1e-3, rot_tol_rad=0.01,
                          posture_gain=0.02, settle_step_rad=1e-5)
    plain = solve_limb_ik(KIN, ARM, FID, target, BENT, BASE, np.eye(3), params.replaced(posture_gain=0.0))
    posture = BENT[ARM] + np.radians((10.0, 10.0, -20.0, 0.0, 20.0, 0.0))
    drawn = solve_limb_ik(KIN, ARM, FID, target, BENT, BASE, np.eye(3), params, posture_rad=posture)
    for sol in (plain, drawn):
        assert sol.reached
        p, R = hand(sol.q_rad)
        assert np.linalg.norm(p + R @ point_in_frame_m - target.p_world_m) < 1e-3
        assert abs(R[:, 1] @ normal_world) < 0.01
    # the posture term kept iterating after the task was met and ended nearer the posture
    assert drawn.iterations > plain.iterations
    assert np.linalg.norm(drawn.q_rad[ARM] - posture) < np.linalg.norm(plain.q_rad[ARM] - posture) - 0.05


def test_an_unreachable_target_gives_the_closest_posture_within_the_joint_limits():
    p0, R0 = hand(BENT)
    far = p0 + np.array([0.6, 0.0, 0.0])
    sol = solve_limb_ik(KIN, ARM, FID, PoseTarget(far, R0), BENT, BASE, np.eye(3), LimbIkParams(max_iterations=30))
    assert not sol.reached and sol.iterations == 30
    assert np.all(sol.q_rad >= KIN.q_lower - 1e-12) and np.all(sol.q_rad <= KIN.q_upper + 1e-12)
    p, _ = hand(sol.q_rad)
    assert np.linalg.norm(p - far) < np.linalg.norm(p0 - far) - 0.1
    assert sol.pos_error_m > 0.1 and math.isfinite(sol.rot_error_rad)


def test_the_seed_itself_is_returned_when_it_already_meets_the_target():
    p0, R0 = hand(BENT)
    sol = solve_limb_ik(KIN, ARM, FID, PoseTarget(p0, R0), BENT, BASE, np.eye(3))
    assert sol.reached and sol.iterations == 1
    np.testing.assert_array_equal(sol.q_rad, BENT)
