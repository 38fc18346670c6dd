"""Closing a stance too wide to walk from: which foot steps, where it lands, which widths it takes, and the plan's
own ZMP offsets (toward the other foot) while it lasts."""

import math

import numpy as np
import pytest

from controller.core.errors import InvalidState
from controller.walking.close_stance import (
    CLOSE_STANCE_MAX_WIDTH_M,
    CLOSE_STANCE_STEP_TIME_S,
    CLOSE_STANCE_ZMP_INWARD_M,
    closing_duration_s,
    closing_gait_params,
    closing_steps,
)
from controller.walking.footsteps import FootstepParams
from controller.walking.gait_generator import GaitGenerator
from controller.walking.gait_sampling import GaitParams
from tests.controller.layers.test_auto_balancer_stance import sole

DT = 0.005


def wide_feet(width_m: float, heading_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Right and left soles `width_m` apart across a heading, mid-coords at (0.4, -0.2)."""
    c, s = math.cos(math.radians(heading_deg)), math.sin(math.radians(heading_deg))
    half = 0.5 * width_m
    return (sole(0.4 + s * half, -0.2 - c * half, heading_deg), sole(0.4 - s * half, -0.2 + c * half, heading_deg))


@pytest.mark.parametrize("heading_deg", [0.0, 30.0, -120.0])
@pytest.mark.parametrize("nearer", ["rleg", "lleg"])
def test_the_foot_farther_from_the_cog_lands_beside_the_other_at_the_walking_width(heading_deg, nearer):
    T_r, T_l = wide_feet(0.40, heading_deg)
    near = T_r if nearer == "rleg" else T_l
    cog = tuple(0.8 * near[:2, 3] + 0.2 * (T_l if nearer == "rleg" else T_r)[:2, 3])
    params = FootstepParams()
    first, landing = closing_steps(T_r, T_l, cog, params)
    assert first.leg == nearer and landing.leg != nearer
    assert np.allclose(first.T_world_foot, near, atol=1e-12)
    # the landing in the stance sole's frame: straight across, at twice the leg offset, turned as the stance sole
    rel = np.linalg.inv(first.T_world_foot) @ landing.T_world_foot
    across = 2.0 * params.leg_offset_y_m * (1.0 if landing.leg == "lleg" else -1.0)
    assert rel[:3, 3] == pytest.approx((0.0, across, 0.0), abs=1e-12)
    assert np.allclose(rel[:3, :3], np.eye(3), atol=1e-12)
    assert first.step_time_s == landing.step_time_s == CLOSE_STANCE_STEP_TIME_S


@pytest.mark.parametrize("width_m", [0.19, 0.34, CLOSE_STANCE_MAX_WIDTH_M + 0.005, 0.6])
def test_only_the_widths_no_walk_starts_from_and_one_step_leaves_are_closed(width_m):
    T_r, T_l = wide_feet(width_m, 0.0)
    with pytest.raises(InvalidState, match=rf"{width_m:.3f} m apart across; it closes 0.34-0.43 m"):
        closing_steps(T_r, T_l, (0.4, -0.2), FootstepParams())


def test_the_closing_plan_puts_each_sole_zmp_toward_the_other_foot_and_the_next_plan_does_not():
    T_r, T_l = wide_feet(0.40, 0.0)
    gg = GaitGenerator(GaitParams(), DT, T_world_rfoot=T_r, T_world_lfoot=T_l)
    steps = closing_steps(T_r, T_l, (0.4, -0.35), FootstepParams())  # the right foot stays
    gg.plan(steps, params=closing_gait_params(gg.params))
    ticks = round(closing_duration_s(gg.params) / DT)
    on_right = []
    for _ in range(ticks + 10):
        g = gg.tick()
        if g.support == "rleg":
            on_right.append(g.zmp_world[:2] - g.p_rfoot_world[:2])
    assert not gg.walking and len(on_right) > 0
    assert np.allclose(on_right, (0.0, CLOSE_STANCE_ZMP_INWARD_M), atol=1e-9)
    gg.go_pos(0.1, 0.0, 0.0)  # a walk after it: the COPs at the soles' centres again
    singles = [(g.zmp_world - (g.p_rfoot_world if g.support == "rleg" else g.p_lfoot_world))[:2]
               for g in (gg.tick() for _ in range(round(4.0 / DT))) if g.support != "both"]
    assert singles and np.allclose(singles, 0.0, atol=1e-9)
