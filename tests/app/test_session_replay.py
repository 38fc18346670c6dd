"""Record and replay: a short operator session, paced at real time in the loop's own thread (walking by
goVelocity, a hand streamed like a joystick, a behaviour, a parameter change, an e-stop and its release), replays
bit for bit through a fresh simulation as fast as possible; an input left out is found at its tick."""

import dataclasses
import time

import pytest

from app.service import OperatorService
from app.service.errors import Refused
from app.service.local import LocalRobot
from app.service.setpoints import Setpoint
from app.service.verbs import ReleaseEstop
from app.session.reader import read_session
from app.session.replay import replay

STREAM_HZ = 50.0


def _wait_sim(robot, t_s, timeout_s=30.0):
    deadline = time.monotonic() + timeout_s
    while robot.latest().snapshot.time_s < t_s:
        assert time.monotonic() < deadline, f"the paced loop did not reach t = {t_s} s"
        time.sleep(0.005)


def _stream(service, seconds, linear):
    """The operator's stick on the right hand, as the page streams it (PUT-like setpoints at 50 Hz)."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        service.put_setpoint(Setpoint("rhand", linear, (0.0, 0.0, 0.0)))
        time.sleep(1.0 / STREAM_HZ)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    path = tmp_path_factory.mktemp("session") / "operator.mcap"
    robot = LocalRobot(speed=1.0, record=path)
    service = OperatorService(robot)
    robot.start()
    try:
        _wait_sim(robot, 2.1)  # the AutoBalancer and the Stabilizer have blended in
        service.set_params({"op": {"deadman_timeout_s": 0.25}})
        service.go_velocity(0.1, 0.0, 0.0)
        _stream(service, 1.0, (0.0, 0.0, 0.03))
        service.walk_stop()
        service.run_behavior("squat", {"depth_m": 0.03})
        _stream(service, 0.4, (0.02, 0.0, 0.0))
        service.estop()
        time.sleep(0.3)
        service.release_estop()
        time.sleep(0.6)
        status = robot.stop_recording()
    finally:
        robot.close()
    assert status["error"] is None
    return read_session(path)


def test_an_operator_session_replays_bit_for_bit_at_max_speed(recorded):
    session = recorded
    assert session.complete and session.ticks > 800  # > 4 s at 5 ms
    kinds = {(d["kind"], d["phase"]) for d in session.inputs}
    assert {("verb", "boundary"), ("estop", "boundary"), ("setpoints", "hook")} <= kinds
    names = [d["name"] for d in session.inputs if d["kind"] == "verb"]
    assert names == ["set_params", "go_velocity", "walk_stop", "run_behavior", "release_estop"]
    assert session.params[0]["changes"] == {"op": {"deadman_timeout_s": 0.25}}
    assert [r["state"] for r in session.behaviors[-1]["runs"]] == ["cancelled"]  # the e-stop cancelled the squat
    result = replay(session)
    assert result.identical, result.summary()
    assert result.ticks == session.ticks and result.inputs == len(session.inputs)


def test_a_replay_without_the_estop_differs_from_its_tick_on(recorded):
    estop = next(d for d in recorded.inputs if d["kind"] == "estop")
    tampered = dataclasses.replace(recorded, inputs=[d for d in recorded.inputs if d is not estop])
    result = replay(tampered)
    assert not result.identical
    assert result.difference.tick == estop["tick"], str(result.difference)
    assert result.difference.what == "row" and "flags/hard_stop" in result.difference.columns


def test_a_recognition_late_at_real_time_is_not_waited_for_and_replays_where_it_entered(tmp_path, monkeypatch):
    """Paced, no tick waits for a camera: a result not ready when due enters at a later boundary, the session
    says which, and the replay (as fast as possible, where results are waited for) holds it until there."""
    from behaviors.perception import worker

    monkeypatch.setattr(worker, "RECOGNITION_DELAY_S", 0.0)  # due at once: the render and the fit are later
    path = tmp_path / "late.mcap"
    robot = LocalRobot("expo", speed=1.0, record=path)
    service = OperatorService(robot)
    robot.host.start_cameras()
    robot.host.cameras().wait_ready()
    robot.start()
    try:
        _wait_sim(robot, 2.1)
        run_id = service.run_behavior("locate_can", {"x_m": 2.15, "y_m": 0.0, "z_m": 0.75, "views": 1})
        deadline = time.monotonic() + 30.0
        while service.get_run(run_id).state == "running":
            assert time.monotonic() < deadline, "locate_can did not end"
            time.sleep(0.05)
        assert service.get_run(run_id).state == "succeeded", service.get_run(run_id)
        status = robot.stop_recording()
    finally:
        robot.close()
    assert status["error"] is None
    session = read_session(path)  # (the lateness of the ticks meanwhile: bench --scenario recognition-paced)
    events = {}  # capture number -> [(name, tick)]
    for d in session.inputs:
        if d["kind"] == "capture":
            events.setdefault(d["input"], []).append((d["name"], d["tick"]))
    assert events, "no result was late (each is due at once)"
    for n, seen in events.items():  # each was late, then entered ticks later
        assert [name for name, _ in seen] == ["result_late", "result_entered"], (n, seen)
        assert seen[1][1] > seen[0][1], (n, seen)
    result = replay(session)
    assert result.identical, result.summary()
    # without them, the replay takes each result when due (waiting for it) and differs from that tick on
    untold = dataclasses.replace(session, inputs=[d for d in session.inputs if d["kind"] != "capture"])
    first_due = min(seen[0][1] for seen in events.values())
    result = replay(untold)
    assert not result.identical and result.difference.tick >= first_due, result.summary()


def test_a_session_started_by_a_reset_after_a_streamed_hand_replays_bit_for_bit(tmp_path):
    # soak seed 10230: the operation layer's IK, shared across resets, went on from the posture it had solved
    # before the reset: the hand streamed on into the new stretch jumped there, the robot fell 1.8 s in, and the
    # stretch's replay (a fresh process) differed from its first tick
    robot = LocalRobot(speed=None)
    stick = Setpoint("lhand", (0.04, 0.08, -0.09), (0.08, -0.26, 0.08))
    try:
        robot.run_for(3.0)
        for k in range(200):
            if k % 8 == 0:
                robot.put_setpoint(stick)
            robot.step()
        robot.host.start_recording(tmp_path / "s.mcap", reset=True)
        for k in range(int(3.0 / 0.005)):
            if k % 8 == 0 and k < 300:
                robot.put_setpoint(stick)
            assert not robot.step().fallen
        robot.host.stop_recording()
        robot.host.last_recorder.wait()
    finally:
        robot.close()
    result = replay(read_session(tmp_path / "s.mcap"))
    assert result.identical, result.first_difference


def test_a_release_refused_for_a_press_after_it_and_the_release_after_replay_bit_for_bit(tmp_path):
    # a release carries the console's monotonic time when it was sent, a clock the replay does not share: the
    # refused one changed nothing and is not applied again, the accepted one is applied unchecked
    robot = LocalRobot(speed=None)
    try:
        robot.host.start_recording(tmp_path / "s.mcap", reset=True)
        robot.run_for(2.5)
        robot.host.engage_estop("page-1:1")
        sent_s = time.monotonic()
        robot.run_for(0.1)
        robot.host.engage_estop("page-2:1")  # another client, after the release below was sent
        with pytest.raises(Refused):
            robot.submit(ReleaseEstop(0, sent_s)).result()
        robot.run_for(0.3)
        assert robot.host.loop.hard_stop_engaged
        robot.submit(ReleaseEstop(0, time.monotonic())).result()
        robot.run_for(0.5)
        assert not robot.host.loop.hard_stop_engaged
        robot.host.stop_recording()
        robot.host.last_recorder.wait()
    finally:
        robot.close()
    session = read_session(tmp_path / "s.mcap")
    result = replay(session)
    assert result.identical, result.first_difference
