"""Targets in the feet frame: F from the soles, one tick of integration (unit)."""

import math

import numpy as np
import pinocchio as pin
import pytest

from controller.operation.points import Twist
from controller.operation.targets import GazeAngles, HandPose, WaistPose, feet_frame, yaw_rotation


def test_the_feet_frame_is_midway_between_the_soles_with_their_mean_yaw():
    p, yaw = feet_frame(np.array((0.0, -0.1, 0.0)), yaw_rotation(0.2), np.array((0.2, 0.1, 0.0)), yaw_rotation(0.4))
    assert np.allclose(p, (0.1, 0.0, 0.0)) and yaw == pytest.approx(0.3)


def test_a_hand_integrates_linear_and_angular_velocity_in_F():
    h = HandPose.of((0.3, -0.2, 0.8), np.eye(3))
    for _ in range(200):
        h = h.integrated(Twist.of((0.1, 0.0, 0.0), (0.0, 0.0, 0.5)), 0.005)
    assert np.allclose(h.p_feet_m, (0.4, -0.2, 0.8))
    assert np.allclose(h.R_feet_hand, yaw_rotation(0.5))
    assert h.integrated(Twist.of(), 0.005) is h


def test_gaze_and_waist_integrate_their_rates():
    g = GazeAngles(0.0, 0.0).integrated(Twist.of(angular_rad_s=(0.0, 0.1, 0.5)), 1.0)
    assert (g.pitch_rad, g.yaw_rad) == pytest.approx((0.1, 0.5))
    back = GazeAngles.of_direction(g.direction_feet())
    assert (back.pitch_rad, back.yaw_rad) == pytest.approx((0.1, 0.5))
    w = WaistPose(0.65, (0.0, 0.0, 0.0)).integrated(Twist.of((0, 0, -0.05), (0.0, 0.1, 0.0)), 2.0)
    assert w.height_m == pytest.approx(0.55) and w.rpy_rad == pytest.approx((0.0, 0.2, 0.0))
    assert math.isclose(GazeAngles(0.3, 0.0).direction_feet()[2], -math.sin(0.3))


def test_a_hand_advanced_by_a_share_of_its_step_goes_along_the_line_and_the_geodesic():
    a = HandPose.of([0.3, -0.2, 0.8], np.eye(3))
    b = HandPose.of([0.4, -0.2, 0.9], pin.exp3(np.array([0.0, 0.0, 0.4])))
    step = a.step_to(b, 0.1)
    np.testing.assert_allclose(step, [0.1, 0.0, 0.1, 0.0, 0.0, 0.04], atol=1e-12)
    half = a.advanced(b, 0.5)
    np.testing.assert_allclose(half.p_feet_m, [0.35, -0.2, 0.85], atol=1e-12)
    np.testing.assert_allclose(pin.log3(half.R_feet_hand), [0.0, 0.0, 0.2], atol=1e-12)
    assert a.advanced(b, 1.0) is b and a.advanced(b, 0.0) is a


@pytest.mark.parametrize("rotated", [False, True])
def test_advanced_along_is_the_share_of_the_step_made_along_it(rotated):
    from controller.operation.limits import share_along

    start = HandPose.of([0.3, -0.2, 0.8], np.eye(3))
    target = start.integrated(Twist.of((0.1, 0.0, 0.02), (0.0, 0.0, 0.3 if rotated else 0.0)), 0.1)
    assert (target.R_feet_hand is start.R_feet_hand) is not rotated  # integrated() keeps the rotation object
    achieved = HandPose.of(start.p_feet_m + [0.004, 0.003, -0.001], pin.exp3(np.array([0.01, 0.0, 0.01])))
    share = share_along(start.step_to(target, 0.1), start.step_to(achieved, 0.1))
    expected = start.advanced(target, share)
    out = start.advanced_along(target, achieved, 0.1)
    np.testing.assert_allclose(out.p_feet_m, expected.p_feet_m, atol=1e-12)
    np.testing.assert_allclose(out.R_feet_hand, expected.R_feet_hand, atol=1e-12)
    assert 0.0 < share < 1.0
    assert start.advanced_along(target, start, 0.1) is start and start.advanced_along(target, target, 0.1) is target


def test_the_status_layout_of_each_target_kind():
    from controller.operation.targets import status_layout

    anchor = np.array((0.01, 0.0, 0.5))
    hand = status_layout(HandPose.of((0.3, -0.2, 0.3), yaw_rotation(0.2)), anchor)
    assert hand == pytest.approx((0.31, -0.2, 0.8, 0.0, 0.0, 0.2))
    assert status_layout(GazeAngles(0.1, 0.5), anchor) == (0.1, 0.5)
    assert status_layout(WaistPose(0.6, (0.0, 0.1, 0.0)), anchor) == (0.6, 0.0, 0.1, 0.0)
    assert status_layout(None, anchor) is None
