"""TiltAnchor: the plan rotated about the support sole by the tilt a held robot came to rest at, levelling
along a minimum-jerk profile."""

import math

import numpy as np
import pinocchio as pin
import pytest

from controller.balance.tilt_anchor import TiltAnchor
from controller.kinematics.rotations import rpy_to_matrix

DT = 0.005
PIVOT = np.array([0.1, -0.095, 0.0])


def test_the_anchor_starts_at_the_measured_tilt_about_the_pivot():
    R_plan = rpy_to_matrix(np.array([0.0, 0.0, 0.3]))
    R_est = rpy_to_matrix(np.array([math.radians(-7.0), 0.0, 0.3]))  # rolled 7 deg onto the left
    t = TiltAnchor(R_plan, R_est, PIVOT, 2.0)
    assert t.angle0_rad == pytest.approx(math.radians(7.0))
    np.testing.assert_allclose(t.rotation(R_plan)[:, 2], R_est[:, 2], atol=1e-12)  # the body's z axis matches
    assert np.array_equal(t.point(PIVOT), PIVOT)
    # a point on the ground 0.19 m to the left of the pivot comes down by 0.19 sin(7 deg)
    left = t.point(PIVOT + R_plan @ np.array([0.0, 0.19, 0.0]))  # 0.19 m to the body's left
    assert left[2] == pytest.approx(-0.19 * math.sin(math.radians(7.0)), abs=1e-12)


def test_the_anchor_levels_along_a_minimum_jerk_profile_and_ends_level():
    t = TiltAnchor(np.eye(3), rpy_to_matrix(np.array([0.0, math.radians(4.0), 0.0])), PIVOT, 1.0)
    angles = []
    while not t.done:
        t.step(DT)
        angles.append(np.linalg.norm(pin.log3(t.R)))
    assert len(angles) == 200 and angles[-1] == 0.0 and np.allclose(t.R, np.eye(3))
    assert np.all(np.diff(angles) <= 1e-15)  # monotone
    assert angles[99] == pytest.approx(math.radians(2.0), rel=0.02)  # half way in the middle


def test_the_anchors_velocity_is_the_derivative_of_its_point():
    t = TiltAnchor(np.eye(3), rpy_to_matrix(np.array([0.1, 0.05, 0.0])), PIVOT, 1.0)
    p = np.array([0.0, 0.0, 0.8])
    for _ in range(60):
        t.step(DT)
    v = t.velocity(p, np.zeros(3))
    before = t.point(p)
    t.step(1e-6)
    np.testing.assert_allclose((t.point(p) - before) / 1e-6, v, atol=1e-6)


def test_a_level_robot_gives_no_rotation():
    t = TiltAnchor(np.eye(3), np.eye(3), PIVOT, 1.0)
    assert t.angle0_rad == 0.0 and np.array_equal(t.R, np.eye(3))
