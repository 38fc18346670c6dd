"""The operator service on a robot in this process: verbs and a reset while the loop thread runs, refusals
that name what is in the way, and the run statistics."""

import math
import time

import numpy as np
import pytest

from app.console.state import jsonable
from app.service import InvalidArgument, OperatorService, Refused
from app.service.local import LocalRobot
from robot.names import JOINT_NAMES


def wait_for(predicate, timeout_s=10.0):
    deadline = time.monotonic() + timeout_s
    while not predicate():
        assert time.monotonic() < deadline, "condition not reached in time"
        time.sleep(0.005)


def test_verbs_and_a_reset_go_through_while_the_loop_thread_runs():
    robot = LocalRobot(speed=None)
    service = OperatorService(robot)
    robot.start()
    try:
        wait_for(lambda: service.snapshot().time_s > 0.2)
        ack = service.estop()
        assert ack.tick > 0 and not ack.already_engaged
        wait_for(lambda: service.state()["emergency"]["hard_stop"])  # seen from the next snapshot on
        generation = robot.host.generation
        wait_for(lambda: service.snapshot().time_s > 1.0)
        time_before_s = service.snapshot().time_s
        service.reset()
        assert robot.running and robot.host.generation == generation + 1
        assert service.state()["emergency"]["hard_stop"] is False
        # the simulation restarted from zero (the loop runs on at once: how far it got by now depends on how long
        # this thread waited for the processor, so the bound is the time it had reached, not a fixed 0.2 s)
        assert service.snapshot().time_s < time_before_s
        wait_for(lambda: service.snapshot().time_s > 0.3)
    finally:
        robot.stop()
    assert not robot.running
    stats = robot.host.stats
    assert stats.ticks > 40 and stats.faults == set() and stats.fallen is False


def test_an_unknown_scene_is_rejected_listing_the_available_ones():
    service = OperatorService(LocalRobot(speed=None))
    with pytest.raises(InvalidArgument, match="default"):
        service.reset("mars")


def test_motion_verbs_are_refused_while_the_hard_estop_is_engaged_and_nothing_runs_on_release():
    robot = LocalRobot(speed=None)
    service = OperatorService(robot)
    robot.run_for(0.1)
    service.estop()
    for verb in (lambda: service.go_velocity(0.1, 0.0, 0.0), lambda: service.go_pos(0.2, 0.0, 0.0),
                 lambda: service.set_some_joint_angles({"RARM_JOINT0": -0.5}, 1.0)):
        with pytest.raises(Refused, match="hard e-stop") as info:
            verb()
        assert info.value.reason == "hard_stop"
    q_frozen = np.array(service.snapshot().q_seq_rad)
    service.release_estop()
    robot.run_for(1.0)
    np.testing.assert_allclose(service.snapshot().q_seq_rad, q_frozen, atol=1e-12)  # nothing was queued


def test_jsonable_turns_numpy_and_non_finite_values_into_plain_json():
    assert jsonable({"a": np.array([1.0, np.nan]), "b": np.int64(3), "c": (np.bool_(True),)}) == {
        "a": [1.0, None], "b": 3, "c": [True]}


def test_the_services_errors_survive_pickling_across_the_process_boundary():
    import pickle

    from app.service import NotFound, Unavailable

    for exc in (InvalidArgument("time", "must be > 0"), Refused("hard_stop", "refused: e-stop"),
                NotFound("no layer 'x'"), Unavailable("gone")):
        back = pickle.loads(pickle.dumps(exc))
        assert type(back) is type(exc) and str(back) == str(exc)
        assert getattr(back, "field", None) == getattr(exc, "field", None)
        assert getattr(back, "reason", None) == getattr(exc, "reason", None)


def test_the_board_gives_every_reader_the_last_value_whole_while_the_writer_goes_on():
    import threading

    from app.service.board import Board

    board = Board(size=1 << 16)
    reader = Board(name=board.name)
    assert reader.get() is None
    stop = threading.Event()
    seen: list[int] = []

    def read():
        while not stop.is_set():
            value = reader.get()
            if value is not None:
                assert value["n"] == len(value["payload"])  # never a torn mix of two values
                seen.append(value["n"])

    threads = [threading.Thread(target=read) for _ in range(3)]
    for th in threads:
        th.start()
    # at least 3000 values, and on until the readers have read 100 (a loaded machine may not schedule them
    # before the first 3000 are written)
    n, deadline = 0, time.monotonic() + 30.0
    while n < 3000 or (len(seen) < 100 and time.monotonic() < deadline):
        n += 1
        board.put({"n": n % 500, "payload": b"x" * (n % 500)})
    stop.set()
    for th in threads:
        th.join()
    assert len(seen) >= 100 and reader.get()["n"] == n % 500
    with pytest.raises(ValueError, match="do not fit"):
        board.put(b"y" * (1 << 17))
    reader.close()
    board.close()


def held_arm_through_the_torso() -> tuple[LocalRobot, OperatorService]:
    """A robot whose CollisionDetector holds the right arm, sent through the torso."""
    from tests.scenarios.helpers import pose_deg

    robot = LocalRobot(speed=None)
    service = OperatorService(robot)
    service.set_joint_angles([math.radians(v) for v in pose_deg(RARM_JOINT0=-20, RARM_JOINT1=0, RARM_JOINT2=80,
                                                                 RARM_JOINT3=-120)], 3.0)
    robot.loop.run_until(lambda s: s.layers["co"].collision, timeout_s=4.0)
    return robot, service


def test_sequence_verbs_are_refused_while_the_collision_detector_holds_or_the_motion_is_stopped():
    # 1. an arm motion through the torso: the CollisionDetector holds the posture, and says so
    robot, service = held_arm_through_the_torso()
    with pytest.raises(Refused, match="CollisionDetector") as info:
        service.set_some_joint_angles({"LARM_JOINT0": -0.3}, 1.0)
    assert info.value.reason == "collision"
    # 2. after a reset, the motion stopped by the operator: the plan is held, new motions are refused
    service.reset()
    robot.run_for(0.1)
    service.stop_motion()
    robot.run_for(0.05)
    with pytest.raises(Refused, match="EmergencyStopper") as info:
        service.set_some_joint_angles({"LARM_JOINT0": -0.3}, 1.0)
    assert info.value.reason == "motion_stop"
    service.release_motion()
    assert "interpolating" in service.set_some_joint_angles({"LARM_JOINT0": -0.3}, 1.0)


def test_under_the_collision_detectors_hold_a_motion_to_a_free_posture_goes_and_ends_the_hold():
    # soak seed 10192: `stand`'s half-sitting was refused under the hold, the one motion that could end it
    from behaviors.stand import HALF_SITTING_RAD

    robot, service = held_arm_through_the_torso()
    assert "interpolating" in service.set_some_joint_angles(HALF_SITTING_RAD, 2.0)
    snap = robot.loop.run_for(3.0)
    assert not snap.layers["co"].collision
    off = max(abs(snap.q_cmd_rad[JOINT_NAMES.index(n)] - q) for n, q in HALF_SITTING_RAD.items())
    assert math.degrees(off) < 1.0, math.degrees(off)


def test_a_startup_parameter_document_is_loaded_checked_and_kept_across_resets():
    doc = {"st": {"cp_threshold_m": 0.05}, "es": {"t1_s": 0.8}, "ic:rarm": {"m_p": 5.0}}
    robot = LocalRobot(params=doc)
    service = OperatorService(robot)
    try:
        def now():
            p = service.params("st", "es", "ic:rarm")
            return p["st"].cp_threshold_m, p["es"].t1_s, p["ic:rarm"].m_p

        assert now() == (0.05, 0.8, 5.0)
        service.set_params({"st": {"cp_threshold_m": 0.07}})
        service.reset()
        assert now() == (0.05, 0.8, 5.0)  # a reset starts again from the document, not the defaults
    finally:
        robot.close()
    with pytest.raises(InvalidArgument, match=r"st\.k1: must be a number"):
        LocalRobot(params={"st": {"k1": "a"}})
    with pytest.raises(InvalidArgument, match=r"es\.t1_s=.*out of range|es\.t1_s"):
        LocalRobot(params={"es": {"t1_s": -1.0}})


_FIRST_BEHAVIOUR = """
import pickle, sys
from app.service.local import LocalRobot
robot = LocalRobot("default", speed=None)
for _ in range(10):
    robot.step()
verbs = pickle.loads(bytes.fromhex(sys.argv[1]))  # as the robot process receives them (no __post_init__)
before = set(sys.modules)
for verb in verbs:
    robot.host.apply_input(verb)
    for _ in range(20):
        robot.step()
print(sorted(set(sys.modules) - before))
"""


def test_the_first_behaviour_imports_nothing_at_a_tick_boundary():
    """The robot host loads the behaviours (and what records a session) when it is made: the first behaviour
    started inside a tick boundary imported them there (0.1-0.2 s: the behaviours, their perception, scipy),
    holding that tick up."""
    import pickle
    import subprocess
    import sys

    from app.service.verbs import RunBehavior

    verbs = [RunBehavior("look_at", (("x_m", 2.0), ("y_m", 0.3), ("z_m", 0.8))),
             RunBehavior("squat", (("depth_m", 0.03),))]
    out = subprocess.run([sys.executable, "-c", _FIRST_BEHAVIOUR, pickle.dumps(verbs).hex()], capture_output=True,
                         text=True, timeout=120, check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout[-2000:]


def test_a_reset_to_another_scene_starts_its_camera_process_at_once():
    """Not at the first capture, whose result would then wait 1-2 s for the process to start (a locate_can right
    after switching to the EXPO scene overran its time)."""
    robot = LocalRobot("default", speed=None)
    try:
        robot.host.start_cameras()
        first = robot.host.cameras()
        robot.host.reset("expo")
        assert robot.host._cameras is not None and robot.host._cameras is not first
        assert robot.host._cameras_scene == "expo"
        expo = robot.host._cameras
        robot.host.reset()  # the same scene: the same process
        assert robot.host._cameras is expo
    finally:
        robot.host.close_cameras()


def test_point_claims_first_come_until_the_stream_stops_on_control_time():
    from app.service import PointTaken
    from app.service.setpoints import PointClaims, Sender, Setpoint

    claims = PointClaims(stale_s=0.3)
    alice, bob = Sender("alice", stream=1), Sender("bob", stream=2)
    move, zero = Setpoint("rhand", (0.05, 0.0, 0.0), (0.0, 0.0, 0.0)), Setpoint("rhand", (0.0,) * 3, (0.0,) * 3)
    claims.claim(move, alice, now_s=1.0)
    with pytest.raises(PointTaken, match="streamed by 'alice'") as exc:
        claims.claim(move, bob, now_s=1.29)
    assert exc.value.owner == "alice" and exc.value.reason == "point_taken" and exc.value.status == 409
    claims.claim(move, Sender("alice"), now_s=1.29)  # a PUT of the same name: the same client
    with pytest.raises(PointTaken):
        claims.claim(move, Sender("alice", stream=3), now_s=1.3)  # another stream under the name: another client
    claims.claim(move, bob, now_s=1.59)  # alice's last setpoint 0.3 s ago: her stream has stopped
    claims.claim(zero, bob, now_s=1.6)  # a zero gives the point up
    claims.claim(move, alice, now_s=1.6)
    claims.claim(move, bob, now_s=1.61, override=True)  # the operator lock's holder
    assert claims.owner("rhand", 1.62) == bob
    assert claims.owner("rhand", 0.1) is None  # the simulation was reset: time went back
    claims.claim(move, bob, now_s=0.2)
    assert claims.release(2) == ["rhand"] and claims.owner("rhand", 0.2) is None
    claims.claim(move, None, now_s=0.2)  # the console's own scripts claim nothing
    assert claims.owner("rhand", 0.2) is None
