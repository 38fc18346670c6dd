"""Leg odometry on hand-made steps: the stance foot stays, the other takes over when loaded and level, and the
plan's frame lands in the world where the measured feet are."""

from __future__ import annotations

import math

import numpy as np
import pytest

from controller.balance.leg_odometry import LegOdometry, control_to_world, world_to_control

LEVEL = np.eye(3)


def rz(yaw_rad: float) -> np.ndarray:
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def ry(pitch_rad: float) -> np.ndarray:
    c, s = math.cos(pitch_rad), math.sin(pitch_rad)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def step_left(odo: LegOdometry, measured_left_x_m: float, planned_left_x_m: float, fz=(100.0, 500.0),
              R_left=LEVEL, walking=True):
    """Right sole at (0, -0.1, -0.7) from BODY, the left measured `measured_left_x_m` ahead of it; the
    controller anchors BODY at the left's planned place, `planned_left_x_m` ahead of the right's (0, -0.1, 0)."""
    p_meas = ((0.0, -0.1, -0.7), (measured_left_x_m, 0.1, -0.7))
    p_body_control = (planned_left_x_m - measured_left_x_m, 0.0, 0.7)
    return odo.update(p_meas, (LEVEL, R_left), fz, p_body_control, walking)


def test_until_the_first_walk_the_controllers_frame_is_the_world():
    odo = LegOdometry()
    feet = ((0.0, -0.1, -0.7), (0.0, 0.1, -0.7))
    est = odo.update(feet, (LEVEL, LEVEL), (350.0, 250.0), (0.01, 0.0, 0.7))
    assert est.stance == 0 and est.switches == 0
    np.testing.assert_allclose(est.p_stance_world_m, (0.01, -0.1, 0.0), atol=1e-12)
    assert est.world_from_control == (0.0, 0.0, 0.0, 0.0)
    est = odo.update(feet, (LEVEL, LEVEL), (350.0, 250.0), (0.01, 0.0, 0.698))  # it settles 2 mm
    assert est.world_from_control == (0.0, 0.0, 0.0, 0.0)
    est = odo.update(feet, (LEVEL, LEVEL), (350.0, 250.0), (0.011, 0.0, 0.698), walking=True)
    np.testing.assert_allclose(est.world_from_control, (-0.001, 0.0, 0.0, 0.0), atol=1e-12)


def test_a_foot_landing_long_moves_the_controllers_frame_by_the_landing_error():
    odo = LegOdometry()
    step_left(odo, 0.0, 0.0, fz=(500.0, 100.0))  # standing on the right
    est = step_left(odo, 0.203, 0.200)  # the left lands 3 mm beyond its plan and takes the load
    assert est.stance == 1 and est.switches == 1
    np.testing.assert_allclose(est.p_stance_world_m, (0.203, 0.1, 0.0), atol=1e-12)
    # the plan's left sole, (0.2, 0.1), is where the left foot really is
    np.testing.assert_allclose(control_to_world(est.world_from_control, (0.2, 0.1, 0.0)), (0.203, 0.1, 0.0),
                               atol=1e-12)


def test_the_stance_stays_until_the_other_foot_carries_most_of_the_load():
    odo = LegOdometry()
    step_left(odo, 0.0, 0.0, fz=(500.0, 100.0))
    est = step_left(odo, 0.203, 0.2, fz=(200.0, 400.0))  # 67 %: not yet
    assert est.stance == 0 and est.switches == 0 and est.p_stance_world_m == (0.0, -0.1, 0.0)
    assert step_left(odo, 0.203, 0.2, fz=(170.0, 430.0)).stance == 1  # 72 %


def test_a_heel_strike_is_not_taken_until_the_sole_is_level_or_the_stance_foot_lifts():
    odo = LegOdometry()
    step_left(odo, 0.0, 0.0, fz=(500.0, 100.0))
    heel = ry(math.radians(5.0))
    assert step_left(odo, 0.203, 0.2, fz=(100.0, 500.0), R_left=heel).stance == 0
    assert step_left(odo, 0.203, 0.2, fz=(100.0, 500.0), R_left=ry(math.radians(1.5))).stance == 1
    odo = LegOdometry()
    step_left(odo, 0.0, 0.0, fz=(500.0, 100.0))
    assert step_left(odo, 0.203, 0.2, fz=(50.0, 550.0), R_left=heel).stance == 1  # the right carries 8 %


def test_no_load_no_change():
    odo = LegOdometry()
    step_left(odo, 0.0, 0.0, fz=(500.0, 100.0))
    assert step_left(odo, 0.203, 0.2, fz=(2.0, 30.0)).stance == 0  # in the air: 32 N in all


def test_headings_chain_with_the_odometrys_own_yaw_not_the_attitude_estimates():
    """The attitude estimate's yaw has drifted by 2 deg: the step is measured relative to the stance foot, so
    the drift does not enter where the new foot is; the controller's frame turns by it."""
    odo = LegOdometry()
    drift = rz(math.radians(2.0))
    p_right = np.array((0.0, -0.1, -0.7))
    p_left_from_right = np.array((0.2, 0.2, 0.0))  # in the right foot's axes
    odo.update((p_right, p_right + p_left_from_right), (LEVEL, LEVEL), (500.0, 100.0), (0.0, 0.0, 0.7))
    meas = (drift @ p_right, drift @ (p_right + p_left_from_right))  # the estimate's yaw drifts by 2 deg
    est = odo.update(meas, (drift, drift @ rz(math.radians(10.0))), (100.0, 500.0), (0.0, 0.0, 0.7),
                     walking=True)
    np.testing.assert_allclose(est.p_stance_world_m, (0.2, 0.1, 0.0), atol=1e-12)
    assert est.stance_yaw_rad == pytest.approx(math.radians(10.0), abs=1e-12)
    assert est.world_from_control[3] == pytest.approx(math.radians(-2.0), abs=1e-12)


def test_control_to_world_and_back():
    placement = (0.3, -0.2, 0.01, math.radians(30.0))
    p = (1.0, 0.5, 0.7)
    world = control_to_world(placement, p)
    np.testing.assert_allclose(world, (0.3 + math.cos(math.pi / 6) - 0.5 * 0.5, -0.2 + 0.5 + 0.5 * math.cos(
        math.pi / 6), 0.71), atol=1e-12)
    np.testing.assert_allclose(world_to_control(placement, world), p, atol=1e-12)


def test_heights_stay_the_controllers_a_step_measured_2_mm_up_does_not_climb():
    odo = LegOdometry()
    odo.update(((0.0, -0.1, -0.7), (0.0, 0.1, -0.7)), (LEVEL, LEVEL), (500.0, 100.0), (0.0, 0.0, 0.7))
    est = odo.update(((0.0, -0.1, -0.7), (0.2, 0.1, -0.698)), (LEVEL, LEVEL), (100.0, 500.0), (-0.2, 0.0, 0.698),
                     walking=True)
    assert est.stance == 1 and est.p_stance_world_m[2] == pytest.approx(0.0, abs=1e-12)
    assert est.world_from_control[2] == pytest.approx(0.0, abs=1e-12)
