"""RemoveForceOffset: the weight below each sensor and calibrated offsets are removed."""

import numpy as np
import pytest

from controller.core.constants import GRAVITY_M_S2
from controller.core.errors import InvalidCommand
from controller.core.types import Reference
from controller.kinematics.model import RobotKinematics
from controller.layers.remove_force_offset import RemoveForceOffset, gravity_wrench_in_sensor
from robot.generate import half_sitting_deg
from robot.names import FORCE_SENSOR_NAMES
from tests.controller.fakes import make_ctx

HALF = np.deg2rad(half_sitting_deg())
RH = FORCE_SENSOR_NAMES.index("rhsensor")


def test_gravity_wrench_of_a_part_hanging_below_a_level_sensor():
    w = gravity_wrench_in_sensor(2.0, np.array([0.1, 0.0, -0.1]), np.zeros(3), np.eye(3), GRAVITY_M_S2)
    assert np.allclose(w[:3], [0, 0, -2.0 * GRAVITY_M_S2])
    assert np.allclose(w[3:], [0, 2.0 * GRAVITY_M_S2 * 0.1, 0])  # r x F: lever +x, force -z -> +y moment


def hand_reading(kin, extra_force_world=None, offset=None):
    """What the right wrist sensor reads when the hand hangs still (and is pushed by extra_force)."""
    extra_force_world = np.zeros(3) if extra_force_world is None else extra_force_world
    offset = np.zeros(6) if offset is None else offset
    kin.update_rpy(np.zeros(3), np.zeros(3), HALF)
    m, c = kin.mass_below("rhsensor")
    p, R = kin.frame_pose("rhsensor")
    w = gravity_wrench_in_sensor(m, c, p, R, GRAVITY_M_S2)
    w[:3] += R.T @ extra_force_world
    wrenches = np.zeros((4, 6))
    wrenches[RH] = w + offset
    return wrenches


def test_a_hanging_hand_reads_zero_external_force_and_a_push_reads_the_push():
    kin = RobotKinematics()
    rmfo = RemoveForceOffset(RobotKinematics())
    for push in (np.zeros(3), np.array([0.0, 0.0, -50.0])):
        ctx = make_ctx(q=HALF, wrenches=hand_reading(kin, push))
        rmfo.tick(ctx, Reference.from_arrays(HALF))
        assert np.allclose(ctx.estimate.wrenches_ext_world[RH, :3], push, atol=1e-9)


def test_calibration_learns_the_offset_of_an_unloaded_sensor():
    kin = RobotKinematics()
    rmfo = RemoveForceOffset(RobotKinematics())
    offset = np.array([3.0, -2.0, 5.0, 0.1, -0.2, 0.05])
    rmfo.calibrate(["rhsensor"])
    for _ in range(int(rmfo.params.calibration_time_s / 0.005) + 1):
        ctx = make_ctx(q=HALF, wrenches=hand_reading(kin, offset=offset))
        rmfo.tick(ctx, Reference.from_arrays(HALF))
    assert np.allclose(rmfo.offsets[RH], offset, atol=1e-9)
    assert rmfo.status().calibrating == ()
    ctx = make_ctx(q=HALF, wrenches=hand_reading(kin, np.array([10.0, 0, 0]), offset=offset))
    rmfo.tick(ctx, Reference.from_arrays(HALF))
    assert np.allclose(ctx.estimate.wrenches_ext_world[RH, :3], [10.0, 0, 0], atol=1e-9)


def test_calibrating_an_unknown_sensor_lists_the_valid_ones():
    with pytest.raises(InvalidCommand, match="rfsensor"):
        RemoveForceOffset(RobotKinematics()).calibrate(["wrist"])
