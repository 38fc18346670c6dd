"""Operational-point targets in the feet frame F, and their integration from a twist (one tick)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from controller.core.types import read_only
from controller.kinematics.rotations import matrix_to_rpy_floats
from controller.operation.limits import share_along
from controller.operation.points import Twist
from robot.sensors import frozen_array


def feet_frame(p_rsole_world: np.ndarray, R_rsole_world: np.ndarray, p_lsole_world: np.ndarray,
               R_lsole_world: np.ndarray) -> tuple[np.ndarray, float]:
    """The feet frame F (points.py): origin (3,) [m] midway between the soles, yaw [rad] their mean yaw
    (of the summed x axes, as the AutoBalancer turns BODY)."""
    R_r, R_l = np.asarray(R_rsole_world, dtype=float), np.asarray(R_lsole_world, dtype=float)
    r00, r10, l00, l10 = float(R_r[0, 0]), float(R_r[1, 0]), float(R_l[0, 0]), float(R_l[1, 0])  # (x axes only)
    xr, yr, zr = np.asarray(p_rsole_world, dtype=float).tolist()
    xl, yl, zl = np.asarray(p_lsole_world, dtype=float).tolist()
    return np.array((0.5 * (xr + xl), 0.5 * (yr + yl), 0.5 * (zr + zl))), math.atan2(r10 + l10, r00 + l00)


def yaw_rotation(yaw_rad: float) -> np.ndarray:
    """Rz(yaw) (3, 3)."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array(((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0)))


@dataclass(frozen=True, slots=True)
class HandPose:
    """A hand target in F: position [m] and rotation (F <- hand)."""

    p_feet_m: np.ndarray  # (3,)
    R_feet_hand: np.ndarray  # (3, 3)

    @staticmethod
    def of(p_feet_m, R_feet_hand) -> HandPose:
        return HandPose(frozen_array(p_feet_m, (3,)), frozen_array(R_feet_hand, (3, 3)))

    @staticmethod
    def owned(p_feet_m: np.ndarray, R_feet_hand: np.ndarray) -> HandPose:
        """of() for float64 arrays (3,) and (3, 3) the caller has just computed and hands over: frozen in
        place, not copied."""
        return HandPose(read_only(p_feet_m), read_only(R_feet_hand))

    def integrated(self, twist: Twist, dt_s: float) -> HandPose:
        """One tick of `twist` (F axes): p += v dt, R = exp([w] dt) R."""
        v, w = twist.linear_m_s.tolist(), twist.angular_rad_s.tolist()
        if not any(w):  # a pure translation keeps the rotation (exp(0) R = R)
            if not any(v):
                return self
            R = self.R_feet_hand
        else:
            R = read_only(pin.exp3(twist.angular_rad_s * dt_s) @ self.R_feet_hand)
        p = self.p_feet_m if not any(v) else read_only(self.p_feet_m + twist.linear_m_s * dt_s)
        return HandPose(p, R)  # both read-only float64 arrays of their own (what HandPose.of makes)


    def step_to(self, other: HandPose, length_m: float) -> np.ndarray:
        """(6,) the step from this pose to `other`: translation [m] and rotation (F axes, left) [rad] times
        `length_m`, so the two weigh alike."""
        w = pin.log3(other.R_feet_hand @ self.R_feet_hand.T)
        return np.concatenate((other.p_feet_m - self.p_feet_m, length_m * w))

    def advanced_along(self, target: HandPose, achieved: HandPose, length_m: float) -> HandPose:
        """From this pose toward `target` by the share of that step `achieved` made along it
        (operation.limits.share_along over step_to with `length_m`): the target of a limited hand. A step
        without rotation (`target` keeps this rotation object, as integrated() does) needs no log or exp."""
        if target.R_feet_hand is not self.R_feet_hand:
            share = share_along(self.step_to(target, length_m), self.step_to(achieved, length_m))
            return self.advanced(target, share)
        p0 = self.p_feet_m.tolist()
        dp = [a - b for a, b in zip(target.p_feet_m.tolist(), p0, strict=True)]
        da = [a - b for a, b in zip(achieved.p_feet_m.tolist(), p0, strict=True)]
        n2 = dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2]
        if not n2 > 0.0:
            return self
        share = (da[0] * dp[0] + da[1] * dp[1] + da[2] * dp[2]) / n2
        if share >= 1.0:
            return target
        if share <= 0.0:
            return self
        return HandPose.owned(np.array([b + share * d for b, d in zip(p0, dp, strict=True)]), self.R_feet_hand)

    def advanced(self, other: HandPose, share: float) -> HandPose:
        """`share` [0, 1] of the way from this pose to `other`, along the straight line and the geodesic."""
        if share >= 1.0:
            return other
        if share <= 0.0:
            return self
        w = pin.log3(other.R_feet_hand @ self.R_feet_hand.T)
        return HandPose.owned(self.p_feet_m + share * (other.p_feet_m - self.p_feet_m),
                              pin.exp3(share * w) @ self.R_feet_hand)


@dataclass(frozen=True, slots=True)
class GazeAngles:
    """The gaze in F: pitch [rad] (> 0 looks down) and yaw [rad] (> 0 to the left)."""

    pitch_rad: float
    yaw_rad: float

    def integrated(self, twist: Twist, dt_s: float) -> GazeAngles:
        _, w_pitch, w_yaw = twist.angular_rad_s.tolist()
        if not (w_pitch or w_yaw):
            return self
        return GazeAngles(self.pitch_rad + w_pitch * dt_s, self.yaw_rad + w_yaw * dt_s)

    def direction_feet(self) -> np.ndarray:
        """Unit gaze axis (3,) in F."""
        cp = math.cos(self.pitch_rad)
        return np.array((cp * math.cos(self.yaw_rad), cp * math.sin(self.yaw_rad), -math.sin(self.pitch_rad)))

    @staticmethod
    def of_direction(d_feet: np.ndarray) -> GazeAngles:
        """The angles of a gaze axis (3,) in F (need not be unit)."""
        x, y, z = (float(v) for v in d_feet)
        return GazeAngles(math.atan2(-z, math.hypot(x, y)), math.atan2(y, x))


@dataclass(frozen=True, slots=True)
class WaistPose:
    """The waist (BODY) target: height above F [m] and roll, pitch, yaw [rad] in F."""

    height_m: float
    rpy_rad: tuple[float, float, float]

    def integrated(self, twist: Twist, dt_s: float) -> WaistPose:
        if twist.is_zero:
            return self
        r, p, y = self.rpy_rad
        wr, wp, wy = twist.angular_rad_s.tolist()
        return WaistPose(self.height_m + float(twist.linear_m_s[2]) * dt_s,
                         (r + wr * dt_s, p + wp * dt_s, y + wy * dt_s))


def status_layout(pose, anchor: np.ndarray) -> tuple[float, ...] | None:
    """A target as the status gives it, in F: a hand (x, y, z [m], roll, pitch, yaw [rad]) held relative to
    `anchor` (BODY in F while walking, else 0) plus the anchor; a gaze (pitch, yaw [rad]); a waist (height [m],
    roll, pitch, yaw [rad]); None for no target."""
    if pose is None:
        return None
    if isinstance(pose, HandPose):
        return (*(pose.p_feet_m + anchor).tolist(), *matrix_to_rpy_floats(pose.R_feet_hand))
    if isinstance(pose, GazeAngles):
        return (pose.pitch_rad, pose.yaw_rad)
    if hasattr(pose, "offset_m"):  # a foot (controller.operation.foot_point.FootOffset)
        return tuple(pose.offset_m)
    return (pose.height_m, *pose.rpy_rad)
