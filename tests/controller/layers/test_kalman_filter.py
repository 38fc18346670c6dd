"""KalmanFilter: BODY attitude from gyro and accelerometer."""

import numpy as np

from controller.core.constants import GRAVITY_M_S2
from controller.core.types import Reference
from controller.kinematics.rotations import rpy_to_matrix
from controller.layers.kalman_filter import AttitudeKalmanFilter, KalmanFilter, KalmanFilterParams
from tests.controller.fakes import make_ctx


def accel_for_tilt(roll, pitch):
    """Specific force felt by a still body with this attitude (world +g up, seen in the body frame)."""
    return rpy_to_matrix(np.array([roll, pitch, 0.0])).T @ np.array([0.0, 0.0, GRAVITY_M_S2])


def test_tilt_from_accel_inverts_a_static_attitude():
    roll, pitch = np.deg2rad(7.0), np.deg2rad(-4.0)
    assert np.allclose(AttitudeKalmanFilter.tilt_from_accel(accel_for_tilt(roll, pitch)), [roll, pitch])


def test_filter_converges_to_a_static_tilt_from_level():
    kf = AttitudeKalmanFilter(KalmanFilterParams())
    a = accel_for_tilt(np.deg2rad(3.0), np.deg2rad(2.0))
    for _ in range(2000):
        rpy = kf.update(np.zeros(3), a, 0.005)
    assert np.allclose(np.rad2deg(rpy[:2]), [3.0, 2.0], atol=0.05)


def test_filter_learns_a_gyro_bias_and_does_not_drift():
    kf = AttitudeKalmanFilter(KalmanFilterParams())
    bias = np.array([0.01, -0.02, 0.0])  # rad/s
    a = accel_for_tilt(0.0, 0.0)
    for _ in range(20000):  # 100 s
        rpy = kf.update(bias, a, 0.005)
    assert np.all(np.abs(np.rad2deg(rpy[:2])) < 0.2)
    assert np.allclose(kf.bias, bias[:2], atol=2e-3)


def test_filter_follows_a_rotation_through_the_gyro():
    kf = AttitudeKalmanFilter(KalmanFilterParams())
    rate = np.deg2rad(10.0)  # pitching at 10 deg/s for 1 s
    dt = 0.005
    for k in range(200):
        pitch = rate * (k + 1) * dt
        rpy = kf.update(np.array([0.0, rate, 0.0]), accel_for_tilt(0.0, pitch), dt)
    assert abs(np.rad2deg(rpy[1]) - 10.0) < 0.2


def test_layer_writes_the_estimate_and_passes_the_reference_through():
    ctx = make_ctx(accel=accel_for_tilt(0.0, np.deg2rad(5.0)))
    layer = KalmanFilter(rpy0=(0.0, np.deg2rad(5.0), 0.0))
    ref = Reference.from_arrays(np.zeros(30))
    assert layer.tick(ctx, ref) is ref
    assert abs(np.rad2deg(ctx.estimate.base_rpy_rad[1]) - 5.0) < 0.05


def test_the_planned_body_acceleration_is_not_read_as_tilt():
    """Walking sway: a still-upright body accelerating sideways at 1 m/s^2, as the plan says (the
    AutoBalancer's cog_acc_world port of the tick before)."""
    a_world = np.array([0.0, 1.0, 0.0])
    ref = Reference.from_arrays(np.zeros(30))
    accel = a_world + np.array([0.0, 0.0, GRAVITY_M_S2])  # upright: the specific force is a - g
    for use, expected_roll in ((True, 0.0), (False, np.rad2deg(np.arctan2(1.0, GRAVITY_M_S2)))):
        layer = KalmanFilter(KalmanFilterParams(use_planned_acceleration=use))
        for _ in range(4000):  # 20 s, long enough for the accelerometer to win
            ctx = make_ctx(accel=accel)
            ctx.last_ports.cog_acc_world = a_world
            layer.tick(ctx, ref)
        assert abs(np.rad2deg(ctx.estimate.base_rpy_rad[0]) - expected_roll) < 0.1


def test_the_soles_tilt_is_the_measurement_when_the_stabilizer_publishes_one():
    """A landing: the accelerometer reads 2 deg of pitch that is not there (an unplanned acceleration); the
    soles' kinematics (Ports.body_tilt_kin_rad of the tick before) say 0.3 deg roll, -0.5 deg pitch. Without
    the port, or with use_sole_tilt off, the accelerometer wins."""
    ref = Reference.from_arrays(np.zeros(30))
    accel = accel_for_tilt(0.0, np.deg2rad(2.0))
    soles = (np.deg2rad(0.3), np.deg2rad(-0.5))
    for use, port, expected in ((True, soles, (0.3, -0.5)), (False, soles, (0.0, 2.0)), (True, None, (0.0, 2.0))):
        layer = KalmanFilter(KalmanFilterParams(use_sole_tilt=use))
        for _ in range(4000):  # 20 s
            ctx = make_ctx(accel=accel)
            ctx.last_ports.body_tilt_kin_rad = port
            layer.tick(ctx, ref)
        np.testing.assert_allclose(np.rad2deg(ctx.estimate.base_rpy_rad[:2]), expected, atol=0.05)


def test_the_soles_tilt_is_followed_within_a_tenth_of_a_second():
    """r_sole_tilt = 1e-4 rad^2 against q_angle 1e-6 per tick: a gain of ~0.1 per tick, so a 1 deg step of the
    soles' tilt is 90 % taken in 0.1 s (the accelerometer's r_angle 1e-2 takes seconds)."""
    kf = AttitudeKalmanFilter(KalmanFilterParams())
    for _ in range(200):
        kf.update(np.zeros(3), None, 0.005, tilt_rad=(0.0, 0.0))
    for _ in range(20):  # 0.1 s
        rpy = kf.update(np.zeros(3), None, 0.005, tilt_rad=(0.0, np.deg2rad(1.0)))
    assert np.rad2deg(rpy[1]) > 0.9
