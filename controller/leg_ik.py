"""Closed-form inverse kinematics of an HRP-2 leg (yaw-roll-pitch hip, knee, pitch-roll ankle).

The leg is Rz(q0) Rx(q1) Ry(q2) [thigh L1] Ry(q3) [shin L2 with a lateral offset dy] Ry(q4) Rx(q5).
Pitch joints leave a lateral (y) vector unchanged, so the shin's offset can be solved with the ankle
roll first (Kajita's method extended by the offset), then the planar knee/ankle pitch, then the hip.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from robot.names import JOINT_GROUPS


@dataclass(frozen=True)
class LegGeometry:
    hip_offset_y_m: float  # BODY origin -> hip joints, along y [m] (+0.06 left, -0.06 right)
    thigh_m: float = 0.3  # hip pitch -> knee [m]
    shin_m: float = 0.3  # knee -> ankle, along -z [m]
    shin_offset_y_m: float = 0.0  # knee -> ankle, along y [m] (-0.035 right, +0.035 left)
    ankle_to_sole_m: float = 0.105


RLEG = LegGeometry(hip_offset_y_m=-0.06, shin_offset_y_m=-0.035)
LLEG = LegGeometry(hip_offset_y_m=0.06, shin_offset_y_m=0.035)
LEG_INDICES = {"rleg": np.array(JOINT_GROUPS["rleg"]), "lleg": np.array(JOINT_GROUPS["lleg"])}


def _rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array(((1.0, 0.0, 0.0), (0.0, c, -s), (0.0, s, c)))


def _ry(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array(((c, 0.0, s), (0.0, 1.0, 0.0), (-s, 0.0, c)))


def leg_ik(geom: LegGeometry, p_body_world: np.ndarray, R_world_body: np.ndarray,
           p_sole_world: np.ndarray, R_world_sole: np.ndarray) -> tuple[np.ndarray, bool]:
    """Six joint angles [rad] putting the sole frame at (p_sole, R_sole) for this BODY pose.

    Returns (q, reachable). An out-of-reach target straightens the knee (q3 = 0) and returns the
    closest pose with reachable = False, so a caller never gets NaN. Scalar maths on purpose:
    this runs several times per 5 ms tick.
    """
    L1, L2, dy = geom.thigh_m, geom.shin_m, geom.shin_offset_y_m
    p_hip = p_body_world + geom.hip_offset_y_m * R_world_body[:, 1]
    p_ankle = p_sole_world + geom.ankle_to_sole_m * R_world_sole[:, 2]
    r0, r1, r2 = R_world_sole.T @ (p_hip - p_ankle)  # hip seen from the ankle, ankle frame
    reachable = True
    # ankle roll: (Rx(q5) r)_y = -dy
    rho = math.hypot(r1, r2)
    ratio = min(1.0, max(-1.0, -dy / rho))
    q5 = math.acos(ratio) - math.atan2(r2, r1)
    q5 = (q5 + math.pi) % (2.0 * math.pi) - math.pi
    c5, s5 = math.cos(q5), math.sin(q5)
    w0, w2 = r0, s5 * r1 + c5 * r2  # Rx(q5) r, x and z
    # knee and ankle pitch in the remaining plane
    c3 = (w0 * w0 + w2 * w2 - L1 * L1 - L2 * L2) / (2.0 * L1 * L2)
    if c3 > 1.0:
        reachable, c3 = False, 1.0
    elif c3 < -1.0:
        reachable, c3 = False, -1.0
    q3 = math.acos(c3)
    psi = math.atan2(L1 * math.sin(q3), L1 * c3 + L2)
    q4 = math.atan2(-w0, w2) - psi
    # hip: Rz(q0) Rx(q1) Ry(q2) = R_body^T R_sole Rx(q5)^T Ry(q3 + q4)^T
    M = R_world_body.T @ R_world_sole @ _rx(-q5) @ _ry(-(q3 + q4))
    q1 = math.asin(min(1.0, max(-1.0, M[2, 1])))
    q0 = math.atan2(-M[0, 1], M[1, 1])
    q2 = math.atan2(-M[2, 0], M[2, 2])
    return np.array((q0, q1, q2, q3, q4, q5)), reachable
