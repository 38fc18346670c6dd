"""[OP] Fig. 7(c), issue 11: after `approach_table`, stick setpoints streamed through the operator service and
the gripper buttons alone take the unknown object from the floor and leave it on the table
(app/lab/experiments/floor_object.py). The simulator's pose of the object is read only for the verdict.

One run of the whole task (78 s simulated): the lift is asserted from the same run."""

from __future__ import annotations

import math

import pytest

import robot.generate as gen
from app.lab.experiments.floor_object import run

pytestmark = pytest.mark.slow

#: the object's footprint reaches this far from its centre at any yaw (half the diagonal of 0.08 x 0.055 m)
HALF_DIAGONAL_M = math.hypot(gen.UNKNOWN_OBJECT_SIZE_M[0], gen.UNKNOWN_OBJECT_SIZE_M[1]) / 2


def test_joystick_only_puts_the_unknown_object_from_the_floor_on_the_table():
    r = run(through="table")
    log = "\n".join([r.verdict, *r.log])
    assert r.succeeded, log
    assert not r.fallen, log
    assert r.lifted_m >= 0.07, log  # the hand rose 0.10 m with it; measured 95 mm
    # standing on the table top: centre at top + half height (measured -0.04 mm; margin 3 mm), upright
    # (measured 0.0 deg), its whole footprint inside the top's outline (measured 0.098 m in from the near edge)
    assert abs(r.on_table_error_mm) < 3.0, log
    assert r.tilt_deg < 2.0, log
    x, y, _ = r.object_end_m
    near = gen.EXPO_TABLE_NEAR_EDGE_X_M
    assert near + HALF_DIAGONAL_M < x < near + gen.EXPO_TABLE_SIZE_M[0] - HALF_DIAGONAL_M, log
    assert abs(y - gen.EXPO_TABLE_CENTRE_Y_M) < gen.EXPO_TABLE_SIZE_M[1] / 2 - HALF_DIAGONAL_M, log
    # released: the withdrawing hand did not take it along (measured 0.0 mm)
    assert r.moved_after_release_mm < 2.0, log
    # no capture-point flag on the way (the EmergencyStopper's 40 mm; measured 17 mm peak)
    assert r.cp_error_peak_mm < 40.0, log
