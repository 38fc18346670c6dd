"""behaviors.servo (unit): the capped proportional approach keeps its direction; rotation vectors."""

import math

import numpy as np
import pytest

from behaviors.servo import rot_z, rotation_vector, toward, wrap_rad
from controller.kinematics.rotations import rpy_to_matrix


def test_toward_is_proportional_below_the_cap_and_capped_along_the_same_direction():
    np.testing.assert_allclose(toward(np.array([0.01, 0.0, 0.0]), 2.0, 0.1), [0.02, 0, 0])
    v = toward(np.array([3.0, 4.0, 0.0]), 2.0, 0.1)
    assert np.linalg.norm(v) == pytest.approx(0.1)
    np.testing.assert_allclose(v / np.linalg.norm(v), [0.6, 0.8, 0.0])


@pytest.mark.parametrize("rpy", [(0.1, -0.2, 0.3), (0.0, 0.0, 3.0), (1.0, 0.5, -2.0), (math.pi - 1e-7, 0, 0)])
def test_rotation_vector_turns_one_orientation_into_the_other(rpy):
    R0 = rpy_to_matrix(np.array([0.2, 0.1, -0.4]))
    R1 = rpy_to_matrix(np.array(rpy)) @ R0
    w = rotation_vector(R0, R1)
    angle = np.linalg.norm(w)
    k = w / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    R = np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K
    np.testing.assert_allclose(R @ R0, R1, atol=1e-6)


def test_wrap_and_yaw():
    assert wrap_rad(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    np.testing.assert_allclose(rot_z(math.pi / 2) @ [1, 0, 0], [0, 1, 0], atol=1e-12)
