"""Actual ZMP from foot wrenches."""

import numpy as np

from controller.balance.state_estimation import zmp_from_foot_wrenches


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
