"""The push envelope with a foot operated (the random operator's, app/lab/campaign/grammar.py PUSH_ENVELOPE_NS):
the right foot lifted 5 cm by its operational point (the robot on its left foot, no step to catch a push), a 10 N s
push on BODY in each of 8 directions: the robot stands. Measured (stop 36): 8 of 8 stand lifted, 8 of 8 while the
weight goes over (the flag rose in 3); at 15 N s lifted, 2 of 8 fall (pushed left, 90 deg, and right, 270 deg)."""

from __future__ import annotations

import math

import pytest

from app.lab.campaign.grammar import PUSH_ENVELOPE_NS
from app.service.local import LocalRobot
from app.service.setpoints import Setpoint

pytestmark = pytest.mark.slow

PUSH_S = 0.1


@pytest.mark.parametrize("direction_deg", range(0, 360, 45))
def test_a_push_inside_the_envelope_with_a_foot_lifted_leaves_the_robot_standing(direction_deg):
    impulse_ns = PUSH_ENVELOPE_NS["foot"]
    robot = LocalRobot("default", speed=None)
    obs = robot.run_for(2.5)
    up = Setpoint("rfoot", (0.0, 0.0, 0.05), (0.0, 0.0, 0.0))
    held = Setpoint("rfoot", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    for k in range(int(round(9.0 / 0.005))):
        t = k * 0.005
        if k % 8 == 0:
            robot.put_setpoint(up if t < 2.6 else held)
        if k == int(round(3.5 / 0.005)):
            assert obs.layers["abc"].foot_lift == "lifted"
            a = math.radians(direction_deg)
            robot.plant.push("BODY", (impulse_ns / PUSH_S * math.cos(a), impulse_ns / PUSH_S * math.sin(a), 0.0),
                             PUSH_S)
        obs = robot.step()
        assert not obs.fallen, f"fell {t - 3.5:.2f} s after a {impulse_ns:g} N s push at {direction_deg} deg"
