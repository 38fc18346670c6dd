"""Scenario: `grasp` and `release` on the simulated JRL-hand, through the operator service's verbs (the
behaviour runs inside the loop, its commands through the service's own verbs)."""

from __future__ import annotations

import math

import pytest

from app.service import OperatorService, Refused
from app.service.local import LocalRobot
from robot.names import joint_index

GRIP = joint_index("RARM_JOINT6")
#: measured: the closed jaw rests 0.06 deg short of its 16 deg limit (the pad against the fixed jaw), the open
#: one 0.02 deg short of -60 deg; bound 0.5 deg
JAW_TOLERANCE_DEG = 0.5


def _until_done(robot: LocalRobot, service: OperatorService, run_id: int, timeout_s: float = 5.0):
    for _ in range(int(timeout_s / robot.loop.dt_control_s)):
        robot.step()
        status = service.get_run(run_id)
        if status.state != "running":
            return status
    raise AssertionError(f"run {run_id} still running after {timeout_s} s")


@pytest.fixture
def robot():
    r = LocalRobot(speed=None)
    r.run_for(0.2)
    yield r
    r.stop()


def test_release_opens_and_grasp_closes_the_jaw_on_nothing_within_the_force_limit(robot):
    service = OperatorService(robot)
    opened = _until_done(robot, service, service.run_behavior("release", {"time_s": 0.5}))
    assert opened.state == "succeeded", opened.message
    assert abs(math.degrees(robot.loop.snapshot.q_meas_rad[GRIP]) - (-60.0)) < JAW_TOLERANCE_DEG
    closed = _until_done(robot, service, service.run_behavior("grasp", {"time_s": 0.5, "require_object": False}))
    assert closed.state == "succeeded" and closed.result["holding"] is False
    assert abs(math.degrees(robot.loop.snapshot.q_meas_rad[GRIP]) - 16.0) < JAW_TOLERANCE_DEG
    assert closed.result["force_n"] <= 14.0
    # a grasp that needs an object fails on an empty hand, and says so
    _until_done(robot, service, service.run_behavior("release", {"time_s": 0.5}))
    empty = _until_done(robot, service, service.run_behavior("grasp", {"time_s": 0.5}))
    assert empty.state == "failed" and empty.message.startswith("the jaw closed on nothing")


def test_a_cancelled_release_leaves_the_jaw_where_it_was(robot):
    service = OperatorService(robot)
    rid = service.run_behavior("release", {"time_s": 2.0})
    robot.run_for(0.6)
    assert service.cancel_run(rid).state == "cancelled"
    robot.run_for(0.3)  # the servo settles on the angle it had when cancelled
    here = robot.loop.snapshot.q_meas_rad[GRIP]
    robot.run_for(1.0)
    assert abs(math.degrees(robot.loop.snapshot.q_meas_rad[GRIP] - here)) < 0.1  # measured 4e-5 deg, bound 0.1 deg
    assert -55.0 < math.degrees(here) < 10.0  # stopped part-way


def test_behaviour_commands_meet_the_operators_refusals(robot):
    service = OperatorService(robot)
    service.estop()
    with pytest.raises(Refused) as err:
        service.run_behavior("release")
    assert err.value.reason == "hard_stop"
    service.release_estop()
    service.stop_motion()  # the EmergencyStopper holds the motion: the SequencePlayer's verbs are refused
    robot.run_for(0.05)
    with pytest.raises(Refused) as err:
        service.run_behavior("release")
    assert err.value.reason == "motion_stop"
