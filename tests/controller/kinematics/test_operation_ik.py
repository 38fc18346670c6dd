"""Operation-layer whole-body IK (placo): joint order, reaching, clamping, gaze, waist, limits, balance."""

import math

import numpy as np
import pytest

from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE, distance_to_polygon_edge, support_polygon
from controller.core.errors import InvalidCommand
from controller.kinematics.model import RobotKinematics
from controller.kinematics.operation_ik import OperationIK
from controller.kinematics.operation_params import OperationIKParams
from controller.kinematics.operation_targets import (
    JOINT_LIMIT,
    REACH,
    SOLVER,
    FeetPoses,
    GazeTarget,
    HandTarget,
    OperationTargets,
    WaistTarget,
)
from controller.kinematics.rotations import rows_angle_between, rpy_to_matrix
from robot.generate import half_sitting_deg, load_parameters
from robot.names import JOINT_NAMES, joint_index

HALF_SITTING = np.deg2rad(half_sitting_deg())
BASE = np.array([0.0, 0.0, load_parameters()["half_sitting_deg"]["base_height_m"]])
RPY = np.zeros(3)
DT = OperationIKParams().dt_s
STEP = OperationIKParams().joint_velocity_limit_rad_s * DT
KIN = RobotKinematics()  # an independent model (pinocchio, JOINT_NAMES order) to check the results


def fk(res):
    KIN.update(res.base_pos_world, rpy_to_matrix(res.base_rpy_rad), res.q_rad)
    return KIN


def reference_pose(frame):
    KIN.update_rpy(BASE, RPY, HALF_SITTING)
    return KIN.frame_pose(frame)


def soles_and_polygon():
    KIN.update_rpy(BASE, RPY, HALF_SITTING)
    (pr, Rr), (pl, Rl) = KIN.frame_pose("rleg_end"), KIN.frame_pose("lleg_end")
    yaw = lambda R: math.atan2(R[1, 0], R[0, 0])  # noqa: E731
    poly = support_polygon([((pr[0], pr[1], yaw(Rr)), HRP2_RIGHT_SOLE), ((pl[0], pl[1], yaw(Rl)), HRP2_LEFT_SOLE)])
    return (pr, pl), poly


def run(ik, targets, ticks, q=HALF_SITTING, feet=None):
    """Solve `ticks` ticks; returns the results."""
    return [ik.solve(q, BASE, RPY, targets(k) if callable(targets) else targets, feet) for k in range(ticks)]


# ---- joint order ------------------------------------------------------------------------------------


def test_joint_order_maps_openhrp_names_to_placo_and_back():
    ik = OperationIK()
    placo_order = list(ik.robot.joint_names())
    assert sorted(placo_order) == sorted(JOINT_NAMES)
    assert placo_order != list(JOINT_NAMES)  # placo orders by name: the map is needed
    assert sorted(ik.idx_q.tolist()) == list(range(7, 7 + len(JOINT_NAMES)))
    for name in ("RLEG_JOINT0", "CHEST_JOINT1", "HEAD_JOINT0", "LARM_JOINT6"):
        assert ik.idx_q[joint_index(name)] == ik.robot.get_joint_offset(name)
    rng = np.random.default_rng(0)
    for _ in range(5):
        q = rng.uniform(ik.q_lower, ik.q_upper)
        p, R = rng.normal(size=3), rpy_to_matrix(rng.uniform(-0.5, 0.5, 3))
        q2, p2, R2 = ik.from_placo(ik.to_placo(q, p, R))
        assert np.allclose(q2, q) and np.allclose(p2, p) and np.allclose(R2, R)
        # placo's forward kinematics through the map agree with pinocchio in JOINT_NAMES order
        ik.robot.state.q = ik.to_placo(q, p, R)
        ik.robot.update_kinematics()
        KIN.update(p, R, q)
        for frame in ("rarm_end", "larm_end", "lleg_end", "HEAD_LINK1"):
            T = ik.robot.get_T_world_frame(frame)
            p_ref, R_ref = KIN.frame_pose(frame)
            assert np.allclose(T[:3, 3], p_ref, atol=1e-12) and np.allclose(T[:3, :3], R_ref, atol=1e-12)



# ---- reaching ------------------------------------------------------------------------------------------


def test_right_hand_reaches_twenty_centimetres_forward_with_feet_fixed_and_com_inside():
    ik = OperationIK()
    p0, R0 = reference_pose("rarm_end")
    (pr, pl), poly = soles_and_polygon()
    target = OperationTargets(rhand=HandTarget(p0 + [0.2, 0.0, 0.0], R0))
    results = run(ik, target, 200)
    for res in results:  # all along the way
        kin = fk(res)
        assert np.linalg.norm(kin.frame_pose("rleg_end")[0] - pr) < 1e-3
        assert np.linalg.norm(kin.frame_pose("lleg_end")[0] - pl) < 1e-3
        assert distance_to_polygon_edge(kin.com_world()[:2], poly) >= 0.03
        assert res.com_margin_m == pytest.approx(distance_to_polygon_edge(res.com_world[:2], poly), abs=1e-9)
        assert np.rad2deg(_angle_np(kin.frame_pose("rarm_end")[1], R0)) < 2.0
    hand = results[-1].points["rhand"]
    p_end = fk(results[-1]).frame_pose("rarm_end")[0]
    assert np.linalg.norm(p_end - (p0 + [0.2, 0.0, 0.0])) < 0.01
    assert hand.error_m == pytest.approx(np.linalg.norm(p_end - (p0 + [0.2, 0.0, 0.0])), abs=1e-9)
    assert hand.limited is None and hand.scale == 1.0


def _angle_np(Ra, Rb):
    return math.acos(max(-1.0, min(1.0, 0.5 * (np.trace(Ra.T @ Rb) - 1.0))))


def test_the_hand_moves_no_faster_than_its_servo_speed():
    ik = OperationIK()
    p0, R0 = reference_pose("rarm_end")
    results = run(ik, OperationTargets(rhand=HandTarget(p0 + [0.2, 0.0, 0.0], R0)), 60)
    path = [r.points["rhand"].p_world for r in results]
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    assert steps.max() <= OperationIKParams().hand_speed_m_s * DT * 1.01
    assert all(r.points["rhand"].scale > 0.95 for r in results)  # free space: it does what it is asked


def test_unreachable_target_is_clamped_at_the_reach_limit_and_the_scale_drops():
    ik = OperationIK()
    p0, R0 = reference_pose("rarm_end")
    (pr, pl), poly = soles_and_polygon()
    # a caller integrating a 0.3 m/s forward command toward 1 m away, clamping to the achieved pose when limited
    goal = p0 + [1.0, 0.0, 0.0]
    target, history = p0.copy(), []
    for _ in range(800):
        target = target + np.clip(goal - target, -0.3 * DT, 0.3 * DT)
        res = ik.solve(HALF_SITTING, BASE, RPY, OperationTargets(rhand=HandTarget(target, R0)))
        hand = res.points["rhand"]
        if hand.limited is not None:
            target = hand.p_world.copy()
        history.append((hand.p_world.copy(), hand.scale, hand.limited, np.linalg.norm(target - hand.p_world)))
        assert res.com_margin_m >= 0.03
    p_last = [h[0] for h in history[-50:]]
    commanded = 0.3 * DT * 50
    assert np.linalg.norm(p_last[-1] - p_last[0]) < 0.02 * commanded  # stopped: < 2 % of the commanded speed
    assert p_last[-1][0] - p0[0] > 0.3  # after getting as far as it can
    assert np.linalg.norm(goal - p_last[-1]) > 0.2
    assert history[-1][2] == REACH
    assert max(h[3] for h in history) < 0.01  # the caller's target never ran away from the hand
    scales = [h[1] for h in history]
    assert scales[0] > 0.99 and max(scales[-50:]) < 0.05
    # the same target given at once: the hand settles at the reach limit too, the IK says why, scale ~0
    ik2 = OperationIK()
    results = run(ik2, OperationTargets(rhand=HandTarget(goal, R0)), 1000)
    hand = results[-1].points["rhand"]
    assert hand.limited == REACH and hand.scale < 0.05
    assert np.linalg.norm(results[-1].points["rhand"].p_world - results[-50].points["rhand"].p_world) < 5e-4
    assert np.all(np.isfinite(results[-1].q_rad))


# ---- head and waist ------------------------------------------------------------------------------------


def test_head_turns_thirty_degrees_of_yaw_relative_to_the_chest():
    ik = OperationIK()
    results = run(ik, OperationTargets(head=GazeTarget(yaw_rad=np.deg2rad(30.0))), 120)
    res = results[-1]
    assert np.rad2deg(res.q_rad[joint_index("HEAD_JOINT0")]) == pytest.approx(30.0, abs=0.1)
    assert abs(res.q_rad[joint_index("HEAD_JOINT1")]) < 1e-3
    kin = fk(res)
    R_chest_head = kin.frame_pose("CHEST_LINK1")[1].T @ kin.frame_pose("HEAD_LINK1")[1]
    assert np.rad2deg(_angle_np(R_chest_head, rpy_to_matrix([0, 0, np.deg2rad(30.0)]))) < 0.1
    assert res.points["head"].error_rad < 1e-3 and res.points["head"].limited is None


def test_head_looks_at_a_point_in_the_world():
    ik = OperationIK()
    point = np.array([1.0, 0.5, 0.5])
    res = run(ik, OperationTargets(head=GazeTarget(look_at_world=point)), 150)[-1]
    kin = fk(res)
    gaze = kin.frame_pose("HEAD_LINK1")[1][:, 0]
    to_point = point - kin.frame_pose("HEAD_LINK0")[0]
    assert np.rad2deg(math.acos(gaze @ to_point / np.linalg.norm(to_point))) < 0.5


def test_waist_goes_down_ten_centimetres_with_the_feet_fixed():
    ik = OperationIK()
    (pr, pl), poly = soles_and_polygon()
    results = run(ik, OperationTargets(waist=WaistTarget(BASE[2] - 0.10, np.zeros(3))), 200)
    res = results[-1]
    assert res.base_pos_world[2] == pytest.approx(BASE[2] - 0.10, abs=1e-3)
    assert np.abs(res.base_rpy_rad).max() < np.deg2rad(0.5)
    for r in results:
        kin = fk(r)
        assert np.linalg.norm(kin.frame_pose("rleg_end")[0] - pr) < 1e-3
        assert np.linalg.norm(kin.frame_pose("lleg_end")[0] - pl) < 1e-3
        assert distance_to_polygon_edge(kin.com_world()[:2], poly) >= 0.03
    assert res.points["waist"].error_m < 1e-3 and res.points["waist"].limited is None


# ---- limits ---------------------------------------------------------------------------------------------


def test_motion_slows_down_near_a_joint_limit_instead_of_stopping_dead():
    ik = OperationIK()
    head = joint_index("HEAD_JOINT0")
    limit = ik.q_upper[head]  # 45 deg
    yaw, q_prev, steps, scales, reasons = 0.0, 0.0, [], [], []
    for _ in range(300):  # the operator pushes the gaze to 60 deg at 1 rad/s
        yaw = min(np.deg2rad(60.0), yaw + 1.0 * DT)
        res = ik.solve(HALF_SITTING, BASE, RPY, OperationTargets(head=GazeTarget(yaw_rad=yaw)))
        q = res.q_rad[head]
        assert q <= limit + 1e-12  # (rounding of q + step at the bound)
        steps.append(q - q_prev)
        scales.append(res.points["head"].scale)
        reasons.append(res.points["head"].limited)
        q_prev = q
    first = next(i for i, s in enumerate(scales) if s < 0.9)  # braking starts
    assert q_prev == pytest.approx(limit, abs=1e-4)
    assert all(b <= a + 1e-9 for a, b in zip(steps[first - 1:], steps[first:], strict=False))  # decelerates
    assert sum(0.05 < s < 0.95 for s in scales) >= 3  # a gradual slow-down, not a step from 1 to 0
    assert reasons[-1] == JOINT_LIMIT and scales[-1] < 0.01


def test_no_joint_step_exceeds_the_velocity_limit():
    fast = OperationIKParams(hand_speed_m_s=5.0, hand_angular_speed_rad_s=20.0, head_angular_speed_rad_s=20.0,
                             waist_speed_m_s=5.0, waist_angular_speed_rad_s=20.0)
    ik = OperationIK(params=fast)
    pr, Rr = reference_pose("rarm_end")
    pl, Rl = reference_pose("larm_end")
    jump = OperationTargets(rhand=HandTarget(pr + [0.25, -0.1, 0.2], rpy_to_matrix([0.5, 0.0, 0.3]) @ Rr),
                            lhand=HandTarget(pl + [0.2, 0.1, -0.1], Rl), head=GazeTarget(0.6, 0.4),
                            waist=WaistTarget(BASE[2] - 0.08, [0.0, 0.1, 0.2]))
    only_left = OperationTargets(lhand=jump.lhand)  # the others released: their chains return to the reference
    q_prev = HALF_SITTING.copy()
    for k in range(400):
        res = ik.solve(HALF_SITTING, BASE, RPY, jump if k < 200 else only_left)
        assert np.abs(res.q_rad - q_prev).max() <= STEP + 1e-9
        q_prev = res.q_rad
    assert np.abs(q_prev[joint_index("HEAD_JOINT0")]) < 1e-9  # back to the reference


# ---- balance, feet, idle ---------------------------------------------------------------------------------


def test_com_stays_inside_the_support_polygon_when_both_hands_reach_far_forward():
    ik = OperationIK()
    pr, Rr = reference_pose("rarm_end")
    pl, Rl = reference_pose("larm_end")
    (_, _), poly = soles_and_polygon()
    far = OperationTargets(rhand=HandTarget(pr + [0.7, 0.0, 0.1], Rr), lhand=HandTarget(pl + [0.7, 0.0, 0.1], Rl))
    margins = [distance_to_polygon_edge(fk(r).com_world()[:2], poly) for r in run(ik, far, 400)]
    assert min(margins) >= 0.03
    assert min(margins) < 0.04  # the balance constraint did the holding back


def test_feet_follow_given_poses_and_the_support_polygon_follows_the_contacts():
    ik = OperationIK()
    KIN.update_rpy(BASE, RPY, HALF_SITTING)
    (pr, Rr), (pl, Rl) = KIN.frame_pose("rleg_end"), KIN.frame_pose("lleg_end")
    pt, Rt = reference_pose("rarm_end")
    hold = OperationTargets(rhand=HandTarget(pt, Rt))
    right_only = support_polygon([((pr[0], pr[1], 0.0), HRP2_RIGHT_SOLE)])
    for k in range(300):  # the left sole lifts 3 cm while the right one carries the robot
        lift = 0.03 * min(1.0, k / 100)
        res = ik.solve(HALF_SITTING, BASE, RPY, hold, FeetPoses(pr, Rr, pl + [0.0, 0.0, lift], Rl, (True, False)))
    kin = fk(res)
    assert np.linalg.norm(kin.frame_pose("lleg_end")[0] - (pl + [0.0, 0.0, 0.03])) < 1e-3
    assert np.linalg.norm(kin.frame_pose("rleg_end")[0] - pr) < 1e-3
    assert distance_to_polygon_edge(kin.com_world()[:2], right_only) >= 0.03
    assert res.com_margin_m == pytest.approx(distance_to_polygon_edge(res.com_world[:2], right_only), abs=1e-9)


def test_idle_tick_returns_the_inputs_without_solving():
    ik = OperationIK()

    class NoSolver:
        def solve(self, apply):
            raise AssertionError("an idle tick must not solve")

    ik.solver = NoSolver()
    res = ik.solve(HALF_SITTING, BASE, RPY, OperationTargets())
    assert not res.active and res.q_rad is HALF_SITTING and res.base_pos_world is BASE and not res.points


def test_a_point_activated_after_idle_starts_from_the_reference_posture():
    ik = OperationIK()
    p0, R0 = reference_pose("rarm_end")
    run(ik, OperationTargets(rhand=HandTarget(p0 + [0.1, 0, 0], R0)), 50)
    ik.solve(HALF_SITTING, BASE, RPY, OperationTargets())  # idle: the layer passed the reference through
    res = ik.solve(HALF_SITTING, BASE, RPY, OperationTargets(rhand=HandTarget(p0, R0)))
    assert np.abs(res.q_rad - HALF_SITTING).max() < 1e-3


# ---- interface ----------------------------------------------------------------------------------------


def test_results_are_read_only():
    ik = OperationIK()
    p0, R0 = reference_pose("rarm_end")
    res = ik.solve(HALF_SITTING, BASE, RPY, OperationTargets(rhand=HandTarget(p0, R0)))
    with pytest.raises(ValueError):
        res.q_rad[0] = 1.0
    with pytest.raises(ValueError):
        res.points["rhand"].p_world[0] = 1.0


def test_a_failed_qp_keeps_the_previous_posture_and_says_so():
    ik = OperationIK()
    p0, R0 = reference_pose("rarm_end")
    target = OperationTargets(rhand=HandTarget(p0 + [0.1, 0.0, 0.0], R0))
    before = run(ik, target, 10)[-1]
    real = ik.solver

    class Failing:
        def solve(self, apply):
            raise RuntimeError("QPError: Problem: Infeasible QP")

        def __getattr__(self, name):
            return getattr(real, name)

    ik.solver = Failing()
    res = ik.solve(HALF_SITTING, BASE, RPY, target)
    assert not res.ok and res.points["rhand"].limited == SOLVER and res.points["rhand"].scale == 0.0
    assert np.array_equal(res.q_rad, before.q_rad)
    ik.solver = real
    assert ik.solve(HALF_SITTING, BASE, RPY, target).ok


def test_the_com_goes_where_the_caller_holds_it_and_never_past_the_margin():
    ik = OperationIK()
    p0, R0 = reference_pose("rarm_end")
    (_, _), poly = soles_and_polygon()
    hold = OperationTargets(rhand=HandTarget(p0, R0))
    res = [ik.solve(HALF_SITTING, BASE, RPY, hold, com_xy_world=np.array((0.03, -0.04))) for _ in range(150)][-1]
    assert np.linalg.norm(res.com_world[:2] - (0.03, -0.04)) < 2e-3
    assert res.points["rhand"].error_m < 1e-3  # the hand stays put while the body shifts under it
    res = [ik.solve(HALF_SITTING, BASE, RPY, hold, com_xy_world=np.array((0.5, 0.0))) for _ in range(150)][-1]
    assert 0.035 - 1e-4 <= distance_to_polygon_edge(res.com_world[:2], poly) <= 0.042



def test_new_parameters_take_effect_on_the_next_tick():
    ik = OperationIK()
    gaze = OperationTargets(head=GazeTarget(yaw_rad=0.5))
    head = joint_index("HEAD_JOINT0")
    q1 = run(ik, gaze, 2)[-1].q_rad[head]
    ik.set_params(ik.params.replaced(joint_velocity_limit_rad_s=0.2, head_angular_speed_rad_s=5.0))
    q2 = ik.solve(HALF_SITTING, BASE, RPY, gaze).q_rad[head]
    assert q2 - q1 == pytest.approx(0.2 * DT, rel=1e-6)


# ---- upper-body mode (what the operation layer runs: the AutoBalancer owns the legs and BODY) ----------------


def test_upper_body_mode_reaches_with_the_arm_and_never_moves_the_base_or_the_legs():
    ik = OperationIK(upper_body=True)
    p0, R0 = reference_pose("rarm_end")
    legs = [joint_index(n) for n in JOINT_NAMES if "LEG" in n]
    res = run(ik, OperationTargets(rhand=HandTarget(p0 + (0.15, 0.0, 0.05), R0)), 200)[-1]
    assert np.array_equal(res.base_pos_world, BASE) and np.array_equal(res.base_rpy_rad, RPY)
    assert np.array_equal(res.q_rad[legs], HALF_SITTING[legs])
    p, R = fk(res).frame_pose("rarm_end")
    assert np.linalg.norm(p - (p0 + (0.15, 0.0, 0.05))) < 1e-3
    assert math.degrees(rows_angle_between(R.tolist(), R0.tolist())) < 0.5


def test_upper_body_mode_guard_keeps_the_com_near_where_it_was_and_refuses_the_waist():
    ik = OperationIK(upper_body=True)
    KIN.update_rpy(BASE, RPY, HALF_SITTING)
    com0 = KIN.com_world()[:2].copy()
    pr, Rr = reference_pose("rarm_end")
    pl, Rl = reference_pose("larm_end")
    # both hands 0.6 m forward and down: the torso would bend far, the COM goes forward until the guard
    far = OperationTargets(rhand=HandTarget(pr + (0.6, 0.0, -0.3), Rr), lhand=HandTarget(pl + (0.6, 0.0, -0.3), Rl))
    results = run(ik, far, 400)
    guard = OperationIKParams().com_guard_m
    worst = max(np.abs(r.com_world[:2] - com0).max() for r in results)
    assert worst <= guard + 1e-3  # measured 0.040 m: at the guard, not past it
    assert results[-1].points["rhand"].limited is not None
    with pytest.raises(InvalidCommand, match="waist"):
        ik.solve(HALF_SITTING, BASE, RPY, OperationTargets(waist=WaistTarget(0.6, np.zeros(3))))


def test_a_lean_solve_gives_the_same_posture_and_reasons_without_the_errors_and_the_com():
    full, lean = OperationIK(upper_body=True), OperationIK(upper_body=True)
    pr, Rr = reference_pose("rarm_end")
    far = OperationTargets(rhand=HandTarget(pr + (0.6, 0.0, -0.3), Rr), head=GazeTarget(yaw_rad=0.3))
    for _ in range(150):  # into the reach limit: reasons set
        a = full.solve(HALF_SITTING, BASE, RPY, far)
        b = lean.solve(HALF_SITTING, BASE, RPY, far, lean=True)
        assert np.array_equal(a.q_rad, b.q_rad)
        for name, r in a.points.items():
            s = b.points[name]
            assert np.array_equal(r.T_world, s.T_world) and (r.scale, r.limited) == (s.scale, s.limited)
            assert s.error_m is None and s.error_rad is None
    assert a.points["rhand"].limited is not None
    assert b.com_world is None and b.com_margin_m is None and a.com_world is not None
