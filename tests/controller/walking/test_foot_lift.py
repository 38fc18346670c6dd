"""The foot-lift pieces of the AutoBalancer (controller/walking/foot_lift.py): the sole's centre, the shifted ZMP,
the offset's step (up, across, down) and the phases under a command and its release."""

from __future__ import annotations

import numpy as np
import pytest

from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE
from controller.core.types import FootCommand
from controller.walking.foot_lift import (
    CLEARANCE_M,
    SETTLE_TIME_S,
    SHIFT_TIME_S,
    FootLift,
    offset_step,
    shifted_zmp,
    sole_centre_offset_m,
)
from controller.walking.gait_generator import GaitSample

DT = 0.005


def test_the_sole_centres_are_forward_and_outward_of_the_sole_frames():
    assert sole_centre_offset_m(HRP2_RIGHT_SOLE) == pytest.approx((0.015, -0.010))
    assert sole_centre_offset_m(HRP2_LEFT_SOLE) == pytest.approx((0.015, 0.010))


def test_the_shifted_zmp_goes_from_the_middle_to_the_stance_centre_at_rest_at_both_ends():
    mid, stance = np.array((0.0, 0.0, 0.0)), np.array((0.02, 0.1, 0.0))
    zmp = shifted_zmp(mid, stance, np.array((-0.5, 0.0, 0.5, 1.0, 1.5)))
    assert zmp[0] == pytest.approx(mid) and zmp[1] == pytest.approx(mid)  # clipped below 0
    assert zmp[2] == pytest.approx(0.5 * (mid + stance))
    assert zmp[3] == pytest.approx(stance) and zmp[4] == pytest.approx(stance)
    near = shifted_zmp(mid, stance, np.array((1e-3, 1.0 - 1e-3)))  # minimum jerk: flat at the ends
    assert np.linalg.norm(near[0] - mid) < 1e-7 and np.linalg.norm(near[1] - stance) < 1e-7


@pytest.mark.parametrize(("start", "goal", "expected"), [
    ((0.0, 0.0, 0.0), (0.1, 0.0, 0.05), (0.0, 0.0, 0.01)),  # on the floor: up first, x-y frozen
    ((0.0, 0.0, 0.02), (0.1, 0.0, 0.02), (0.01, 0.0, 0.02)),  # above the clearance: across
    ((0.1, 0.0, 0.05), (0.0, 0.0, 0.0), (0.09, 0.0, 0.05)),  # back across before down
    ((0.0, 0.0, 0.05), (0.0, 0.0, 0.0), (0.0, 0.0, 0.04)),  # over its rest place: down
    ((0.0, 0.0, 0.045), (0.0, 0.0, 0.05), (0.0, 0.0, 0.05)),  # within a step: lands on the goal
])
def test_the_offset_step_lifts_first_goes_across_then_down(start, goal, expected):
    assert offset_step(start, goal, 0.01) == pytest.approx(expected)


def test_the_offset_step_keeps_the_sole_off_the_floor_while_it_crosses():
    offset, lowest_across = (0.0, 0.0, 0.0), 1.0
    for _ in range(200):
        new = offset_step(offset, (0.1, 0.05, 0.0), 0.002)
        if abs(new[0] - offset[0]) + abs(new[1] - offset[1]) > 0.0:
            lowest_across = min(lowest_across, offset[2], new[2])
        offset = new
    assert offset == pytest.approx((0.1, 0.05, 0.0))  # down once over the goal
    assert lowest_across >= CLEARANCE_M - 1e-9


def _idle_sample() -> GaitSample:
    eye = np.eye(3)
    return GaitSample(time_s=0.0, walking=False, support="both", footstep_index=0, remaining_footsteps=0,
                      zmp_world=np.zeros(3), p_rfoot_world=np.array((0.0, -0.095, 0.0)), R_rfoot_world=eye,
                      p_lfoot_world=np.array((0.0, 0.095, 0.0)), R_lfoot_world=eye, r_lleg=0.5,
                      cop_offset_x_m=np.zeros(2), pitch_offset_rad=np.zeros(2))


def test_the_phases_shift_lift_lower_and_return_and_the_support_is_the_stance_foot_while_lifted():
    lift, g = FootLift(DT), _idle_sample()
    cmd = FootCommand("rfoot", (0.05, 0.0, 0.03))
    phases, supports = [], set()
    for k in range(round(6.0 / DT)):
        lift.step(cmd if k < round(3.0 / DT) else None, walking=False)
        sample, off = lift.sample(g)
        if not phases or phases[-1] != lift.phase:
            phases.append(lift.phase)
        supports.add((lift.phase, sample.support))
        if k == round((SHIFT_TIME_S + SETTLE_TIME_S) / DT) - 2:  # shifted and settled, not lifted yet
            assert lift.phase == "shifting" and sample.zmp_world[:2] == pytest.approx((0.015, 0.105))
        if k == round(3.0 / DT) - 1:
            assert off == pytest.approx((0.05, 0.0, 0.03))
            assert sample.p_rfoot_world == pytest.approx((0.05, -0.095, 0.03))
    assert phases == ["shifting", "lifted", "lowering", "returning", "idle"]
    assert {s for p, s in supports if p == "lifted"} == {"lleg"}
    assert {s for p, s in supports if p == "lowering"} == {"lleg", "both"}  # both within TOUCH_M of the floor
    assert {s for p, s in supports if p in ("shifting", "returning", "idle")} == {"both"}
    assert lift.sample(g)[0] is g  # idle: the gait's own sample


def test_a_lift_is_refused_while_walking_and_says_why():
    lift = FootLift(DT)
    lift.step(FootCommand("lfoot", (0.0, 0.0, 0.02)), walking=True)
    assert lift.phase == "idle" and lift.refused == "ignored: walking"


def test_the_preview_carries_the_shift_ahead():
    lift, g = FootLift(DT), _idle_sample()
    lift.step(FootCommand("lfoot", (0.0, 0.0, 0.02)), walking=False)
    future = lift.zmp_preview(np.zeros((400, 3)), g)
    assert future[0][:2] == pytest.approx((0.0, 0.0), abs=1e-6)
    assert future[-1][:2] == pytest.approx((0.015, -0.105))  # the right sole's centre, 2 s ahead
    assert np.all(np.diff(future[:, 1]) <= 1e-12)  # monotonic toward it


def test_returning_the_preview_waits_for_the_pause_on_both_feet_then_carries_the_shift_back():
    lift, g = FootLift(DT), _idle_sample()
    lift.phase, lift.foot, lift.progress = "returning", "rfoot", 1.0
    future = lift.zmp_preview(np.zeros((400, 3)), g)
    pause = round(SETTLE_TIME_S / DT)
    assert np.allclose(future[:pause + 1, :2], (0.015, 0.105))  # still over the left sole during the pause
    assert future[-1][:2] == pytest.approx((0.0, 0.0), abs=1e-9)  # back in the middle 1.2 s later
