"""FallDetector (unit): a tilt past the limit or feet unloaded for long enough is a fall, latched, with the
reason; the usual standing and walking readings are not."""

import math

import numpy as np
import pytest

from controller.balance.fall_detector import FallDetector, FallDetectorParams, foot_load_n
from controller.core.types import Estimate

WEIGHT_N = 58.0 * 9.81
DT = 0.005


def test_a_standing_or_walking_robot_is_not_fallen():
    d = FallDetector(WEIGHT_N)
    for k in range(2000):  # 10 s of walking: a few degrees, the load swapping between the feet but never gone
        assert d.update(math.radians(3.0) * math.sin(k * 0.01), math.radians(1.0), WEIGHT_N * (0.9 + 0.2 * (k % 2)),
                        DT) is None
    assert not d.fallen


def test_a_tilt_past_the_limit_is_a_fall_at_once_and_stays_one():
    d = FallDetector(WEIGHT_N, FallDetectorParams(max_tilt_deg=30.0))
    assert d.update(math.radians(20.0), math.radians(20.0), WEIGHT_N, DT) is None  # 28 deg off the vertical
    reason = d.update(math.radians(25.0), math.radians(20.0), WEIGHT_N, DT)  # 31.7 deg
    assert reason is not None and reason.startswith("tilt 32 deg > 30 deg")
    assert d.update(0.0, 0.0, WEIGHT_N, DT) == reason and d.fallen  # latched


def test_feet_unloaded_for_the_stated_time_are_a_fall_and_a_short_lift_is_not():
    p = FallDetectorParams(min_load_ratio=0.1, unloaded_time_s=0.3)
    d = FallDetector(WEIGHT_N, p)
    light = 0.05 * WEIGHT_N
    for _ in range(round(0.25 / DT)):  # a hop's worth: 0.25 s unloaded
        assert d.update(0.0, 0.0, light, DT) is None
    assert d.update(0.0, 0.0, WEIGHT_N, DT) is None  # loaded again: the count restarts
    for _ in range(round(0.3 / DT) - 1):
        assert d.update(0.0, 0.0, light, DT) is None
    reason = d.update(0.0, 0.0, light, DT)
    assert reason is not None and reason.startswith("feet unloaded: 28 N < 0.1 x weight for 0.30 s")


def test_the_foot_load_sums_the_feet_vertical_forces_only():
    w = np.zeros((4, 6))
    w[:, 2] = (200.0, 300.0, 50.0, 40.0)  # rfsensor, lfsensor, then the hands
    assert foot_load_n(w) == pytest.approx(500.0)


def test_the_loop_check_reads_the_attitude_and_the_feet_of_the_estimate():
    wrenches = np.zeros((4, 6))
    wrenches[:2, 2] = 0.5 * WEIGHT_N
    est = Estimate(base_rpy_rad=np.array([math.radians(40.0), 0.0, 0.0]), wrenches_ext=wrenches)
    reason = FallDetector(WEIGHT_N).check(est, DT)
    assert reason is not None and reason.startswith("tilt 40 deg")
