"""Actual ZMP from foot wrenches; BODY tilt from the kinematics of flat soles."""

import numpy as np

from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE
from controller.balance.state_estimation import (
    FLAT_SOLE_COP_MARGIN_M,
    FLAT_SOLE_MIN_LOAD_SHARE,
    body_tilt_from_flat_soles,
    zmp_from_foot_wrenches,
)
from controller.kinematics.rotations import rpy_to_matrix


def test_zmp_of_two_pure_vertical_forces_is_their_weighted_mean():
    pos = np.array([[0.0, -0.095, 0.0], [0.0, 0.095, 0.0]])
    w = np.array([[0, 0, 300.0, 0, 0, 0], [0, 0, 100.0, 0, 0, 0]])
    assert np.allclose(zmp_from_foot_wrenches(pos, w, 0.0), [0.0, -0.095 * 0.5, 0.0])


def test_a_pitch_moment_shifts_the_zmp_forward_by_minus_tau_over_f():
    pos = np.array([[0.0, 0.0, 0.0]])
    w = np.array([[0, 0, 500.0, 0.0, -10.0, 0]])  # ground pushes the toe: negative tau_y
    assert np.allclose(zmp_from_foot_wrenches(pos, w, 0.0), [0.02, 0.0, 0.0])


def test_unloaded_feet_give_no_zmp():
    pos = np.zeros((2, 3))
    assert zmp_from_foot_wrenches(pos, np.zeros((2, 6)), 0.0) is None


# ---- body_tilt_from_flat_soles ---------------------------------------------------------------------------------

RECTS = (HRP2_RIGHT_SOLE, HRP2_LEFT_SOLE)
FLAT = np.eye(3)


def soles_seen(R_body_est, R_body_sole):
    """What the encoders and the estimate say of each sole: R_body_est R_body_sole, whatever BODY truly is."""
    return [R_body_est @ R for R in R_body_sole]


def test_the_true_body_tilt_comes_back_whatever_the_estimate_says():
    # BODY truly rolled 1 deg, pitched -2 deg; the legs hold the soles flat on the floor; the estimate is 3 deg off
    R_true = rpy_to_matrix(np.radians([1.0, -2.0, 30.0]))
    R_body_sole = [R_true.T @ FLAT, R_true.T @ FLAT]  # the encoders' sole-in-BODY rotation
    R_est = rpy_to_matrix(np.radians([-2.0, 1.0, 10.0]))
    w = np.array([[0, 0, 300.0, 0, 0, 0], [0, 0, 300.0, 0, 0, 0]])
    tilt = body_tilt_from_flat_soles(R_est, [FLAT, FLAT], soles_seen(R_est, R_body_sole), w, RECTS,
                                     (True, True))
    np.testing.assert_allclose(np.degrees(tilt), [1.0, -2.0], atol=1e-9)


def test_the_soles_are_averaged_by_load():
    R_est = np.eye(3)
    meas = [rpy_to_matrix(np.radians([0.0, 1.0, 0.0])).T, rpy_to_matrix(np.radians([0.0, 3.0, 0.0])).T]
    w = np.array([[0, 0, 300.0, 0, 0, 0], [0, 0, 100.0, 0, 0, 0]])
    _, pitch = body_tilt_from_flat_soles(R_est, [FLAT, FLAT], meas, w, RECTS, (True, True))
    assert abs(np.degrees(pitch) - (0.75 * 1.0 + 0.25 * 3.0)) < 1e-3


def test_a_lightly_loaded_sole_does_not_count_and_none_when_no_sole_qualifies():
    meas = [rpy_to_matrix(np.radians([0.0, 1.0, 0.0])).T, rpy_to_matrix(np.radians([0.0, 3.0, 0.0])).T]
    share = FLAT_SOLE_MIN_LOAD_SHARE
    light = 0.9 * share / (1.0 - 0.9 * share)  # the left foot's share just under the minimum
    w = np.array([[0, 0, 400.0, 0, 0, 0], [0, 0, 400.0 * light, 0, 0, 0]])
    _, pitch = body_tilt_from_flat_soles(np.eye(3), [FLAT, FLAT], meas, w, RECTS, (True, True))
    assert abs(np.degrees(pitch) - 1.0) < 1e-9  # the right sole alone
    # the right sole not planned in contact: nothing left
    assert body_tilt_from_flat_soles(np.eye(3), [FLAT, FLAT], meas, w, RECTS, (False, True)) is None
    assert body_tilt_from_flat_soles(np.eye(3), [FLAT, FLAT], meas, np.zeros((2, 6)), RECTS, (True, True)) is None


def test_a_sole_whose_pressure_is_near_an_edge_or_that_is_planned_pitched_does_not_count():
    meas = [np.eye(3), np.eye(3)]
    fz = 400.0
    m = FLAT_SOLE_COP_MARGIN_M
    toe = HRP2_RIGHT_SOLE.front_m
    for cop_x, counts in ((toe - m - 0.002, True), (toe - m + 0.002, False)):
        w = np.array([[0, 0, fz, 0, -cop_x * fz, 0], [0, 0, 0.0, 0, 0, 0]])  # tau_y = -x f_z
        assert (body_tilt_from_flat_soles(np.eye(3), [FLAT, FLAT], meas, w, RECTS, (True, True)) is not None) is counts
    outside = HRP2_RIGHT_SOLE.right_m  # the right sole's outer edge is at -y
    w = np.array([[0, 0, fz, (-outside + m - 0.002) * fz, 0, 0], [0, 0, 0.0, 0, 0, 0]])  # tau_x = y f_z
    assert body_tilt_from_flat_soles(np.eye(3), [FLAT, FLAT], meas, w, RECTS, (True, True)) is None
    toe_off = rpy_to_matrix(np.radians([0.0, 5.0, 0.0]))
    w = np.array([[0, 0, fz, 0, 0, 0], [0, 0, 0.0, 0, 0, 0]])
    assert body_tilt_from_flat_soles(np.eye(3), [toe_off, FLAT], meas, w, RECTS, (True, True)) is None
