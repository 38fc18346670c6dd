"""[OP] Eq. 5 per point, and the twist checks (unit)."""

import numpy as np
import pytest

from controller.core.errors import InvalidCommand
from controller.operation.points import Twist, check_twist, sum_per_point


def test_eq5_adds_motion_and_behaviour_per_point_and_keeps_points_apart():
    motion = {"rhand": Twist.of((0.1, 0.0, 0.0)), "head": Twist.of(angular_rad_s=(0.0, 0.0, 0.5))}
    behaviour = {"rhand": Twist.of((0.0, 0.0, 0.05)), "lhand": Twist.of((0.0, 0.02, 0.0))}
    total = sum_per_point(motion, behaviour)
    assert np.allclose(total["rhand"].linear_m_s, (0.1, 0.0, 0.05))
    assert np.allclose(total["lhand"].linear_m_s, (0.0, 0.02, 0.0))
    assert np.allclose(total["head"].angular_rad_s, (0.0, 0.0, 0.5))
    assert "waist" not in total and "walk" not in total  # absent = zero


def test_a_point_given_an_unused_component_is_refused_by_name():
    with pytest.raises(InvalidCommand, match=r"head\.linear\.x"):
        check_twist("head", Twist.of((0.1, 0.0, 0.0)))
    with pytest.raises(InvalidCommand, match="valid"):
        check_twist("elbow", Twist.of())
