"""The walking point's twist as the goVelocity command: limited by one factor, one zero when it ends (unit)."""

import pytest

from controller.core.types import WalkCommand
from controller.operation.points import Twist
from controller.operation.walk_point import WalkPoint


def test_a_walk_twist_is_scaled_by_one_factor_and_carries_the_step_parameters():
    w = WalkPoint()
    steps = WalkCommand(0, 0, 0, max_stride_m=0.15, foot_distance_m=0.2)
    cmd = w.command(Twist.of((0.6, 0.0, 0.0), (0.0, 0.0, 0.2)), steps, 0.3, 0.5)
    assert (cmd.vx_m_s, cmd.vtheta_rad_s) == pytest.approx((0.3, 0.1))  # halved, turning halved too
    assert (cmd.max_stride_m, cmd.foot_distance_m) == (0.15, 0.2)
    assert w.active and w.status_target() == pytest.approx((0.3, 0.0, 0.1))


def test_a_held_stick_gives_the_same_command_object_and_the_end_one_zero_then_nothing():
    w = WalkPoint()
    twist = Twist.of((0.1, 0.0, 0.0))
    first = w.command(twist, None, 0.3, 0.5)
    assert w.command(Twist.of((0.1, 0.0, 0.0)), None, 0.3, 0.5) is first
    assert w.command(twist, None, 0.2, 0.5) is not first  # other limits: computed again
    stop = w.command(None, None, 0.3, 0.5)
    assert stop.is_zero and not w.active and w.status_target() is None
    assert w.command(Twist.of(), None, 0.3, 0.5) is None  # not driven any more
