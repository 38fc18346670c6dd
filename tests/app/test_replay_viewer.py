"""The replay viewer, headless: the time slider moves the drawn robot to the recorded tick (the hand where the
recorded encoders put it), play advances it at the chosen speed and stops at the end."""

import time

import numpy as np
import pytest

from app.lab.replay_viewer import ReplayViewer
from app.service.data_logger import DataLogger
from app.service.local import LocalRobot
from app.service.verbs import SetSomeJointAngles
from app.session.reader import Session


@pytest.fixture(scope="module")
def session():
    """0.6 s of the right arm swinging forward (60 deg in 0.5 s), as a session's rows."""
    robot = LocalRobot(speed=None)
    robot.host.logger = logger = DataLogger(400)
    robot.submit(SetSomeJointAngles((("RARM_JOINT0", np.radians(-60.0)),), 0.5)).result()
    robot.run_for(0.6)
    rows = logger.rows()
    return Session(None, {"scene": "default", "dt_control_s": 0.005}, rows, [None] * len(rows))


@pytest.fixture
def viewer(session):
    v = ReplayViewer(session, port=0, rate_hz=50.0)
    yield v
    v.stop()


def test_the_slider_moves_the_drawn_robot_to_the_recorded_tick(viewer, session):
    start = viewer.body_position("RARM_LINK6").copy()
    viewer.slider.value = viewer.time_of(session.ticks - 1)
    assert viewer.tick == session.ticks - 1
    moved = viewer.body_position("RARM_LINK6")
    assert moved[0] - start[0] > 0.2  # the arm swung forward: the hand is 0.2 m further ahead
    viewer.slider.value = viewer.time_of(0)
    np.testing.assert_allclose(viewer.body_position("RARM_LINK6"), start, atol=1e-12)
    assert "tick **0**" in viewer._readout.content


def test_play_runs_at_the_chosen_speed_and_stops_at_the_end(viewer, session):
    viewer.speed.value = "1"
    viewer.playing = True
    time.sleep(0.1)  # 0.1 s of the 0.6 s at real time
    assert viewer.playing and 0 < viewer.tick < session.ticks - 1
    deadline = time.monotonic() + 5.0
    while viewer.playing and time.monotonic() < deadline:
        time.sleep(0.02)
    assert not viewer.playing and viewer.tick == session.ticks - 1
