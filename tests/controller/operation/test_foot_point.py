"""The foot point's pieces (controller/operation/foot_point.py): integration inside the reach, the refusals."""

from __future__ import annotations

import pytest

from controller.core.errors import InvalidCommand
from controller.operation.foot_point import RFOOT_REACH_M, FootOffset, check_foot_allowed, integrate_foot, reach_of
from controller.operation.limits import REACH, VELOCITY
from controller.operation.points import Twist
from controller.walking.foot_lift import CLEARANCE_M


def test_the_left_foot_reach_mirrors_the_right_one_across():
    (x, y, z) = RFOOT_REACH_M
    assert reach_of("lfoot") == (x, (-y[1], -y[0]), z)
    assert reach_of("rfoot")[1][1] > 0.0 and reach_of("lfoot")[1][0] < 0.0  # a little inward, never through


def test_a_foot_integrates_its_velocity_scaled_to_the_speed_limit():
    assert integrate_foot("rfoot", (0.0, 0.0, 0.02), Twist.of((0.1, 0.0, 0.0)), 0.2, 0.01) == \
        (pytest.approx((0.001, 0.0, 0.02)), None)
    offset, why = integrate_foot("rfoot", (0.0, 0.0, 0.02), Twist.of((0.3, 0.0, 0.4)), 0.1, 0.01)
    assert offset == pytest.approx((0.0006, 0.0, 0.0208)) and why == VELOCITY  # 0.5 m/s scaled to 0.1, same line


@pytest.mark.parametrize(("foot", "start", "v", "clamped"), [
    ("rfoot", (0.0, 0.0, 0.0), (0.0, 0.0, -0.1), (0.0, 0.0, CLEARANCE_M)),  # not onto the floor while lifted
    ("rfoot", (0.1, -0.1, 0.011), (0.0, 0.0, -0.1), (0.1, -0.1, CLEARANCE_M)),  # nor away from its rest place
    ("rfoot", (0.0, 0.029, 0.05), (0.0, 0.1, 0.0), (0.0, 0.03, 0.05)),  # not into the other foot
    ("lfoot", (0.0, -0.029, 0.05), (0.0, -0.1, 0.0), (0.0, -0.03, 0.05)),
    ("rfoot", (0.199, 0.0, 0.05), (0.1, 0.0, 0.0), (0.2, 0.0, 0.05)),
])
def test_a_foot_is_held_inside_its_reach(foot, start, v, clamped):
    offset, why = integrate_foot(foot, start, Twist.of(v), 0.1, 0.02)
    assert offset == pytest.approx(clamped) and why == REACH


def test_a_foot_is_refused_while_walking_and_one_at_a_time_and_the_walk_while_a_foot_is_up():
    up = {"rfoot": FootOffset((0.0, 0.0, 0.03))}
    with pytest.raises(InvalidCommand, match=r"rfoot: refused while walking"):
        check_foot_allowed("rfoot", Twist.of((0.0, 0.0, 0.1)), True, {})
    with pytest.raises(InvalidCommand, match=r"lfoot: the rfoot is operated; one foot at a time"):
        check_foot_allowed("lfoot", Twist.of((0.0, 0.0, 0.1)), False, up)
    with pytest.raises(InvalidCommand, match=r"walk: refused while the rfoot is operated"):
        check_foot_allowed("walk", Twist.of((0.1, 0.0, 0.0)), False, up)
    check_foot_allowed("walk", Twist.of(), False, up)  # a zero walking point passes (the stick at rest)
    check_foot_allowed("rfoot", Twist.of((0.0, 0.0, 0.1)), False, up)
