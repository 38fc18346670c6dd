"""Per-point speed limits with one scale factor, and the reach clamp (unit)."""

import numpy as np
import pytest

from controller.core.errors import InvalidCommand
from controller.operation.limits import JOINT_LIMIT, MOTION_STOP, REACH, VELOCITY, clamp_to_achieved, limit_twist
from controller.operation.points import Twist


def test_a_twist_under_its_limits_passes_unchanged():
    t = Twist.of((0.1, 0.0, 0.0), (0.0, 0.0, 0.2))
    out = limit_twist(t, 0.3, 1.0)
    assert out.scale == 1.0 and out.twist is t


def test_one_scale_factor_keeps_the_direction_of_a_too_fast_twist():
    t = Twist.of((0.3, 0.4, 0.0), (0.0, 0.0, 0.1))  # 0.5 m/s
    out = limit_twist(t, 0.25, 1.0)
    assert out.scale == pytest.approx(0.5)
    assert np.allclose(out.twist.linear_m_s, (0.15, 0.2, 0.0))
    assert np.allclose(out.twist.angular_rad_s, (0.0, 0.0, 0.05))  # the angular part slows down with it


def test_the_smaller_of_the_linear_and_angular_factors_wins():
    t = Twist.of((0.1, 0.0, 0.0), (0.0, 2.0, 0.0))  # linear fine, angular 4x over
    out = limit_twist(t, 0.5, 0.5)
    assert out.scale == pytest.approx(0.25)
    assert np.allclose(out.twist.linear_m_s, (0.025, 0.0, 0.0))


def test_a_non_positive_limit_is_refused():
    with pytest.raises(InvalidCommand, match="must be > 0"):
        limit_twist(Twist.of((0.1, 0, 0)), 0.0, 1.0)


def test_a_target_the_ik_cannot_reach_is_clamped_to_the_achieved_pose():
    target, achieved = "target", "achieved"
    assert clamp_to_achieved(target, achieved, None) is target
    for reason in (REACH, JOINT_LIMIT, VELOCITY):
        assert clamp_to_achieved(target, achieved, reason) is achieved
    assert clamp_to_achieved(target, achieved, MOTION_STOP) is target  # frozen, not clamped
    with pytest.raises(InvalidCommand, match="valid"):
        clamp_to_achieved(target, achieved, "tired")
