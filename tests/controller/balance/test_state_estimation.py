"""Actual ZMP from foot wrenches; BODY tilt from the kinematics of flat soles."""

import numpy as np

from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE
from controller.balance.state_estimation import (
    FLAT_SOLE_COP_MARGIN_M,
    FLAT_SOLE_MAX_DISAGREEMENT_RAD,
    FLAT_SOLE_MIN_LOAD_SHARE,
    body_tilt_from_flat_soles,
    lip_velocity_filter_step,
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


def test_a_sole_seen_far_from_its_planned_orientation_does_not_count():
    # a catching step's foot touched down early, 18 deg pitched, with its pressure inside the edges: read as flat,
    # it gave BODY 18 deg of pitch, the COG estimate ran 18 cm in 20 ms and the robot fell (issue 26, 15 N s left)
    w = np.array([[0, 0, 200.0, 0, 0, 0], [0, 0, 250.0, 0, 0, 0]])
    limit = np.degrees(FLAT_SOLE_MAX_DISAGREEMENT_RAD)
    for pitch_deg, counts in ((18.0, False), (limit + 0.1, False), (limit - 0.1, True), (-(limit - 0.1), True)):
        meas = [rpy_to_matrix(np.radians([0.0, pitch_deg, 0.0])), np.eye(3)]
        tilt = body_tilt_from_flat_soles(np.eye(3), [FLAT, FLAT], meas, w, RECTS, (True, False))
        assert (tilt is not None) is counts, pitch_deg
    # the same off the roll axis; the other sole, flat, still counts alone
    meas = [rpy_to_matrix(np.radians([limit + 0.1, 0.0, 0.0])), np.eye(3)]
    roll, pitch = body_tilt_from_flat_soles(np.eye(3), [FLAT, FLAT], meas, w, RECTS, (True, True))
    assert abs(roll) < 1e-12 and abs(pitch) < 1e-12


# ---- lip_velocity_filter_step ----------------------------------------------------------------------------------

DT_S = 0.005
ALPHA_4HZ = 1.0 - np.exp(-2.0 * np.pi * 4.0 * DT_S)  # a 4 Hz cutoff (the Stabilizer had it without the prediction)


def test_without_an_acceleration_it_is_the_first_order_low_pass():
    v = (0.1, -0.2)
    assert np.allclose(lip_velocity_filter_step(v, (0.3, 0.4), ALPHA_4HZ),
                       [0.1 + ALPHA_4HZ * 0.2, -0.2 + ALPHA_4HZ * 0.6])
    assert np.allclose(lip_velocity_filter_step(v, (0.3, 0.4), 1.0, (5.0, 5.0), DT_S), [0.3, 0.4])  # alpha 1


def run_on_a_lip(predict: bool, push_accel: float = 0.0) -> float:
    """Largest velocity error [m/s] over 0.5 s of a LIP diverging from its ZMP (x'' = omega^2 (x - p)), the
    finite difference of the sampled position as the measurement; `push_accel` an acceleration the LIP does
    not explain, from 0.25 s."""
    omega, p = 3.5, 0.0
    x, xd = 0.01, 0.0
    v_est, worst, steps = (0.0, 0.0), 0.0, 100
    for k in range(steps):
        x_prev = x
        a = omega**2 * (x - p) + (push_accel if k * DT_S >= 0.25 else 0.0)
        xd += a * DT_S
        x += xd * DT_S
        lip_a = (omega**2 * (x - p), 0.0) if predict else (0.0, 0.0)
        v_est = lip_velocity_filter_step(v_est, ((x - x_prev) / DT_S, 0.0), ALPHA_4HZ, lip_a, DT_S)
        if k >= 20:  # after the filter's settling (0.1 s)
            worst = max(worst, abs(v_est[0] - xd))
    return worst


def test_the_lip_prediction_removes_the_low_pass_lag_of_an_accelerating_cog():
    lagged, predicted = run_on_a_lip(False), run_on_a_lip(True)
    # the low-pass lags by about a / (2 pi 4 Hz): measured 12.0 mm/s at most on this LIP (a 0.36 m/s^2 at 0.5 s) ...
    assert lagged > 0.010
    # ... the prediction leaves the order-dt error of the finite difference (measured 0.2 mm/s)
    assert predicted < 0.1 * lagged and predicted < 0.0005


def test_an_acceleration_the_lip_does_not_explain_is_followed_as_the_low_pass_follows_it():
    push = 2.0  # [m/s^2], as a 0.1 s push of about 120 N on the 58 kg robot
    extra_lag = run_on_a_lip(True, push) - run_on_a_lip(True)  # measured 73 mm/s against 80 mm/s
    assert 0.8 * push / (2 * np.pi * 4.0) < extra_lag < 1.2 * push / (2 * np.pi * 4.0)
