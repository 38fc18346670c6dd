"""Rotation helpers: the float fast paths agree with the numpy ones and with pinocchio, and give known values."""

import numpy as np
import pinocchio as pin
import pytest

from controller.kinematics.rotations import (
    matrix_to_rpy,
    matrix_to_rpy_floats,
    quat_wxyz_to_matrix,
    quat_xyzw_to_rows,
    quat_xyzw_to_rpy,
    rows_angle_between,
    rows_exp3,
    rows_log3,
    rows_small_log3,
    rpy_to_matrix,
)


@pytest.mark.parametrize("rpy", [(0.0, 0.0, 0.0), (0.3, -0.2, 2.9), (-3.0, 1.5, -0.1), (0.1, np.pi / 2, 0.4),
                                 (0.2, -np.pi / 2, -1.0)])
def test_matrix_to_rpy_floats_is_matrix_to_rpy(rpy):
    R = rpy_to_matrix(np.array(rpy))
    floats = matrix_to_rpy_floats(R)
    assert all(type(v) is float for v in floats)
    np.testing.assert_allclose(floats, matrix_to_rpy(R), rtol=0.0, atol=1e-15)


def test_matrix_to_rpy_floats_recovers_the_angles():
    rng = np.random.default_rng(3)
    for rpy in rng.uniform((-np.pi, -1.5, -np.pi), (np.pi, 1.5, np.pi), size=(200, 3)):
        np.testing.assert_allclose(matrix_to_rpy_floats(rpy_to_matrix(rpy)), rpy, rtol=0.0, atol=1e-12)


# ---- SO(3) on row tuples -----------------------------------------------------------------------------------

IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


def rows(R: np.ndarray):
    return tuple(map(tuple, np.asarray(R).tolist()))


def test_exp3_of_a_quarter_turn_about_z_is_the_known_matrix():
    R = np.array(rows_exp3((0.0, 0.0, np.pi / 2)))
    np.testing.assert_allclose(R, [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], atol=1e-15)


def test_log3_inverts_exp3_over_all_angles_including_near_zero_and_a_half_turn():
    rng = np.random.default_rng(1)
    axes = rng.normal(size=(40, 3))
    angles = np.concatenate([rng.uniform(0, np.pi, 34), [0.0, 1e-9, 1e-4, np.pi - 1e-4, np.pi - 1e-8, np.pi]])
    for axis, angle in zip(axes, angles, strict=True):
        w = axis / np.linalg.norm(axis) * angle
        R = pin.exp3(w)
        np.testing.assert_allclose(rows_exp3(tuple(w)), R, atol=1e-12)  # Rodrigues, as pinocchio
        # the rotation vector back (at a half turn w and -w are the same rotation: compare rotations; within
        # 1e-8 rad of it the axis comes from the diagonal with half the digits, measured 2.6e-8, so 1e-7)
        np.testing.assert_allclose(pin.exp3(np.array(rows_log3(rows(R)))), R, rtol=0.0, atol=1e-7)
        if angle < np.pi - 1e-3:
            np.testing.assert_allclose(rows_log3(rows(R)), w, atol=1e-9)


def test_small_log3_is_log3_to_first_order():
    w = (1e-3, -2e-3, 0.5e-3)  # 2.3 mrad: error ~ angle^3 / 6 ~ 2e-9 rad
    np.testing.assert_allclose(rows_small_log3(rows_exp3(w)), w, atol=1e-8)
    big = (0.0, 0.0, 0.5)
    assert rows_small_log3(rows_exp3(big))[2] == pytest.approx(np.sin(0.5))  # not the angle any more


def test_angle_between_two_rotations_is_the_angle_of_the_relative_rotation():
    assert rows_angle_between(IDENTITY, IDENTITY) == 0.0
    A = rows(rpy_to_matrix(np.array((0.3, -0.2, 1.0))))
    B = rows(np.asarray(A) @ pin.exp3(np.array((0.0, 0.6, 0.8)) * 0.7))  # 0.7 rad about a unit axis
    assert rows_angle_between(A, B) == pytest.approx(0.7, abs=1e-12)
    assert rows_angle_between(B, A) == pytest.approx(0.7, abs=1e-12)
    assert rows_angle_between(IDENTITY, rows_exp3((np.pi, 0.0, 0.0))) == pytest.approx(np.pi)


@pytest.mark.parametrize(("xyzw", "R"), [
    ((0.0, 0.0, 0.0, 1.0), [[1, 0, 0], [0, 1, 0], [0, 0, 1]]),
    ((0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)), [[0, -1, 0], [1, 0, 0], [0, 0, 1]]),  # +90 deg about z
    ((1.0, 0.0, 0.0, 0.0), [[1, 0, 0], [0, -1, 0], [0, 0, -1]]),  # half turn about x
    ((0.0, 2.0, 0.0, 2.0), [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]),  # +90 deg about y, not normalised
])
def test_quaternion_to_rows_and_to_rpy_give_the_known_rotation(xyzw, R):
    np.testing.assert_allclose(quat_xyzw_to_rows(*xyzw), R, atol=1e-15)
    np.testing.assert_allclose(rpy_to_matrix(np.array(quat_xyzw_to_rpy(*xyzw))), R, atol=1e-15)
    x, y, z, w = xyzw
    np.testing.assert_allclose(quat_wxyz_to_matrix(np.array((w, x, y, z))), R, atol=1e-15)  # MuJoCo's order


def test_quaternion_to_rpy_recovers_the_angles_of_pinocchios_quaternion():
    rng = np.random.default_rng(2)
    for rpy in rng.uniform([-1.0, -1.4, -3.0], [1.0, 1.4, 3.0], size=(20, 3)):
        x, y, z, w = pin.Quaternion(rpy_to_matrix(rpy)).coeffs()
        np.testing.assert_allclose(quat_xyzw_to_rpy(x, y, z, w), rpy, atol=1e-9)
        np.testing.assert_allclose(quat_xyzw_to_rows(x, y, z, w), rpy_to_matrix(rpy), atol=1e-12)
