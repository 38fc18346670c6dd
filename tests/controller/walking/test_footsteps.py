"""Footstep planners: goPos goal and stride limits, goVelocity / goStop / emergencyStop, setFootSteps."""

import math

import numpy as np
import pytest

from controller.walking.footsteps import (
    Footstep,
    FootstepParams,
    StrideLimits,
    VelocityStepper,
    clamp_stride,
    go_pos,
    mid_coords,
    set_footsteps,
)

Y = FootstepParams().leg_offset_y_m
LIMITS = StrideLimits()


def feet_T(x=0.0, y=0.0, yaw=0.0):
    out = []
    for sign in (-1.0, 1.0):
        T = np.eye(4)
        c, s = math.cos(yaw), math.sin(yaw)
        T[:2, :2] = [[c, -s], [s, c]]
        T[:3, 3] = [x - s * sign * Y, y + c * sign * Y, 0.0]
        out.append(T)
    return out


def implied_mid(f: Footstep):
    sign = 1.0 if f.leg == "lleg" else -1.0
    return (f.x + math.sin(f.yaw) * sign * Y, f.y - math.cos(f.yaw) * sign * Y, f.yaw)


def relative(a, b):
    c, s = math.cos(a[2]), math.sin(a[2])
    dx, dy = b[0] - a[0], b[1] - a[1]
    return (c * dx + s * dy, -s * dx + c * dy, (b[2] - a[2] + math.pi) % (2 * math.pi) - math.pi)


def assert_within_stride_limits(steps, start_mid):
    mids = [start_mid] + [implied_mid(f) for f in steps[1:]]
    for f, a, b in zip(steps[1:], mids[:-1], mids[1:], strict=True):
        d = relative(a, b)
        clamped = clamp_stride(d, f.leg, LIMITS)
        assert np.allclose(d, clamped, atol=1e-9), (f, d, clamped)


def final_mid(steps):
    last = {f.leg: f for f in steps}
    return mid_coords(last["rleg"], last["lleg"])


@pytest.mark.parametrize("goal", [(0.1, 0.1, 20.0), (-0.1, -0.1, -10.0), (0.2, 0.1, 20.0), (0.3, 0.0, 0.0)])
def test_go_pos_ends_with_the_feet_mid_coords_on_the_goal(goal):
    start = (0.3, -0.2, math.radians(30.0))
    steps = go_pos(*feet_T(*start), goal[0], goal[1], math.radians(goal[2]))
    c, s = math.cos(start[2]), math.sin(start[2])
    expected = (start[0] + c * goal[0] - s * goal[1], start[1] + s * goal[0] + c * goal[1],
                start[2] + math.radians(goal[2]))
    mid = final_mid(steps)
    assert math.hypot(mid[0] - expected[0], mid[1] - expected[1]) < 5e-5
    assert abs(math.degrees(relative(expected, mid)[2])) < 0.01


@pytest.mark.parametrize("goal", [(0.1, 0.1, 20.0), (-0.1, -0.1, -10.0), (0.0, 0.15, 0.0), (0.0, 0.0, 30.0)])
def test_go_pos_respects_the_stride_limits_on_every_step(goal):
    rT, lT = feet_T()
    steps = go_pos(rT, lT, goal[0], goal[1], math.radians(goal[2]))
    assert_within_stride_limits(steps, (0.0, 0.0, 0.0))


def test_go_pos_starts_on_the_support_foot_with_zero_height_and_alternates_legs():
    rT, lT = feet_T()
    left = go_pos(rT, lT, 0.1, 0.1, 0.0)
    right = go_pos(rT, lT, 0.1, -0.1, 0.0)
    assert left[0].leg == "rleg" and right[0].leg == "lleg"  # hrpsys: support = y > 0 ? RLEG : LLEG
    assert left[0].step_height_m == 0.0 and left[0].position[1] == pytest.approx(-Y)
    assert all(a.leg != b.leg for a, b in zip(left[:-1], left[1:], strict=True))


def test_go_velocity_steps_respect_the_limits_and_advance_v_times_t_per_step():
    stepper = VelocityStepper(*feet_T())
    v = (0.1, 0.05, math.radians(10.0))
    steps = stepper.start(*v)
    assert len(steps) == 4 and steps[0].leg == "rleg"  # vy > 0: support rleg, first swing lleg
    for _ in range(5):
        stepper.advance_to(len(stepper.footsteps) - 3)
        steps = stepper.replan()
    assert_within_stride_limits(steps, (0.0, 0.0, 0.0))
    mids = [(0.0, 0.0, 0.0)] + [implied_mid(f) for f in steps[1:]]
    for f, a, b in zip(steps[1:], mids[:-1], mids[1:], strict=True):
        assert np.allclose(relative(a, b), clamp_stride([x * 1.0 for x in v], f.leg, LIMITS), atol=1e-12)


def test_a_velocity_update_mid_walk_changes_only_the_steps_after_the_overwritable_one():
    stepper = VelocityStepper(*feet_T())
    stepper.start(0.1, 0.0, 0.0)
    stepper.advance_to(2)
    before = stepper.footsteps
    stepper.set_velocity(0.0, 0.0, math.radians(5.0))
    after = stepper.replan()
    assert tuple(after[:3]) == before[:3]
    assert len(after) == 3 + FootstepParams().lookahead_steps and after[3] != before[3]
    assert after[3].yaw == pytest.approx(math.radians(5.0))


def test_finalize_puts_the_feet_side_by_side():
    stepper = VelocityStepper(*feet_T())
    stepper.start(0.1, 0.05, math.radians(10.0))
    stepper.advance_to(2)
    steps = stepper.finalize()
    assert len(steps) in (4, 5) and stepper.state == "ending"
    last = {f.leg: f for f in steps}
    rel = relative(implied_mid(last["rleg"]), implied_mid(last["lleg"]))
    assert np.allclose(rel, 0.0, atol=1e-12)
    assert stepper.replan() == steps  # nothing more is planned once ending


def test_emergency_stop_places_the_remaining_steps_on_the_current_feet():
    stepper = VelocityStepper(*feet_T())
    stepper.start(0.1, 0.0, 0.0)
    stepper.advance_to(2)
    landed, other = stepper.footsteps[2], stepper.footsteps[1]
    steps = stepper.emergency_stop()
    assert [f.leg for f in steps[3:]] == [other.leg, landed.leg, other.leg]
    for f in steps[3:]:
        ref = landed if f.leg == landed.leg else other
        assert f.position.tolist() == ref.position.tolist() and f.yaw == ref.yaw and f.step_height_m == 0.0
    assert stepper.remaining()[0] == landed


def test_set_footsteps_re_expresses_inputs_relative_to_the_first_snapped_on_the_current_foot():
    rT, lT = feet_T(1.0, 2.0, math.radians(90.0))
    inputs = [("rleg", [5.0, 5.0, 0.0], [0, 0, 0]), ("lleg", [5.1, 5.19, 0.0], [0, 0, 0.1]),
              ("rleg", [5.2, 5.0, 0.0], [0, 0, 0])]
    steps = set_footsteps(inputs, rT, lT)
    assert np.allclose(steps[0].T_world_foot, rT)
    assert steps[0].step_height_m == 0.0 and steps[1].step_height_m == FootstepParams().step_height_m
    assert np.allclose(steps[1].position, rT[:3, 3] + [-0.19, 0.1, 0.0])  # +x of the input is +y in the world
    assert steps[1].yaw == pytest.approx(math.radians(90.0) + 0.1)
    assert np.allclose(steps[2].position, rT[:3, 3] + [0.0, 0.2, 0.0])


def test_set_footsteps_with_an_unknown_leg_is_a_value_error_listing_the_valid_legs():
    with pytest.raises(ValueError, match=r"valid legs: \['rleg', 'lleg'\]"):
        set_footsteps([("rleg", [0, 0, 0], [0, 0, 0]), ("larm", [0.1, 0, 0], [0, 0, 0])], *feet_T())
