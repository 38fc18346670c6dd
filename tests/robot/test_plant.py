"""The MuJoCo plant stands on its servos in half-sitting and reports sensors with the hardware conventions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robot.names import JOINT_NAMES
from robot.plant import MujocoPlant

GRAVITY_M_S2 = 9.81
TOTAL_MASS_KG = 58.0
FOOT_LINK_MASS_KG = 1.63877
TICK_STEPS = 5  # 5 ms control tick over 1 ms physics
STAND_DURATION_S = 30.0


@pytest.fixture(scope="module")
def stood():
    """30 s of standing on the servos alone, the home angles written every 5 ms tick."""
    plant = MujocoPlant()
    q_home_rad = np.array(plant.data.ctrl)
    base_start_m = plant.ground_truth().base_pos_world.copy()
    worst_tracking_rad = 0.0
    for tick in range(round(STAND_DURATION_S / (TICK_STEPS * plant.dt_physics))):
        plant.write(q_home_rad)
        plant.step(TICK_STEPS)
        if tick * TICK_STEPS * plant.dt_physics > 1.0:  # after settling on the floor
            worst_tracking_rad = max(worst_tracking_rad, np.abs(plant.read().q_rad - q_home_rad).max())
    return {"plant": plant, "q_home_rad": q_home_rad, "base_start_m": base_start_m,
            "worst_tracking_rad": worst_tracking_rad}


def tilt_deg(quat_wxyz) -> float:
    w, x, y, z = quat_wxyz
    body_z_in_world_z = 1.0 - 2.0 * (x * x + y * y)
    return math.degrees(math.acos(min(1.0, body_z_in_world_z)))


def test_standing_body_tilt_stays_below_one_degree(stood):
    assert tilt_deg(stood["plant"].ground_truth().base_quat_wxyz) < 1.0


def test_standing_body_drifts_less_than_5_mm(stood):
    drift = stood["plant"].ground_truth().base_pos_world - stood["base_start_m"]
    assert np.hypot(drift[0], drift[1]) < 0.005


def test_standing_joints_track_commands_within_half_a_degree(stood):
    assert math.degrees(stood["worst_tracking_rad"]) < 0.5


def test_no_mujoco_warnings_while_standing(stood):
    assert stood["plant"].warnings() == {}


def test_foot_sensors_carry_the_weight_above_the_feet(stood):
    wrenches = stood["plant"].read().wrenches
    weight_above_feet_n = (TOTAL_MASS_KG - 2 * FOOT_LINK_MASS_KG) * GRAVITY_M_S2
    assert wrenches[0, 2] > 0 and wrenches[1, 2] > 0
    assert wrenches[0, 2] + wrenches[1, 2] == pytest.approx(weight_above_feet_n, rel=0.02)


def test_hanging_hands_pull_down_on_the_wrist_sensors(stood):
    wrenches = stood["plant"].read().wrenches
    assert wrenches[2, 2] < 0 and wrenches[3, 2] < 0


def test_imu_at_rest_reads_no_rotation_and_gravity_up(stood):
    sensors = stood["plant"].read()
    assert np.linalg.norm(sensors.gyro_rad_s) < 1e-3
    assert sensors.accel_m_s2 == pytest.approx([0.0, 0.0, GRAVITY_M_S2], abs=0.05)


def test_read_arrays_are_read_only_and_in_joint_order(stood):
    sensors = stood["plant"].read()
    assert sensors.q_rad.shape == (len(JOINT_NAMES),) and sensors.wrenches.shape == (4, 6)
    with pytest.raises(ValueError):
        sensors.q_rad[0] = 1.0


def test_read_gives_the_mean_sensor_values_in_the_hardware_convention(stood):
    plant = stood["plant"]
    data = plant._sensor_mean
    sensors = plant.read()
    for i, name in enumerate(("rfsensor", "lfsensor", "rhsensor", "lhsensor")):
        force, torque = plant.model.sensor(f"{name}_force"), plant.model.sensor(f"{name}_torque")
        raw = np.concatenate((data[force.adr[0]:force.adr[0] + 3], data[torque.adr[0]:torque.adr[0] + 3]))
        assert np.array_equal(sensors.wrenches[i], -raw)
    assert np.array_equal(sensors.q_rad, plant.data.qpos[plant._qpos_adr])
    for a in (sensors.q_rad, sensors.dq_rad_s, sensors.wrenches, sensors.gyro_rad_s, sensors.accel_m_s2):
        assert not a.flags.writeable and a.dtype == np.float64


def test_ground_truth_is_a_read_only_copy_of_the_simulation_state(stood):
    plant = stood["plant"]
    truth = plant.ground_truth()
    d = plant.data
    assert np.array_equal(truth.qpos, d.qpos) and truth.qpos is not d.qpos
    assert np.array_equal(truth.base_pos_world, d.qpos[:3]) and np.array_equal(truth.base_quat_wxyz, d.qpos[3:7])
    assert np.array_equal(truth.body_pos_world, d.xpos) and np.array_equal(truth.com_world, d.subtree_com[1])
    for name in ("base_pos_world", "base_quat_wxyz", "base_linvel_world", "base_angvel_world", "com_world",
                 "body_pos_world", "body_quat_wxyz", "qpos", "mocap_pos", "mocap_quat"):
        a = getattr(truth, name)
        assert not a.flags.writeable, name
        assert not np.shares_memory(a, d.qpos) and not np.shares_memory(a, d.xpos), name
    plant.step(5)  # later steps leave an earlier truth as it was
    assert not np.array_equal(truth.qpos, d.qpos)


def test_push_on_body_changes_the_base_velocity():
    plant = MujocoPlant()
    plant.step(200)
    before = plant.ground_truth().base_linvel_world.copy()
    plant.push("BODY", [60.0, 0.0, 0.0], duration_s=0.1)
    plant.step(100)
    after = plant.ground_truth().base_linvel_world
    assert after[0] - before[0] > 0.01
    assert np.all(plant.data.xfrc_applied == 0.0)  # the push ended after 0.1 s


def test_push_on_unknown_body_lists_the_bodies():
    with pytest.raises(ValueError, match="RARM_LINK6"):
        MujocoPlant().push("ARM", [1.0, 0.0, 0.0], 0.1)


@pytest.mark.parametrize("bad", [np.zeros(29), np.zeros((30, 1)), np.full(30, np.nan), np.full(30, np.inf)])
def test_bad_write_raises_value_error(bad):
    with pytest.raises(ValueError):
        MujocoPlant().write(bad)


def test_unknown_keyframe_lists_the_valid_ones():
    with pytest.raises(ValueError, match="home"):
        MujocoPlant().reset("crouch")


def test_write_sets_the_servo_targets_in_joint_order():
    plant = MujocoPlant()
    q = np.array(plant.data.ctrl)
    q[JOINT_NAMES.index("HEAD_JOINT0")] = 0.3
    plant.write(q)
    plant.step(500)
    assert plant.read().q_rad[JOINT_NAMES.index("HEAD_JOINT0")] == pytest.approx(0.3, abs=math.radians(0.5))


def test_translating_the_robot_moves_its_base_and_not_its_sensors():
    plant = MujocoPlant()
    plant.step(50)
    before = plant.read()
    base0 = plant.ground_truth().base_pos_world.copy()
    base = plant.translate_robot((-0.07, 0.03))
    np.testing.assert_allclose(base - base0, [-0.07, 0.03, 0.0], atol=1e-12)
    np.testing.assert_allclose(plant.ground_truth().base_pos_world, base)
    after = plant.read()
    np.testing.assert_array_equal(after.q_rad, before.q_rad)
    np.testing.assert_array_equal(after.gyro_rad_s, before.gyro_rad_s)
    plant.step(5)  # the next sensor means: the same floor, the same wrenches
    moved = plant.read().wrenches
    twin = MujocoPlant()
    twin.step(50)
    twin.step(5)
    np.testing.assert_allclose(moved, twin.read().wrenches, atol=1e-9)


@pytest.mark.parametrize("bad", [(0.1,), (0.1, float("nan")), "ab", None])
def test_translating_the_robot_takes_two_finite_metres(bad):
    with pytest.raises(ValueError, match="offset_xy_m"):
        MujocoPlant().translate_robot(bad)
