"""[OP] Fig. 7(c), issue 11: after `approach_table`, stick setpoints streamed through the operator service and
the gripper buttons alone take the unknown object from the floor and leave it on the table
(app/experiments/floor_object.py). The simulator's pose of the object is read only here, for the verdict."""

from __future__ import annotations

import pytest

import robot.generate as gen
from app.experiments.floor_object import run

pytestmark = pytest.mark.slow


def test_joystick_only_puts_the_unknown_object_from_the_floor_on_the_table():
    r = run()
    assert r.succeeded, "\n".join([r.verdict, *r.log])
    assert not r.fallen
    x, y, z = r.object_end_m
    depth, width, height = gen.EXPO_TABLE_SIZE_M
    assert z == pytest.approx(height + gen.UNKNOWN_OBJECT_SIZE_M[2] / 2, abs=0.005)  # resting upright on the top
    assert gen.EXPO_TABLE_NEAR_EDGE_X_M < x < gen.EXPO_TABLE_NEAR_EDGE_X_M + depth
    assert abs(y - gen.EXPO_TABLE_CENTRE_Y_M) < width / 2
