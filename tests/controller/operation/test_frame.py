"""The feet frame as a planar frame: world <-> F for points and rotations, on floats as with matrices (unit)."""

import math

import numpy as np
import pytest

from controller.kinematics.rotations import rpy_to_matrix
from controller.operation.frame import PlanarFrame, sole_from_sole, sub3
from controller.operation.targets import yaw_rotation


def test_a_point_goes_to_the_frame_and_back():
    F = PlanarFrame(np.array((0.3, -0.1, 0.05)), 0.4)
    p_world = np.array((1.0, 0.5, 0.8))
    p_local = F.to_local(p_world)
    assert np.allclose(p_local, yaw_rotation(0.4).T @ (p_world - F.p))
    assert np.allclose(F.to_world(p_local), p_world)


def test_to_local_rpy_on_floats_is_to_local_with_the_rotation_matrix():
    F = PlanarFrame((0.3, -0.1, 0.05), -0.7)
    p_world, rpy = np.array((1.0, 0.5, 0.8)), np.array((0.1, -0.2, 0.3))
    p, R = F.to_local_rpy(p_world, rpy)
    p_ref, R_ref = F.to_local(p_world, rpy_to_matrix(rpy))
    assert np.allclose(p, p_ref, atol=1e-15) and np.allclose(R, R_ref, atol=1e-15)
    p_rows, R_rows = F.to_local_rpy_rows(p_world, rpy)  # the same floats, not in arrays
    assert p_rows == tuple(p.tolist()) and R_rows == tuple(map(tuple, R.tolist()))


def test_to_world_rows_on_floats_is_to_world_with_the_rotation_matrix():
    F = PlanarFrame((0.3, -0.1, 0.05), 1.2)
    R_local = rpy_to_matrix(np.array((0.2, 0.1, -0.4)))
    p_w, R_w = F.to_world_rows((0.2, 0.3, 0.7), R_local.tolist())
    p_ref, R_ref = F.to_world(np.array((0.2, 0.3, 0.7)), R_local)
    assert np.allclose(p_w, p_ref, atol=1e-15) and np.allclose(R_w, R_ref, atol=1e-15)


def test_the_left_sole_is_seen_from_the_right_one_with_its_relative_yaw_wrapped():
    p_r, p_l = np.array((1.0, 2.0, 0.0)), np.array((1.0, 2.2, 0.0))
    x, y, yaw = sole_from_sole(p_r, yaw_rotation(math.pi / 2), p_l, yaw_rotation(-math.pi + 0.1))
    assert (x, y) == pytest.approx((0.2, 0.0), abs=1e-12)  # 0.2 m to the left in the world: ahead of a sole facing +y
    assert yaw == pytest.approx(-3 * math.pi / 2 + 0.1 + 2 * math.pi)


def test_sub3_subtracts_two_vectors_of_floats():
    assert sub3((1.0, 2.0, 3.0), (0.5, 0.5, 4.0)) == (0.5, 1.5, -1.0)
    assert "yaw=0.5" in repr(PlanarFrame((0.0, 0.0, 0.0), 0.5))
