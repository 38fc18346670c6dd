"""RemoveForceOffset: the weight below each sensor and calibrated offsets are removed."""

import numpy as np
import pytest

from controller.core.constants import GRAVITY_M_S2
from controller.core.errors import InvalidCommand
from controller.core.types import Reference
from controller.kinematics.model import RobotKinematics
from controller.layers.remove_force_offset import RemoveForceOffset, gravity_wrench_in_sensor
from robot.generate import half_sitting_deg
from robot.names import FORCE_SENSOR_NAMES, JOINT_NAMES
from tests.controller.fakes import make_ctx

HALF = np.deg2rad(half_sitting_deg())
RH = FORCE_SENSOR_NAMES.index("rhsensor")
#: [N m] the largest wrist moment of a hand hanging still: measured 0.0003 N m over 3.8 s standing, 2.6 N m
#: before the subtree COM was placed in the world
MOMENT_STILL_NM = 0.005


def test_gravity_wrench_of_a_part_hanging_below_a_level_sensor():
    w = gravity_wrench_in_sensor(2.0, np.array([0.1, 0.0, -0.1]), np.zeros(3), np.eye(3), GRAVITY_M_S2)
    assert np.allclose(w[:3], [0, 0, -2.0 * GRAVITY_M_S2])
    assert np.allclose(w[3:], [0, 2.0 * GRAVITY_M_S2 * 0.1, 0])  # r x F: lever +x, force -z -> +y moment


def hand_reading(kin, extra_force_world=None, offset=None, q=HALF):
    """What the right wrist sensor reads when the hand hangs still in posture q (and is pushed by extra_force)."""
    extra_force_world = np.zeros(3) if extra_force_world is None else extra_force_world
    offset = np.zeros(6) if offset is None else offset
    kin.update_rpy(np.zeros(3), np.zeros(3), q)
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
        assert np.allclose(ctx.estimate.wrenches_ext_world[RH, 3:], 0.0, atol=1e-9)  # a push along the lever arm


def test_the_hands_weight_is_removed_about_its_com_as_the_jaw_opens_and_closes():
    """The jaw below the wrist sensor moves the hand's COM: the layer follows it (to 1e-4 rad of the jaw)."""
    kin = RobotKinematics()
    rmfo = RemoveForceOffset(RobotKinematics())
    jaw = JOINT_NAMES.index("RARM_JOINT6")
    # the jaw's range is -60..16 deg; +5e-5 rad is under the refresh step: the COM of 0.2 rad is kept (0.16 um off)
    for angle_rad, tol_nm in ((0.0, 1e-9), (0.2, 1e-9), (0.2 + 5e-5, 1e-5), (-1.0, 1e-9), (0.25, 1e-9)):
        q = HALF.copy()
        q[jaw] = angle_rad
        ctx = make_ctx(q=q, wrenches=hand_reading(kin, q=q))
        rmfo.tick(ctx, Reference.from_arrays(q))
        assert np.abs(ctx.estimate.wrenches_ext[RH]).max() < tol_nm, (angle_rad, ctx.estimate.wrenches_ext[RH])


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


def test_the_part_below_each_sensor_has_the_simulators_mass_and_com_relative_to_the_sensor():
    """The model's (pinocchio) mass and COM below each sensor against MuJoCo's subtree of the sensor's body, in
    the plant's home posture: an independent model of the same robot. pinocchio keeps subtree COMs in the joint's
    frame; read as world positions they were 0.34 m off at the wrists (2.7 N m of moment that was not there)."""
    import mujoco

    from robot.plant import MujocoPlant

    plant = MujocoPlant()
    mujoco.mj_forward(plant.model, plant.data)
    truth = plant.ground_truth()
    kin = RobotKinematics()
    w, x, y, z = truth.base_quat_wxyz
    R_base = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                       [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                       [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    kin.update(truth.base_pos_world, R_base, plant.read().q_rad)
    for sensor in FORCE_SENSOR_NAMES:
        site = plant.model.site(sensor)
        body = int(site.bodyid[0])
        mass, com = kin.mass_below(sensor)
        p, _ = kin.frame_pose(sensor)
        assert mass == pytest.approx(plant.model.body_subtreemass[body], rel=1e-6)
        np.testing.assert_allclose(com - p, plant.data.subtree_com[body] - plant.data.site_xpos[site.id], atol=1e-4,
                                   err_msg=sensor)


def test_standing_still_in_simulation_the_hands_read_no_external_moment():
    """The hands hang free: once the weight below each sensor is removed, nothing is left at the wrists."""
    from app.service.local import LocalRobot

    robot = LocalRobot(speed=None)
    try:
        snap = robot.run_for(2.0)
        for sensor in ("rhsensor", "lhsensor"):
            wrench = snap.wrenches_ext[FORCE_SENSOR_NAMES.index(sensor)]
            assert np.abs(wrench[:3]).max() < 0.05, (sensor, wrench)
            assert np.abs(wrench[3:]).max() < MOMENT_STILL_NM, (sensor, wrench)
    finally:
        robot.close()
