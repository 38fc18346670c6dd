"""Closed-form leg IK agrees with the URDF's forward kinematics."""

import numpy as np
import pytest

from controller.kinematics.leg_ik import LEG_INDICES, LLEG, RLEG, leg_ik
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import rpy_to_matrix

KIN = RobotKinematics()


@pytest.mark.parametrize("leg,geom,sole", [("rleg", RLEG, "rleg_end"), ("lleg", LLEG, "lleg_end")])
def test_ik_inverts_forward_kinematics_at_random_leg_configurations(leg, geom, sole):
    rng = np.random.default_rng(3)
    idx = LEG_INDICES[leg]
    lo, hi = KIN.q_lower[idx], KIN.q_upper[idx]
    for _ in range(50):
        q = np.zeros(30)
        q[idx] = rng.uniform(lo, hi)
        q[idx[3]] = rng.uniform(0.05, 2.4)  # knee bent: the solver picks the positive-knee branch
        base_pos = rng.uniform(-0.2, 0.2, 3) + np.array([0, 0, 0.65])
        base_R = rpy_to_matrix(rng.uniform(-0.3, 0.3, 3))
        KIN.update(base_pos, base_R, q)
        p, R = KIN.frame_pose(sole)
        q_ik, ok = leg_ik(geom, base_pos, base_R, p, R)
        assert ok
        KIN.update(base_pos, base_R, np.where(np.isin(np.arange(30), idx), 0.0, q) + _scatter(idx, q_ik))
        p2, R2 = KIN.frame_pose(sole)
        assert np.linalg.norm(p2 - p) < 1e-9
        assert np.linalg.norm(R2 - R) < 1e-9


def _scatter(idx, values):
    out = np.zeros(30)
    out[idx] = values
    return out


def test_half_sitting_is_recovered_from_its_sole_pose():
    q = np.deg2rad([0, 0, -26, 50, -24, 0] * 2 + [0] * 18)
    base = np.array([0.0, 0.0, 0.648702])
    KIN.update(base, np.eye(3), q)
    p, R = KIN.frame_pose("rleg_end")
    q_ik, ok = leg_ik(RLEG, base, np.eye(3), p, R)
    assert ok and np.allclose(q_ik, q[:6], atol=1e-9)
    assert abs(p[2]) < 1e-3


def test_unreachable_target_straightens_the_knee_and_says_so():
    q_ik, ok = leg_ik(RLEG, np.array([0, 0, 0.65]), np.eye(3), np.array([0.0, -0.095, -0.5]), np.eye(3))
    assert not ok
    assert q_ik[3] == pytest.approx(0.0)
    assert np.all(np.isfinite(q_ik))
