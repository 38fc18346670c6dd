"""The robot in its own process: verbs over the command pipe, the e-stop over its own, snapshots on the
shared-memory board; a crash the console survives and a reset recovers from."""

import time

import pytest

from app.service import OperatorService, Refused, Unavailable
from app.service.process import RobotConfig, RobotProcess


def wait_for(predicate, timeout_s=20.0, period_s=0.01):
    deadline = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        assert time.monotonic() < deadline, "condition not reached in time"
        time.sleep(period_s)


@pytest.fixture(scope="module")
def robot():
    rp = RobotProcess(RobotConfig(speed=None))  # as fast as it can: the tests wait on simulated time
    yield rp
    rp.close()


def test_the_robot_process_publishes_snapshots_and_answers_verbs(robot):
    service = OperatorService(robot)
    t0 = service.snapshot().time_s
    wait_for(lambda: service.snapshot().time_s > t0 + 0.5)
    assert robot.process.pid and robot.alive
    assert service.info.chain[0] == "kf" and "hes" in service.info.chain
    assert service.is_interpolating() is False
    assert "interpolating" in service.set_some_joint_angles({"HEAD_JOINT0": 0.2}, 0.2)
    state = service.state()
    assert state["tick"] > 0 and state["emergency"]["hard_stop"] is False


def test_the_estop_takes_its_own_path_and_is_confirmed_by_the_loop(robot):
    service = OperatorService(robot)
    ack = service.estop()
    assert ack.tick > 0 and not ack.already_engaged
    assert service.estop().already_engaged
    wait_for(lambda: service.state()["emergency"]["hard_stop"])
    with pytest.raises(Refused) as info:
        service.go_velocity(0.1, 0.0, 0.0)
    assert info.value.reason == "hard_stop"
    service.release_estop()
    wait_for(lambda: not service.state()["emergency"]["hard_stop"])


def test_a_crash_of_the_robot_process_is_reported_and_a_reset_starts_a_new_one():
    robot = RobotProcess(RobotConfig(speed=None))
    try:
        service = OperatorService(robot)
        pid = robot.process.pid
        robot.kill_for_test()
        wait_for(lambda: not robot.alive)
        assert "exit code" in robot.exit_reason
        with pytest.raises(Unavailable, match="reset"):
            service.state()
        with pytest.raises(Unavailable):
            service.go_pos(0.1, 0.0, 0.0)
        with pytest.raises(Unavailable):
            service.estop()
        service.reset()
        assert robot.alive and robot.process.pid != pid
        wait_for(lambda: service.snapshot().tick > 10)
        assert service.state()["emergency"]["hard_stop"] is False
    finally:
        robot.close()
