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


def as_floats(a) -> list:
    """An array (or sequence) as nested Python floats."""
    return (a if isinstance(a, np.ndarray) else np.asarray(a, dtype=float)).tolist()


def leg_ik(geom: LegGeometry, p_body_world: np.ndarray, R_world_body: np.ndarray,
           p_sole_world: np.ndarray, R_world_sole: np.ndarray) -> tuple[np.ndarray, bool]:
    """Six joint angles [rad] putting the sole frame at (p_sole, R_sole) for this BODY pose.

    Returns (q, reachable). An out-of-reach target straightens the knee (q3 = 0) and returns the
    closest pose with reachable = False, so a caller never gets NaN. Scalar maths on purpose:
    this runs several times per 5 ms tick.
    """
    q, reachable = leg_ik_floats(geom, as_floats(p_body_world), as_floats(R_world_body),
                                  as_floats(p_sole_world), as_floats(R_world_sole))
    return np.array(q), reachable


def leg_ik_floats(geom: LegGeometry, p_body_world, R_world_body, p_sole_world, R_world_sole
                   ) -> tuple[tuple[float, ...], bool]:
    """leg_ik on Python floats: positions as 3 floats, rotations as 3 rows of 3 floats."""
    L1, L2, dy = geom.thigh_m, geom.shin_m, geom.shin_offset_y_m
    (b00, b01, b02), (b10, b11, b12), (b20, b21, b22) = R_world_body
    (s00, s01, s02), (s10, s11, s12), (s20, s21, s22) = R_world_sole
    bx, by, bz = p_body_world
    sx, sy, sz = p_sole_world
    h, a = geom.hip_offset_y_m, geom.ankle_to_sole_m
    # hip minus ankle, world frame (hip = body + h * body y axis, ankle = sole + a * sole z axis)
    d0 = (bx + h * b01) - (sx + a * s02)
    d1 = (by + h * b11) - (sy + a * s12)
    d2 = (bz + h * b21) - (sz + a * s22)
    r0 = s00 * d0 + s10 * d1 + s20 * d2  # hip seen from the ankle, ankle frame (R_sole^T d)
    r1 = s01 * d0 + s11 * d1 + s21 * d2
    r2 = s02 * d0 + s12 * d1 + s22 * d2
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
    # hip: Rz(q0) Rx(q1) Ry(q2) = M = R_body^T R_sole Rx(q5)^T Ry(q3 + q4)^T
    # A = R_body^T R_sole (the entries needed for M[0, 1], M[1, 1] and row 2 of M)
    a01 = b00 * s01 + b10 * s11 + b20 * s21
    a02 = b00 * s02 + b10 * s12 + b20 * s22
    a11 = b01 * s01 + b11 * s11 + b21 * s21
    a12 = b01 * s02 + b11 * s12 + b21 * s22
    a20 = b02 * s00 + b12 * s10 + b22 * s20
    a21 = b02 * s01 + b12 * s11 + b22 * s21
    a22 = b02 * s02 + b12 * s12 + b22 * s22
    # B = A Rx(-q5): Rx(-q5) = [[1, 0, 0], [0, c5, s5], [0, -s5, c5]]
    e01 = a01 * c5 - a02 * s5
    e11 = a11 * c5 - a12 * s5
    e21, e22 = a21 * c5 - a22 * s5, a21 * s5 + a22 * c5
    # M = B Ry(t), t = -(q3 + q4): Ry(t) = [[ct, 0, st], [0, 1, 0], [-st, 0, ct]]; the entries used below
    t = -(q3 + q4)
    ct, st = math.cos(t), math.sin(t)
    m20 = a20 * ct - e22 * st
    m22 = a20 * st + e22 * ct
    q1 = math.asin(min(1.0, max(-1.0, e21)))
    q0 = math.atan2(-e01, e11)
    q2 = math.atan2(-m20, m22)
    return (q0, q1, q2, q3, q4, q5), reachable
