"""The float fast paths of the rotation helpers agree with the numpy ones."""

import numpy as np
import pytest

from controller.kinematics.rotations import matrix_to_rpy, matrix_to_rpy_floats, rpy_to_matrix


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
