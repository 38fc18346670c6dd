"""Actual COG and ZMP from encoders, the KalmanFilter attitude and the foot F/T sensors."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from controller.balance.leg_odometry import LegOdometry
from controller.core.types import Estimate, Reference, read_only
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import rows_mul, rows_tmul
from robot.names import FORCE_SENSOR_NAMES

FOOT_SENSORS = (FORCE_SENSOR_NAMES.index("rfsensor"), FORCE_SENSOR_NAMES.index("lfsensor"))
CONTACT_FZ_N = 20.0  # a foot carrying less than this is not in contact
# the foot rows of the per-sensor arrays (a slice when they are adjacent: a view, no copy)
_FEET = (slice(FOOT_SENSORS[0], FOOT_SENSORS[1] + 1) if FOOT_SENSORS[1] == FOOT_SENSORS[0] + 1
         else list(FOOT_SENSORS))
_EQUAL_WEIGHTS = np.array([0.5, 0.5])
read_only(_EQUAL_WEIGHTS)

if TYPE_CHECKING:
    from controller.balance.capture_point import FootRectangle

#: [-] a sole gives the BODY tilt (body_tilt_from_flat_soles) only if it carries at least this share of the
#: feet's vertical load: a foot just touching down or about to lift may not lie flat yet
FLAT_SOLE_MIN_LOAD_SHARE = 0.25
#: [m] ... and its centre of pressure is at least this far inside every sole edge: a COP near an edge means
#: the sole may be tipping about it
FLAT_SOLE_COP_MARGIN_M = 0.02
#: [rad] a planned sole whose z axis is tilted more than this from the vertical is not planned flat (toe-off,
#: heel-strike)
FLAT_SOLE_PLAN_TILT_RAD = 1e-3
#: [rad] ... and the encoders with the attitude estimate see it within this of the plan's orientation: the
#: estimate errs by about a degree at a landing and by 5.1 deg at the first tick (it starts level); a sole seen
#: farther off is not flat on the floor (a catching step's foot that touched down early on its heel, 18 deg
#: pitched, was read as BODY pitch)
FLAT_SOLE_MAX_DISAGREEMENT_RAD = math.radians(10.0)


def body_tilt_from_flat_soles(R_body_est, R_soles_plan, R_soles_meas, wrenches_sole, rectangles: tuple[
        FootRectangle, ...], contact: tuple[bool, ...], min_load_share: float = FLAT_SOLE_MIN_LOAD_SHARE,
        cop_margin_m: float = FLAT_SOLE_COP_MARGIN_M, max_disagreement_rad: float = FLAT_SOLE_MAX_DISAGREEMENT_RAD
        ) -> tuple[float, float] | None:
    """BODY roll, pitch [rad] from the kinematics of the soles that lie flat where the plan puts them.

    A sole planned in contact and flat (`contact[i]`, `R_soles_plan[i]` (3, 3) world) that carries at least
    `min_load_share` of the feet's vertical load, with its centre of pressure at least `cop_margin_m` inside
    its rectangle's edges, and seen within `max_disagreement_rad` of that orientation, is taken to have it; BODY then is
    R_plan R_sole_meas^T R_body_est, where `R_soles_meas[i]` (3, 3) is the sole's orientation that the
    encoders and the attitude estimate `R_body_est` (3, 3) give (world-aligned). `wrenches_sole` (n, 6):
    the external wrench on each foot at its sole frame's origin, in the sole frame [N, N m]. The soles that
    qualify are averaged, weighted by their load. None when none qualifies (no measurement: the caller
    falls back on the accelerometer). The result does not depend on the estimate's attitude (it cancels)."""
    rows = (wrenches_sole.tolist() if isinstance(wrenches_sole, np.ndarray)
            else [w.tolist() if isinstance(w, np.ndarray) else w for w in wrenches_sole])
    fz = [max(float(w[2]), 0.0) for w in rows]
    total = sum(fz)
    if total <= 0.0:
        return None
    R_body = R_body_est.tolist() if isinstance(R_body_est, np.ndarray) else R_body_est
    roll_sum = pitch_sum = weight = 0.0
    for i, rect in enumerate(rectangles):
        f = fz[i]
        if not contact[i] or f < min_load_share * total:
            continue
        plan = R_soles_plan[i].tolist() if isinstance(R_soles_plan[i], np.ndarray) else R_soles_plan[i]
        if math.hypot(plan[2][0], plan[2][1]) > FLAT_SOLE_PLAN_TILT_RAD:  # the sole's z axis off the vertical
            continue
        cop_x, cop_y = -rows[i][4] / f, rows[i][3] / f  # [m] in the sole frame
        m = cop_margin_m
        if not (-rect.rear_m + m <= cop_x <= rect.front_m - m and -rect.right_m + m <= cop_y <= rect.left_m - m):
            continue
        meas = R_soles_meas[i].tolist() if isinstance(R_soles_meas[i], np.ndarray) else R_soles_meas[i]
        cos_off = plan[0][2] * meas[0][2] + plan[1][2] * meas[1][2] + plan[2][2] * meas[2][2]  # the z axes' angle
        if cos_off < math.cos(max_disagreement_rad):
            continue
        R = rows_mul(plan, rows_tmul(meas, R_body))
        r20, r21, r22 = R[2]
        roll_sum += f * math.atan2(r21, r22)
        pitch_sum += f * math.atan2(-r20, math.hypot(r21, r22))
        weight += f
    if weight <= 0.0:
        return None
    return roll_sum / weight, pitch_sum / weight


def lip_velocity_filter_step(v_xy: tuple[float, float], diff_xy: tuple[float, float], alpha: float,
                             accel_xy: tuple[float, float] = (0.0, 0.0), dt_s: float = 0.0) -> tuple[float, float]:
    """One tick of the COG velocity filter [m/s]: predict `v_xy` with the acceleration `accel_xy` [m/s^2] over
    `dt_s`, then move it by `alpha` (0..1) towards the finite difference `diff_xy` [m/s].

    With no acceleration it is the first-order low-pass of the finite difference, which lags an accelerating
    COG by about a / (2 pi f_c); with the LIP's acceleration omega^2 (balance point - measured ZMP) only what
    the LIP does not explain (a push, a model error) is lagged."""
    vx = v_xy[0] + accel_xy[0] * dt_s
    vy = v_xy[1] + accel_xy[1] * dt_s
    return vx + alpha * (diff_xy[0] - vx), vy + alpha * (diff_xy[1] - vy)


def zmp_from_foot_wrenches(pos_world: np.ndarray, wrench_world: np.ndarray, z0: float,
                           min_fz: float = CONTACT_FZ_N) -> np.ndarray | None:
    """ZMP on the plane z = z0 from per-foot wrenches at the sensor origins (world axes).

    pos_world (n, 3), wrench_world (n, 6) = [f, tau]; feet with fz < min_fz are ignored.
    Returns None when no foot carries load.
    """
    num_x = num_y = fz_sum = 0.0
    pos = pos_world.tolist() if isinstance(pos_world, np.ndarray) else pos_world
    wrenches = wrench_world.tolist() if isinstance(wrench_world, np.ndarray) else wrench_world
    for p, w in zip(pos, wrenches, strict=True):
        f0, f1, f2, tau0, tau1 = w[0], w[1], w[2], w[3], w[4]
        if f2 < min_fz:
            continue
        dz = p[2] - z0
        num_x += p[0] * f2 - tau1 - dz * f0
        num_y += p[1] * f2 + tau0 - dz * f1
        fz_sum += f2
    if fz_sum <= 0.0:
        return None
    return np.array([num_x / fz_sum, num_y / fz_sum, z0])


class ActualStateEstimator:
    """Places the measured robot in the world by anchoring the loaded soles where the reference puts them
    (a support foot does not slip), then reads COG and ZMP off it. No simulator ground truth is used."""

    def __init__(self, kinematics: RobotKinematics) -> None:
        self.kin = kinematics
        self.last_zmp = np.zeros(3)
        self.base_pos_world = np.zeros(3)  # where the anchoring put BODY [m]
        #: [m] how far this tick's change of anchor (the planned contacts switched) moved the estimate: the COG
        #: with the new anchor minus with the previous one; zero on the other ticks. Not a motion of the robot:
        #: a velocity estimate takes it out of its finite difference.
        self.anchor_shift_world = (0.0, 0.0, 0.0)
        self._anchor_weights: tuple[float, float] | None = None  # the planned contacts' weights last tick
        self._soles_key: tuple[bytes, bytes, bytes] | None = None  # the reference posture of _soles
        self._soles: np.ndarray | None = None
        #: where the feet are in the world (leg odometry), beside the plan's frame the anchoring above uses
        self.odometry = LegOdometry()

    def reference_soles(self, ref: Reference) -> np.ndarray:
        """World positions of the two sole sensors in the reference posture, (2, 3), read-only.

        Forward kinematics only when the reference posture changed (a standing reference does not)."""
        key = (ref.base_pos_world.tobytes(), ref.base_rpy_rad.tobytes(), ref.q_rad.tobytes())
        if key != self._soles_key:
            self.kin.update_rpy(ref.base_pos_world, ref.base_rpy_rad, ref.q_rad)
            soles = np.array([self.kin.frame_pose(FORCE_SENSOR_NAMES[i])[0] for i in FOOT_SENSORS])
            read_only(soles)
            self._soles, self._soles_key = soles, key
        return self._soles

    def _odometry(self, est: Estimate, pos: list, wrench_rows: list, p_body, walking: bool) -> None:
        """One tick of leg odometry (the measured soles from BODY and their loads, BODY as this estimate places
        it), published in the Estimate. pos, wrench_rows: est.sensor_pos_from_base and est.wrenches_ext_world
        as lists."""
        r, left = FOOT_SENSORS
        if not any(pos[r]) and not any(pos[left]):  # no kinematics measured yet (the loop's first snapshot)
            return
        R = est.sensor_R_world.tolist()
        est.odometry = self.odometry.update(
            (pos[r], pos[left]), (R[r], R[left]), (wrench_rows[r][2], wrench_rows[left][2]), p_body,
            walking)

    def __call__(self, sensors, est: Estimate, ref: Reference) -> tuple[np.ndarray, np.ndarray]:
        if ref.gait is not None:  # the AutoBalancer says where the soles are meant to be
            # hrpsys's actual foot-origin frame: the feet mid-point when both are meant to be down,
            # otherwise the planned support foot (deterministic switches, no Fz chatter)
            return self._with_gait(est, ref.gait)
        self.anchor_shift_world, self._anchor_weights = (0.0, 0.0, 0.0), None  # (the measured loads anchor)
        # the soles weighted by their measured load (equal weights when hardly loaded). The two weighted
        # sums stay numpy dot products: the same roundings as ever (numpy fuses the multiply-add)
        ref_soles = self.reference_soles(ref)
        meas_soles = est.sensor_pos_from_base[_FEET]
        rows = est.wrenches_ext_world.tolist()
        foot_wrenches = [rows[i] for i in FOOT_SENSORS]
        fz0, fz1 = max(foot_wrenches[0][2], 0.0), max(foot_wrenches[1][2], 0.0)  # np.clip(fz, 0.0, None)
        fz_sum = fz0 + fz1
        w = np.array((fz0 / fz_sum, fz1 / fz_sum)) if fz_sum > 2 * CONTACT_FZ_N else _EQUAL_WEIGHTS
        offset = w @ (ref_soles - meas_soles)
        self.base_pos_world = offset
        self._odometry(est, est.sensor_pos_from_base.tolist(), rows, offset.tolist(), False)
        cog = est.com_from_base + offset
        soles = meas_soles + offset
        zmp = zmp_from_foot_wrenches(soles, foot_wrenches, float(w @ soles[:, 2]))
        if zmp is not None:
            self.last_zmp = zmp
        return read_only(cog), read_only(self.last_zmp.copy())  # published in the snapshot as they are

    def _with_gait(self, est: Estimate, gait) -> tuple[np.ndarray, np.ndarray]:
        """__call__ with a gait reference, on Python floats (same maths)."""
        (rx, ry, rz), (lx, ly, lz) = gait.p_rsole_world.tolist(), gait.p_lsole_world.tolist()  # planned
        pos = est.sensor_pos_from_base.tolist()
        (mrx, mry, mrz), (mlx, mly, mlz) = pos[FOOT_SENSORS[0]], pos[FOOT_SENSORS[1]]  # measured, from BODY
        right_down, left_down = gait.contact
        c0, c1 = (1.0 if right_down else 0.0), (1.0 if left_down else 0.0)
        csum = c0 + c1
        w0, w1 = (c0 / csum, c1 / csum) if csum > 0 else (0.5, 0.5)
        # BODY offset: the weighted mean of planned minus measured soles (x, y, z written out)
        ox = w0 * (rx - mrx) + w1 * (lx - mlx)
        oy = w0 * (ry - mry) + w1 * (ly - mly)
        oz = w0 * (rz - mrz) + w1 * (lz - mlz)
        last = self._anchor_weights
        if last is None or last == (w0, w1):
            self.anchor_shift_world = (0.0, 0.0, 0.0)
        else:  # the same measurement with last tick's anchor: the difference is the switch's, not the robot's
            v0, v1 = last
            self.anchor_shift_world = (ox - v0 * (rx - mrx) - v1 * (lx - mlx), oy - v0 * (ry - mry) - v1 * (ly - mly),
                                       oz - v0 * (rz - mrz) - v1 * (lz - mlz))
        self._anchor_weights = (w0, w1)
        self.base_pos_world = np.array((ox, oy, oz))
        cx, cy, cz = est.com_from_base.tolist()
        cog = np.array((cx + ox, cy + oy, cz + oz))
        soles = ((mrx + ox, mry + oy, mrz + oz), (mlx + ox, mly + oy, mlz + oz))
        wrenches = est.wrenches_ext_world.tolist()
        self._odometry(est, pos, wrenches, (ox, oy, oz), gait.walking)
        zmp = zmp_from_foot_wrenches(soles, (wrenches[FOOT_SENSORS[0]], wrenches[FOOT_SENSORS[1]]),
                                     w0 * soles[0][2] + w1 * soles[1][2])
        if zmp is not None:
            self.last_zmp = zmp
        return read_only(cog), read_only(self.last_zmp.copy())  # published in the snapshot as they are
