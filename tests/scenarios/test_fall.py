"""A fall is detected from the robot's own sensors, ends in the safe stop, is reported with its reason,
refuses motion until a reset, and the reset recovers."""

import pytest

from app.service import OperatorService, Refused
from app.service.local import LocalRobot


@pytest.mark.slow
def test_a_70_newton_second_push_ends_in_the_safe_stop_reported_and_a_reset_recovers():
    robot = LocalRobot()
    service = OperatorService(robot)
    robot.run_for(2.5)
    # 1. a 70 N s push forward on BODY (beyond what the ankles absorb, 28 N s, and what the emergency step
    #    catches, 45 N s: 48 N s falls with the step)
    service.push("BODY", (700.0, 0.0, 0.0), 0.1)
    snap = robot.run_until(lambda s: s.safety.fall is not None, timeout_s=3.0)
    # 2. detected from the KF attitude (or unloaded feet) before the body hits the ground, in the safe stop
    assert snap.safety.hard_stop and snap.safety.hard_stop_reason == "fallen"
    robot.run_for(2.0)
    state = service.state()
    assert state["fallen"] is True and state["emergency"]["fall"] == snap.safety.fall
    assert state["emergency"]["hard_stop"] and state["emergency"]["hard_stop_reason"] == "fallen"
    # 3. nothing moves it until a reset: motion and the release are refused, naming the fall
    for verb in (lambda: service.go_pos(0.2, 0.0, 0.0),
                 lambda: service.set_some_joint_angles({"HEAD_JOINT0": 0.1}, 1.0), service.release_estop):
        with pytest.raises(Refused, match="fallen") as info:
            verb()
        assert info.value.reason == "fallen"
    # 4. the reset recovers: standing, no stop, walking accepted
    service.reset()
    robot.run_for(2.5)
    state = service.state()
    assert state["fallen"] is False and state["emergency"]["fall"] is None and not state["emergency"]["hard_stop"]
    assert "walking" in service.go_pos(0.1, 0.0, 0.0)
