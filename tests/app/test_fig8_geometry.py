"""The small geometry of the Fig. 8 experiments: the trash's stance and its position in the feet frame (inverse
of each other), the left hand's grasp on a turned chair's rail."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.lab.experiments.chair import hand_rotation
from app.lab.experiments.trash import in_feet, stance_for

pytestmark = pytest.mark.in_process  # in this process, no wall clock: on make test's parallel pass


@pytest.mark.parametrize("yaw_deg", [0.0, 30.0, -120.0])
def test_the_stance_puts_the_target_where_asked_in_the_feet_frame(yaw_deg):
    target = np.array([1.4, 0.2])
    stance = stance_for(target, (0.24, -0.33), math.radians(yaw_deg))
    got = in_feet(target, (stance[0], stance[1], yaw_deg))
    assert got == pytest.approx([0.24, -0.33], abs=1e-12)


@pytest.mark.parametrize("yaw_deg", [-10.0, 0.0, 10.0])
def test_the_hand_on_the_rail_points_along_the_chair_with_its_jaws_vertical(yaw_deg):
    R = hand_rotation(math.radians(yaw_deg))
    assert R.T @ R == pytest.approx(np.eye(3), abs=1e-12) and np.linalg.det(R) == pytest.approx(1.0)
    forward = np.array([math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg)), 0.0])
    assert R[:, 2] == pytest.approx(-forward, abs=1e-12)  # the hand's z axis back along its approach
    assert R[:, 0] == pytest.approx([0.0, 0.0, 1.0])  # the jaws close vertically across the horizontal rail
