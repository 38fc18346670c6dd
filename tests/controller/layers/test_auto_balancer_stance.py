"""The stance width a walk may start from: the soles' centres across, in the frame of their mean heading."""

import math

import numpy as np
import pytest

from controller.walking.auto_balancer_params import stance_width_m


def sole(x: float, y: float, yaw_deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    T = np.eye(4)
    T[:2, :2] = ((c, -s), (s, c))
    T[:2, 3] = (x, y)
    return T


@pytest.mark.parametrize("heading_deg", [0.0, 37.0, 90.0, -150.0])
@pytest.mark.parametrize("across_m, along_m", [(0.19, 0.0), (0.40, 0.0), (0.385, 0.134), (0.30, -0.25)])
def test_the_width_is_the_distance_across_whatever_the_heading_and_the_stride(heading_deg, across_m, along_m):
    c, s = math.cos(math.radians(heading_deg)), math.sin(math.radians(heading_deg))
    mid = np.array((1.3, -0.7))
    right = mid + 0.5 * np.array((c * -along_m - s * -across_m, s * -along_m + c * -across_m))
    left = mid + 0.5 * np.array((c * along_m - s * across_m, s * along_m + c * across_m))
    width = stance_width_m(sole(*right, heading_deg), sole(*left, heading_deg))
    assert width == pytest.approx(across_m, abs=1e-12)


def test_feet_turned_apart_are_measured_in_their_mean_heading():
    # the feet 0.2 m apart across, each turned 10 deg the other way: the mean heading is the x axis
    assert stance_width_m(sole(0.0, -0.1, -10.0), sole(0.0, 0.1, 10.0)) == pytest.approx(0.2, abs=1e-12)
