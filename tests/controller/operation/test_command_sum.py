"""[OP] Eq. 5 per tick: the operator's streamed twists plus the behaviours', the latter for one tick (unit)."""

import numpy as np
import pytest

from controller.core.types import WalkCommand
from controller.operation.command_sum import CommandSum
from controller.operation.points import Twist


def test_the_operators_and_the_behaviours_twists_add_per_point():
    c = CommandSum()
    c.streamed.set("rhand", Twist.of((0.1, 0.0, 0.0)), 0.0)
    c.set_behavior({"rhand": Twist.of((0.0, 0.0, 0.05)), "lhand": Twist.of((0.0, 0.02, 0.0))})
    total, changed = c.take(0.0, 0.2, 0.1)
    assert changed
    assert np.allclose(total["rhand"].linear_m_s, (0.1, 0.0, 0.05))
    assert np.allclose(total["lhand"].linear_m_s, (0.0, 0.02, 0.0))
    assert set(c.motion) == {"rhand"} and set(c.behavior) == {"rhand", "lhand"}  # kept for the status


def test_the_behaviours_count_for_one_take_and_the_change_is_reported_once_after():
    c = CommandSum()
    c.set_behavior({"head": Twist.of(angular_rad_s=(0.0, 0.1, 0.0))})
    assert c.take(0.0, 0.2, 0.1)[0]
    total, changed = c.take(0.005, 0.2, 0.1)
    assert total == {} and changed  # the status' behaviour twist goes back to zero
    assert c.take(0.01, 0.2, 0.1) == ({}, False)  # nothing before, nothing now


def test_the_operators_twist_fades_under_the_dead_man():
    c = CommandSum()
    c.streamed.set("rhand", Twist.of((0.1, 0.0, 0.0)), 0.0)
    assert c.take(0.25, 0.2, 0.1)[0]["rhand"].linear_m_s[0] == pytest.approx(0.05)
    assert c.take(0.31, 0.2, 0.1)[0] == {}


def test_the_walking_step_parameters_are_the_operators_else_the_behaviours():
    c = CommandSum()
    assert c.walk_steps() is None
    theirs, mine = WalkCommand(0, 0, 0, max_stride_m=0.1), WalkCommand(0, 0, 0, max_stride_m=0.2)
    c.set_behavior({}, theirs)
    assert c.walk_steps() is theirs
    c.streamed.set("walk", Twist.of((0.1, 0.0, 0.0)), 0.0, mine)
    assert c.walk_steps() is mine
