"""Findings of the random-operator campaign (issue 27), each shrunk to its actions and replayed in process on the
simulated robot: the verbs and stick setpoints the session sent, at the times it sent them."""

import math

import pytest

from app.service.errors import Refused
from app.service.local import LocalRobot
from app.service.setpoints import Setpoint
from app.service.verbs import GoVelocity, WalkStop

STICK_PERIOD_TICKS = 8  # the page streams a held stick every 40 ms

WAIST_STICK = Setpoint("waist", (0.0, 0.0, 0.0365), tuple(math.radians(w) for w in (-5.67, -9.69, -6.57)))
WALK_STICK = Setpoint("walk", (-0.0952, 0.1181, 0.0), (0.0, 0.0, math.radians(19.41)), max_stride_m=0.264,
                      foot_distance_m=0.237)


def replay(actions, until_s: float):
    """Run the (session time [s], verb or (setpoint, held [s])) list; the observation at the end or the fall."""
    robot = LocalRobot("default")
    robot.run_for(2.5)
    t0 = robot.step().time_s
    pending, stick = sorted(actions, key=lambda a: a[0]), None
    for k in range(int(round(until_s / 0.005))):
        obs = robot.step()
        t = obs.time_s - t0
        while pending and t >= pending[0][0]:
            _, action = pending.pop(0)
            if isinstance(action, tuple):
                stick = (action[0], t + action[1])
            else:
                robot.submit(action).result()
        if stick is not None and k % STICK_PERIOD_TICKS == 0:
            if t < stick[1]:
                robot.put_setpoint(stick[0])
            else:
                stick = None
        assert obs.safety.fault is None, f"controller fault at {t:.3f} s: {obs.safety.fault}"
        if obs.fallen:
            return obs
    return obs


BACKWARD_TURNING = [(2.46, GoVelocity(-0.135, -0.1405, math.radians(-18.23))),
                    (8.44, GoVelocity(-0.0762, -0.0482, math.radians(-27.98))), (9.57, WalkStop())]


@pytest.mark.slow
@pytest.mark.parametrize("after_stop_s", [1.6, 1.7, 1.8])
def test_seed_1009_a_walk_stick_in_the_final_double_support_walks_on_without_a_fault(after_stop_s):
    # the walk point pressed in the ending walk's last double support raised in goStop: a controller fault
    obs = replay([*BACKWARD_TURNING, (9.57 + after_stop_s, (WALK_STICK, 0.48))], 12.0)
    assert not obs.fallen


@pytest.mark.slow
def test_seed_1009_a_waist_stick_through_a_backward_walk_and_a_walk_stick_after_it_end_standing():
    # the waist stick raised the CP flag at the walk's end and a walk stick started a walk under it, which fell;
    # now the waist keeps the legs' walking range (no flag) and no walk starts under a raised flag (unit-tested)
    actions = [*BACKWARD_TURNING, (7.95, (WAIST_STICK, 1.54)), (11.27, (WALK_STICK, 0.48))]
    assert not replay(actions, 16.0).fallen


@pytest.mark.slow
@pytest.mark.parametrize("roll_deg_s", [7.61, -7.61])
def test_seeds_1017_1018_the_waist_rolls_until_the_hip_has_range_left_and_a_walk_then_waits_for_it(roll_deg_s):
    # a waist stick rolled BODY 19 deg: a hip roll sat at its limit, the sole tipped onto its edge, the CP flag
    # rose standing, and a walk then fell
    robot = LocalRobot("default")
    robot.run_for(2.5)
    stick = Setpoint("waist", (0.0, 0.0, 0.0), (math.radians(roll_deg_s), 0.0, 0.0))
    limited = False
    for k in range(int(round(3.5 / 0.005))):
        if k % STICK_PERIOD_TICKS == 0 and k * 0.005 < 2.47:
            robot.put_setpoint(stick)
        obs = robot.step()
        assert not obs.layers["st"].emergency, f"the CP flag rose at {k * 0.005:.3f} s into the roll"
        limited = limited or obs.layers["op"].points["waist"].limited == "reach"
    assert limited  # the operator was told while pushing the stick
    waist = obs.layers["op"].points["waist"]
    assert 8.0 < abs(math.degrees(waist.achieved[1])) < 14.0, waist  # held at 11.5 deg (measured), not 19
    with pytest.raises(Refused, match=r"LEG_JOINT1 is .* deg from its limit"):
        robot.submit(GoVelocity(0.16, 0.096, math.radians(27.3))).result()
    obs = robot.run_for(3.0)
    assert not obs.fallen and not obs.layers["abc"].walking
