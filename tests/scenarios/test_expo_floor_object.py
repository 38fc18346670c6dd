"""[OP] Fig. 7(c), issue 11: after `approach_table`, stick setpoints streamed through the operator service and
the gripper buttons alone take the unknown object from the floor (app/experiments/floor_object.py). The
simulator's pose of the object is read only for the verdict.

So far the run goes as far as the lift: standing up with the object sets the capture-point flag (the
EmergencyStopper stops the motion), so the table part is not asserted yet (`run(through="table")`)."""

from __future__ import annotations

import pytest

from app.experiments.floor_object import run

pytestmark = pytest.mark.slow


def test_joystick_only_grasps_the_unknown_object_on_the_floor_and_lifts_it():
    r = run(through="lift")
    assert r.succeeded, "\n".join([r.verdict, *r.log])
    assert not r.fallen
    assert r.lifted_m >= 0.07  # the hand rose 0.090 m; measured: see the log
