"""Where a walk held by the hard e-stop stops from: the frozen robot's ZMP at rest, and the plan as a robot that
tipped onto its swing foot sees it (levelling as that foot lands)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE
from controller.balance.tilt_anchor import TiltAnchor
from controller.core.types import Estimate, GaitState
from controller.kinematics.rotations import matrix_to_rpy, rpy_to_matrix
from controller.walking.auto_balancer_params import FEET, SWING_FOOT_LOADED_N

REST_ZMP_MARGIN_M = 0.02  # [m] a robot stopped on one foot keeps its ZMP this far inside the sole
#: [rad/s] a robot that tipped onto its swing foot under the hard e-stop lands it, and so levels, along a
#: minimum-jerk path whose peak rate is this: well below the KalmanFilter's gyro trust band (0.1 rad/s), so its
#: accelerometer keeps the attitude right as the robot turns back (levelling 7 deg in 2 s, 0.11 rad/s at the
#: peak, the estimate lagged 0.5 deg and caught up in a jump: a capture-point error of 42-58 mm; in 5.7 s (0.04
#: rad/s) 30-38 mm, in 7.6 s 32-36 mm)
TIPPED_LEVELLING_RATE_RAD_S = 0.03
#: [rad] ... when it rests tilted more than this (a swing foot loaded with the robot level lands in the usual time)
TIPPED_MIN_TILT_RAD = math.radians(1.0)
#: [-] peak over mean rate of a minimum-jerk path (15/8)
MIN_JERK_PEAK_RATIO = 1.875


def rest_zmp_xy(cog_xy_world: np.ndarray, gait: GaitState | None) -> tuple[float, float]:
    """Where the ZMP of the robot frozen now is once at rest [m]: under the planned COG `cog_xy_world` (2,), kept
    REST_ZMP_MARGIN_M inside the support sole when on one foot."""
    x, y = cog_xy_world.tolist()
    if gait is None or gait.support == "both":
        return x, y
    right = gait.support == "rleg"
    p, R = (gait.p_rsole_world, gait.R_rsole_world) if right else (gait.p_lsole_world, gait.R_lsole_world)
    sole = HRP2_RIGHT_SOLE if right else HRP2_LEFT_SOLE
    c, s_ = float(R[0, 0]), float(R[1, 0])
    n = math.hypot(c, s_)
    c, s_ = c / n, s_ / n
    dx, dy = x - float(p[0]), y - float(p[1])
    u, v = c * dx + s_ * dy, -s_ * dx + c * dy  # in the sole frame
    m = REST_ZMP_MARGIN_M
    u = min(max(u, -sole.rear_m + m), sole.front_m - m)
    v = min(max(v, -sole.right_m + m), sole.left_m - m)
    return float(p[0]) + c * u - s_ * v, float(p[1]) + s_ * u + c * v


def levelling_time_s(tilt: TiltAnchor | None) -> float:
    """[s] how long a robot resting tilted by `tilt` takes to level at TIPPED_LEVELLING_RATE_RAD_S (0 when level)."""
    return 0.0 if tilt is None or tilt.angle0_rad <= TIPPED_MIN_TILT_RAD else \
        MIN_JERK_PEAK_RATIO * tilt.angle0_rad / TIPPED_LEVELLING_RATE_RAD_S


def tipped(gait: GaitState | None, estimate: Estimate, duration_s: float) -> TiltAnchor | None:
    """The held walk's robot resting on its swing foot as well (it tipped onto it): the plan as it sees it,
    levelling over `duration_s`; None when the plan is not on one foot or the swing foot carries nothing."""
    if gait is None or gait.support == "both":
        return None
    swing = FEET[0] if gait.support == "lleg" else FEET[1]
    if not float(estimate.wrenches_ext[swing][2]) > SWING_FOOT_LOADED_N:
        return None
    p_support = gait.p_rsole_world if gait.support == "rleg" else gait.p_lsole_world
    return TiltAnchor(rpy_to_matrix(gait.base_rpy_rad), rpy_to_matrix(estimate.base_rpy_rad), p_support, duration_s)


def tilted(gait: GaitState, t: TiltAnchor) -> tuple[GaitState, np.ndarray, np.ndarray]:
    """The gait, BODY position and rpy as the robot tipped by `t` sees them."""
    R_body = t.rotation(rpy_to_matrix(gait.base_rpy_rad))
    out = dataclasses.replace(
        gait, p_rsole_world=t.point(gait.p_rsole_world), R_rsole_world=t.rotation(gait.R_rsole_world),
        p_lsole_world=t.point(gait.p_lsole_world), R_lsole_world=t.rotation(gait.R_lsole_world),
        zmp_world=t.point(gait.zmp_world), cog_world=t.point(gait.cog_world),
        cog_vel_world=t.velocity(gait.cog_world, gait.cog_vel_world), cog_pc_world=t.point(gait.cog_pc_world),
        base_pos_world=t.point(gait.base_pos_world), base_rpy_rad=matrix_to_rpy(R_body))
    return out, out.base_pos_world, out.base_rpy_rad
