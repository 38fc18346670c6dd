"""Per-point speed limits with one scale factor, and the reach clamp (unit)."""

import numpy as np
import pytest

from controller.core.errors import InvalidCommand
from controller.operation.limits import (
    JOINT_LIMIT,
    MOTION_STOP,
    REACH,
    VELOCITY,
    clamp_to_achieved,
    limit_twist,
    share_along,
)
from controller.operation.points import ZERO_TWIST as ZERO
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


def test_a_ramp_moves_the_twist_toward_the_goal_by_at_most_the_step_along_the_straight_line():
    from controller.operation.limits import ramp_twist

    forward, up = Twist.of((0.1, 0.0, 0.0)), Twist.of((0.0, 0.0, 0.05))
    step = ramp_twist(forward, up, 0.0025, 1.0)  # 0.5 m/s^2 over 5 ms
    change = np.asarray(step.linear_m_s) - np.asarray(forward.linear_m_s)
    assert np.linalg.norm(change) == pytest.approx(0.0025)
    direction = np.asarray(up.linear_m_s) - np.asarray(forward.linear_m_s)
    assert np.allclose(np.cross(change, direction), 0.0)  # along the line from one to the other
    t = forward
    for _ in range(45):  # |up - forward| = 0.1118 m/s: 44.7 steps of 2.5 mm/s
        t = ramp_twist(t, up, 0.0025, 1.0)
    assert t is up  # reached: the goal itself
    # the angular step limits too, one factor for both parts
    turn = ramp_twist(ZERO, Twist.of((0.01, 0.0, 0.0), (0.0, 0.0, 1.0)), 1.0, 0.02)
    assert np.allclose(turn.angular_rad_s, (0.0, 0.0, 0.02)) and np.allclose(turn.linear_m_s, (0.0002, 0.0, 0.0))
    with pytest.raises(InvalidCommand):
        ramp_twist(ZERO, up, 0.0, 1.0)


def test_the_share_along_is_the_projection_of_the_achieved_step_on_the_asked_one_within_0_and_1():
    asked = np.array([0.01, 0.0, 0.0, 0.0, 0.0, 0.0])
    assert share_along(asked, np.array([0.004, 0.003, -0.002, 0.0, 0.0, 0.0])) == pytest.approx(0.4)
    assert share_along(asked, 2 * asked) == 1.0 and share_along(asked, -asked) == 0.0
    assert share_along(np.zeros(6), asked) == 0.0  # nothing asked: nothing to advance
