"""Closing a stance too wide to walk from (a catching step's landing): one slow step of the foot farther from the
COG to the walking stance width beside the other, BODY lowered so that the far knee stays bent while the COM sits
over the near foot (a walk from there stretches that knee straight: campaign seed 1004)."""

from __future__ import annotations

import math

import numpy as np

from controller.core.errors import InvalidState
from controller.walking.auto_balancer_params import WALK_STANCE_MAX_WIDTH_M, stance_width_m
from controller.walking.footsteps import Footstep, FootstepParams
from controller.walking.gait_sampling import GaitParams

#: [m] no single step leaves a wider stance: with the COM over one foot the far leg's hip roll reaches its limit and
#: the flag rises (measured: 0.43 m closes, the knees 0.38 rad from straight; 0.45 m does not, lowered 0.08-0.10 m
#: with the ZMP 0.04-0.05 m inward)
CLOSE_STANCE_MAX_WIDTH_M = 0.43
#: [m] BODY below the walking height through the closing step, so that the far knee stays bent (at 0.40 m: 0.36 rad
#: from straight at 0.08 m, 0.00 at 0.06 m, with the ZMP at the soles' centres)
CLOSE_STANCE_LOWERING_M = 0.08
#: [s] the closing step's time and its double supports' share at each end: the COM travels 0.1-0.15 m sideways in
#: them, slow enough for the CP error to stay well under the flag's 40 mm
CLOSE_STANCE_STEP_TIME_S = 1.5
CLOSE_STANCE_DOUBLE_SUPPORT_RATIO = 0.25
#: [m] each sole's ZMP this far toward the other foot (of 0.059 m to its inner edge): the COM travels less far over
#: the stance foot, and the far leg's hip roll stays off its limit (without it, 0.40 m raised the flag)
CLOSE_STANCE_ZMP_INWARD_M = 0.03


def closing_steps(T_world_rfoot: np.ndarray, T_world_lfoot: np.ndarray, cog_xy_world: tuple[float, float],
                  params: FootstepParams) -> list[Footstep]:
    """The plan [the stance foot where it is, the other beside it]: the foot nearer the COG stays; the other lands
    2 * params.leg_offset_y_m from it across, level with it and turned as it is. InvalidState when the stance is
    not one it closes (WALK_STANCE_MAX_WIDTH_M, CLOSE_STANCE_MAX_WIDTH_M]."""
    width = stance_width_m(T_world_rfoot, T_world_lfoot)
    if not WALK_STANCE_MAX_WIDTH_M < width <= CLOSE_STANCE_MAX_WIDTH_M:
        raise InvalidState(f"closeStance: the feet stand {width:.3f} m apart across; it closes "
                           f"{WALK_STANCE_MAX_WIDTH_M:g}-{CLOSE_STANCE_MAX_WIDTH_M:g} m (narrower: goPos walks from "
                           "there; wider: with the COM over one foot the far leg's hip roll reaches its limit)")
    rfoot, lfoot = Footstep.from_T("rleg", T_world_rfoot), Footstep.from_T("lleg", T_world_lfoot)
    x, y = cog_xy_world
    near_right = math.hypot(rfoot.x - x, rfoot.y - y) <= math.hypot(lfoot.x - x, lfoot.y - y)
    stance, swing = (rfoot, lfoot) if near_right else (lfoot, rfoot)
    across = (1.0 if swing.leg == "lleg" else -1.0) * 2.0 * params.leg_offset_y_m
    c, s = math.cos(stance.yaw), math.sin(stance.yaw)
    first = stance.replaced(step_height_m=0.0, toe_angle_rad=0.0, heel_angle_rad=0.0,
                            step_time_s=CLOSE_STANCE_STEP_TIME_S)
    landing = Footstep(swing.leg, stance.x - s * across, stance.y + c * across, stance.z, stance.yaw,
                       step_height_m=params.step_height_m, step_time_s=CLOSE_STANCE_STEP_TIME_S)
    return [first, landing]



def closing_gait_params(params: GaitParams) -> GaitParams:
    """The closing step's plan timing: `params` with the slow double supports."""
    ratio, inward = CLOSE_STANCE_DOUBLE_SUPPORT_RATIO, CLOSE_STANCE_ZMP_INWARD_M
    return params.replaced(double_support_ratio_before=ratio, double_support_ratio_after=ratio,
                           rleg_zmp_offset_y_m=params.rleg_zmp_offset_y_m + inward,
                           lleg_zmp_offset_y_m=params.lleg_zmp_offset_y_m - inward)


def closing_duration_s(params: GaitParams) -> float:
    """[s] the closing step's walk: its initial double support, the step, and the gait's final double support."""
    return 2.0 * CLOSE_STANCE_STEP_TIME_S + params.final_double_support_s
