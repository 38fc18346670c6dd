"""The capture-point emergency step's maths: the LIP capture point, the trigger, the swing leg, where the foot lands
(the capture point at touchdown, the sole's centre on it, clamped to the leg's reach without crossing), and the
plan (its timing agrees with the gait generator's, its ZMP path and re-planning)."""

import math

import numpy as np
import pytest

from controller.balance.capture_point import (
    HRP2_LEFT_SOLE,
    HRP2_RIGHT_SOLE,
    distance_to_polygon_edge,
    point_in_convex_polygon,
    shrink_polygon,
    support_polygon,
)
from controller.core.errors import InvalidCommand, InvalidState
from controller.interpolation.hoff_arbib import min_jerk
from controller.walking.emergency_step import (
    EmergencyStepParams,
    EmergencyStepPlan,
    SupportRegion,
    clamp_landing,
    cp_weights,
    landing_for,
    lip_capture_point,
    needs_step,
    sole_corners_world,
    stance_zmp,
    swing_leg_for,
    zmp_path_column,
    zmp_path_weights,
)
from controller.walking.footsteps import Footstep
from controller.walking.gait_generator import GaitGenerator, GaitParams

DT = 0.005
OMEGA = math.sqrt(9.80665 / 0.81)  # HRP-2's LIP [1/s]
P = EmergencyStepParams()
RIGHT = Footstep("rleg", 0.0, -0.095)
LEFT = Footstep("lleg", 0.0, 0.095)


def feet_polygon(right=RIGHT, left=LEFT):
    return support_polygon([((right.x, right.y, right.yaw), HRP2_RIGHT_SOLE), ((left.x, left.y, left.yaw),
                                                                                 HRP2_LEFT_SOLE)])


# ---- the LIP and the trigger


def test_the_lip_capture_point_runs_away_from_the_zmp_exponentially():
    zmp = np.array([0.1, -0.05])
    cp0 = np.array([0.15, 0.0])
    t = 0.3
    cp = lip_capture_point(cp0, zmp, OMEGA, t)
    assert np.allclose(cp - zmp, (cp0 - zmp) * math.exp(OMEGA * t))
    # it solves xi_dot = omega (xi - zmp): a central difference agrees
    h = 1e-6
    rate = (lip_capture_point(cp0, zmp, OMEGA, t + h) - lip_capture_point(cp0, zmp, OMEGA, t - h)) / (2 * h)
    assert np.allclose(rate, OMEGA * (cp - zmp), atol=1e-6)
    assert np.allclose(lip_capture_point(zmp, zmp, OMEGA, 5.0), zmp)  # a CP on the ZMP stays


def test_a_step_is_needed_only_when_the_capture_point_is_outside_the_support_polygon_beyond_the_margin():
    poly = feet_polygon()
    front = HRP2_RIGHT_SOLE.front_m  # the toe edge of both soles
    assert not needs_step((front - 0.001, 0.0), poly, 0.0)
    assert needs_step((front + 0.001, 0.0), poly, 0.0)
    assert not needs_step((front + 0.004, 0.0), poly, 0.005)  # within the margin outside
    assert needs_step((front - 0.004, 0.0), poly, -0.005)  # a negative margin steps before the edge
    assert not needs_step((0.0, 0.0), poly, 0.0)


@pytest.mark.parametrize("seed", range(3))
def test_the_support_region_measures_the_same_signed_distance_as_the_polygon(seed):
    rng = np.random.default_rng(seed)
    right = Footstep("rleg", 0.02, -0.1, yaw=0.2)
    left = Footstep("lleg", 0.3, 0.12, yaw=-0.1)
    poly = feet_polygon(right, left)
    region = SupportRegion(poly)
    for x, y in rng.uniform(-0.5, 0.7, size=(200, 2)):
        assert region.outside_m(x, y) == pytest.approx(-distance_to_polygon_edge((x, y), poly), abs=1e-12)


def test_support_region_of_soles_is_the_hull_of_both_soles():
    R = np.eye(3)
    region = SupportRegion.of_soles((np.array([0.0, -0.095, 0.0]), R), (np.array([0.0, 0.095, 0.0]), R))
    assert np.allclose(region.polygon_xy, feet_polygon())


# ---- which leg, where


def test_sideways_the_leg_on_the_side_the_capture_point_goes_to_steps():
    assert swing_leg_for((0.02, 0.2), 100.0, 500.0) == "lleg"  # loaded or not
    assert swing_leg_for((-0.02, -0.2), 500.0, 100.0) == "rleg"


def test_forward_or_backward_the_less_loaded_leg_steps_the_left_one_on_a_tie():
    assert swing_leg_for((0.2, 0.05), 300.0, 250.0) == "lleg"
    assert swing_leg_for((-0.2, 0.05), 250.0, 300.0) == "rleg"
    assert swing_leg_for((0.2, 0.0), 280.0, 280.0) == "lleg"


def test_the_stance_zmp_is_the_point_of_the_shrunk_stance_sole_nearest_the_capture_point():
    z = stance_zmp((0.3, 0.0), "rleg", (0.0, -0.095), 0.0, 0.015)
    assert z == pytest.approx((HRP2_RIGHT_SOLE.front_m - 0.015, -0.095 + HRP2_RIGHT_SOLE.left_m - 0.015))
    inside = (0.05, -0.1)
    assert stance_zmp(inside, "rleg", (0.0, -0.095), 0.0, 0.015) == pytest.approx(inside)


def test_the_landing_is_clamped_to_the_reach_ahead_behind_and_sideways():
    stance = (0.0, -0.095)
    far = clamp_landing((1.0, 1.0), stance, 0.0, "lleg", P)
    assert far == pytest.approx((P.max_forward_m, -0.095 + P.max_width_m))
    back = clamp_landing((-1.0, 0.2), stance, 0.0, "lleg", P)
    assert back[0] == pytest.approx(-P.max_backward_m)
    inside = clamp_landing((0.2, 0.15), stance, 0.0, "lleg", P)
    assert inside == pytest.approx((0.2, 0.15))


@pytest.mark.parametrize("swing, target_y", [("lleg", -0.3), ("lleg", -0.095), ("rleg", 0.3), ("rleg", 0.095)])
def test_the_landing_never_crosses_nor_overlaps_the_stance_sole(swing, target_y):
    stance_y = 0.095 if swing == "rleg" else -0.095
    landing = clamp_landing((0.05, target_y), (0.0, stance_y), 0.0, swing, P)
    side = 1.0 if swing == "lleg" else -1.0
    assert side * (landing[1] - stance_y) == pytest.approx(P.min_width_m)
    stance_sole = sole_corners_world("rleg" if swing == "lleg" else "lleg", 0.0, stance_y, 0.0)
    landed_sole = sole_corners_world(swing, *landing.tolist(), 0.0)
    assert not any(point_in_convex_polygon(c, stance_sole) for c in landed_sole)


def test_the_reach_is_in_the_stance_soles_frame():
    yaw = math.radians(90.0)  # the robot faces +y: forward is +y, its left is -x
    landing = clamp_landing((0.0, 1.0), (0.0, 0.0), yaw, "lleg", P)
    assert landing == pytest.approx((-P.min_width_m, P.max_forward_m))


def test_the_sole_centre_lands_on_the_capture_point_predicted_at_touchdown():
    cp_td, zmp = np.array([0.36, 0.15]), np.array([0.11, -0.05])
    landing = landing_for(cp_td, zmp, (0.0, -0.095), 0.0, "lleg", P)
    rect = HRP2_LEFT_SOLE
    centre = landing + np.array((0.5 * (rect.front_m - rect.rear_m), 0.5 * (rect.left_m - rect.right_m)))
    assert centre == pytest.approx(cp_td)


def test_a_landing_offset_puts_the_sole_farther_along_the_capture_points_motion():
    cp_td, zmp = np.array([0.3, 0.2]), np.array([0.11, -0.05])  # nothing clamped
    at = landing_for(cp_td, zmp, (0.0, -0.095), 0.0, "lleg", P)
    beyond = landing_for(cp_td, zmp, (0.0, -0.095), 0.0, "lleg", P.replaced(landing_offset_m=0.03))
    motion = (cp_td - zmp) / np.linalg.norm(cp_td - zmp)
    assert (beyond - at) == pytest.approx(0.03 * motion)


def test_params_refuse_an_empty_lateral_range():
    with pytest.raises(InvalidCommand, match="min_width_m"):
        EmergencyStepParams(min_width_m=0.3, max_width_m=0.2)


# ---- the plan


def forward_plan(cp=(0.17, 0.0), params=P):
    return EmergencyStepPlan(params, DT, RIGHT, LEFT, np.array(cp), np.array([0.13, 0.0]), OMEGA)


def test_the_plans_timing_is_the_gait_generators():
    plan = forward_plan()
    gg = GaitGenerator(GaitParams(), DT, T_world_rfoot=RIGHT.T_world_foot, T_world_lfoot=LEFT.T_world_foot)
    gg.plan(plan.footsteps(), params=plan.gait_params(gg.params))
    support = [gg.tick().support for _ in range(plan.n_end)]
    assert not gg.walking  # the plan and the gait end on the same sample
    assert support[:plan.n_lift] == ["both"] * plan.n_lift
    assert support[plan.n_lift:plan.n_touchdown] == ["rleg"] * (plan.n_touchdown - plan.n_lift)
    assert set(support[plan.n_touchdown:]) == {"both"}
    landed = gg.T_world_lfoot[:2, 3]
    assert landed == pytest.approx(plan.landing_xy)


def test_the_plan_lands_the_left_foot_ahead_where_the_capture_point_will_be():
    plan = forward_plan()
    assert plan.swing.leg == "lleg"
    assert plan.landing_xy[0] > 0.25  # the CP 5 cm past the toe runs on through the swing
    # held at the stance ZMP from the start, the CP would be 2 cm farther: the ZMP starts at the toe's middle
    td = plan.n_touchdown * DT
    held = lip_capture_point((0.17, 0.0), plan.zmp_stance_xy, OMEGA, td)
    assert 0.005 < np.linalg.norm(held - plan.cp_touchdown_xy) < 0.03


def test_the_zmp_path_starts_where_the_zmp_is_stays_on_the_stance_sole_and_ends_between_the_feet():
    plan = forward_plan()
    zmp = plan.zmp(0)
    assert zmp.shape == (plan.n_end, 3)
    assert np.linalg.norm(zmp[0, :2] - plan.zmp_start_xy) < 0.02  # one tick into the initial double support
    stance = shrink_polygon(sole_corners_world("rleg", 0.0, -0.095, 0.0), P.zmp_margin_m - 1e-9)
    assert all(point_in_convex_polygon(z, stance) for z in zmp[plan.n_lift:plan.n_touchdown, :2])
    assert zmp[-1, :2] == pytest.approx(plan.feet_middle_xy())
    step = np.linalg.norm(np.diff(zmp[:, :2], axis=0), axis=1)  # [m] per tick
    n_shift = round(P.zmp_shift_s / DT)
    shift = slice(plan.n_touchdown - 1, plan.n_touchdown + n_shift)
    assert np.delete(step, np.arange(len(step))[shift]).max() < 0.015  # no jump (the first 10 ticks: 5.6 cm) ...
    distance = np.linalg.norm(plan.zmp_after_touchdown_xy() - plan.zmp_stance_xy)
    assert step[shift].max() < 1.9 * distance / n_shift  # ... but the quick min-jerk shift at touchdown


def test_until_touchdown_the_planned_zmp_takes_the_lip_capture_point_to_the_one_the_landing_is_planned_for():
    plan = forward_plan()
    zmp = plan.zmp(0)[:, :2]
    cp = np.array([0.17, 0.0])
    for k in range(plan.n_touchdown):  # exact discretisation of xi_dot = omega (xi - zmp), zmp held over a tick
        cp = lip_capture_point(cp, zmp[k], OMEGA, DT)
    assert cp == pytest.approx(plan.cp_touchdown_xy, abs=1e-9)
    assert point_in_convex_polygon(cp, plan.support_polygon_after())


def test_the_landing_follows_the_measured_capture_point_until_the_freeze():
    plan = forward_plan()
    first = plan.landing_xy.copy()
    assert plan.replan(plan.n_lift + 5, np.array([0.22, 0.0]))  # the CP ran on: the landing moves ahead
    assert plan.landing_xy[0] > first[0]
    moved = plan.landing_xy.copy()
    assert not plan.replan(plan.n_freeze, np.array([0.4, 0.0]))  # frozen: no late jerk of the swing foot
    assert plan.landing_xy == pytest.approx(moved)


def test_an_early_touchdown_lands_the_foot_where_it_is_and_the_zmp_follows():
    plan = forward_plan()
    k = plan.n_touchdown - 10
    plan.land(k, (0.3, 0.2))
    assert plan.touchdown_k == k and not plan.swinging(k)
    assert plan.landing_xy == pytest.approx((0.3, 0.2))
    zmp = plan.zmp(k)
    after = shrink_polygon(plan.support_polygon_after(), P.zmp_margin_m - 1e-9)
    assert point_in_convex_polygon(zmp[10, :2], after)
    assert not plan.replan(k + 1, np.array([0.5, 0.0]))  # down: nothing moves it any more


def test_a_plan_needs_one_foot_of_each_leg():
    with pytest.raises(InvalidCommand, match="both rleg"):
        EmergencyStepPlan(P, DT, RIGHT, RIGHT, np.zeros(2), np.zeros(2), OMEGA)


# ---- the plan's maths made cheap for every tick: the floats of the direct computation, bit for bit


def _zmp_direct(plan, k_from):
    """The reference ZMP as the plan first computed it: every sample's branch by np.where over the whole queue."""
    k = np.arange(k_from, plan.n_end)
    td, z0, zs = plan.touchdown_k, plan.zmp_start_xy, plan.zmp_stance_xy
    zl, zm = plan.zmp_after_touchdown_xy(), plan.feet_middle_xy()
    n_shift = min(max(1, round(plan.params.zmp_shift_s / plan.dt_s)), max(plan.n_step_end - td, 1))
    lift = min_jerk((k + 1) / plan.n_lift)[:, None]
    shift = min_jerk((k + 1 - td) / n_shift)[:, None]
    final = min_jerk((k + 1 - plan.n_step_end) / max(plan.n_end - plan.n_step_end, 1))[:, None]
    until = np.where((k < plan.n_lift)[:, None], z0 + lift * (zs - z0), zs)
    xy = np.where((k < td)[:, None], until,
                  np.where((k < plan.n_step_end)[:, None], zs + shift * (zl - zs), zl + final * (zm - zl)))
    return np.column_stack([xy, np.full(len(k), plan.z_m)])


def test_the_zmp_queue_from_cached_weights_is_the_direct_computations_floats():
    plan = forward_plan()
    for k in (0, 1, plan.n_lift, plan.n_lift + 7, plan.n_touchdown - 1, plan.n_touchdown, plan.n_step_end,
              plan.n_end - 1):
        assert plan.zmp(k).tolist() == _zmp_direct(plan, k).tolist()
    plan.replan(plan.n_lift + 5, np.array([0.22, 0.03]))
    plan.land(plan.n_touchdown - 10, (0.3, 0.2))  # an early touchdown: other shift and final weights
    for k in (plan.n_touchdown - 10, plan.n_touchdown, plan.n_step_end + 3):
        assert plan.zmp(k).tolist() == _zmp_direct(plan, k).tolist()


def test_the_zmp_weights_depend_on_the_timing_alone_and_are_shared_read_only():
    lift, shift, final = zmp_path_weights(10, 60, 70, 370, 6)
    assert (lift.shape, shift.shape, final.shape) == ((10, 1), (10, 1), (300, 1))
    assert lift[-1, 0] == shift[5, 0] == final[-1, 0] == 1.0 and shift[-1, 0] == 1.0
    assert zmp_path_weights(10, 60, 70, 370, 6)[1] is shift  # a re-plan reuses them
    assert not shift.flags.writeable
    column, counts = zmp_path_column(10, 60, 70, 370, 6)  # end to end, 0 while held on the stance sole
    assert counts == (10, 50, 10, 300) and column.shape == (370, 1)
    assert column[:10].tolist() == lift.tolist() and column[60:70].tolist() == shift.tolist()
    assert not column[10:60].any()


def test_the_cp_weights_are_the_direct_computations_floats():
    a = math.exp(OMEGA * DT)
    km, k = 3, 57
    j = np.arange(km, k)
    assert cp_weights(a, k - km).tolist() == ((a - 1.0) * a ** (k - 1 - j)).tolist()


def test_the_capture_point_at_touchdown_is_the_direct_computations_floats():
    for k, cp in ((0, (0.17, 0.0)), (forward_plan().n_lift + 3, (0.2, 0.01))):  # through the lift, and after it
        plan = forward_plan()
        if k:
            plan.replan(k, np.array(cp))
        j = np.arange(k, plan.n_touchdown)
        a = math.exp(OMEGA * DT)
        # the reference ZMP until touchdown, contiguous as the plan's own: a strided operand takes another BLAS
        # path whose sums round differently on some CPUs (1 ulp on an AMD EPYC VM)
        zmp = np.ascontiguousarray(plan.zmp(0)[k:plan.n_touchdown, :2])
        direct = a ** (plan.n_touchdown - k) * np.array(cp) - ((a - 1.0) * a ** (plan.n_touchdown - 1 - j)) @ zmp
        assert plan.cp_touchdown_xy.tolist() == direct.tolist()


def test_a_replan_made_on_a_copy_leaves_the_plan_alone_and_adopted_gives_the_floats_of_replanning_it():
    direct, ahead = forward_plan(), forward_plan()
    for k, cp in ((ahead.n_lift + 5, (0.22, 0.0)), (ahead.n_lift + 6, (0.225, 0.01)), (ahead.n_freeze, (0.4, 0.0))):
        state = dict(vars(ahead))
        copy, moved = ahead.replanned(k, np.array(cp))
        assert all(vars(ahead)[name] is value for name, value in state.items())  # untouched
        assert moved == direct.replan(k, np.array(cp))
        ahead.adopt(copy)
        assert ahead.landing_xy.tolist() == direct.landing_xy.tolist()
        assert ahead.zmp_stance_xy.tolist() == direct.zmp_stance_xy.tolist()
        assert ahead.zmp(k).tolist() == direct.zmp(k).tolist()


def test_a_copy_replanned_from_an_older_revision_is_not_adopted():
    plan = forward_plan()
    copy, _ = plan.replanned(plan.n_lift + 5, np.array((0.22, 0.0)))
    plan.replan(plan.n_lift + 5, np.array((0.21, 0.0)))
    with pytest.raises(InvalidState, match="revision"):
        plan.adopt(copy)
