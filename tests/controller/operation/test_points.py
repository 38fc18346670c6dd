"""[OP] Eq. 5 per point, and the twist checks (unit)."""

import math

import numpy as np
import pytest

from controller.core.errors import InvalidCommand
from controller.operation.points import OperationView, PointPose, Twist, check_twist, sum_per_point


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


def test_a_view_placed_in_the_world_moves_its_world_poses_and_keeps_what_is_relative_to_the_feet():
    R_feet_hand = np.eye(3)
    hand = PointPose(p_world_m=np.array((1.3, -0.2, 0.9)), R_world_point=np.eye(3), p_feet_m=np.array((0.3, -0.2, 0.9)),
                     R_feet_point=R_feet_hand)
    view = OperationView(time_s=1.0, feet_p_world_m=np.array((1.0, 0.0, 0.0)), feet_yaw_rad=0.0,
                         points={"rhand": hand}, gaze_rad=(0.0, 0.0), waist_height_m=0.7, walking=False,
                         motion_stopped=False)
    placed = view.placed_in_world((0.02, -0.01, 0.0, math.radians(90.0)))
    np.testing.assert_allclose(placed.feet_p_world_m, (0.02, 1.0 - 0.01, 0.0), atol=1e-12)
    assert placed.feet_yaw_rad == pytest.approx(math.pi / 2)
    np.testing.assert_allclose(placed.points["rhand"].p_world_m, (0.02 + 0.2, 1.3 - 0.01, 0.9), atol=1e-12)
    np.testing.assert_allclose(placed.points["rhand"].R_world_point[:, 0], (0.0, 1.0, 0.0), atol=1e-12)
    assert placed.points["rhand"].p_feet_m is hand.p_feet_m and placed.waist_height_m == 0.7
    # the hand relative to the feet is the same in both
    rel = placed.points["rhand"].p_world_m - placed.feet_p_world_m
    c, s = math.cos(placed.feet_yaw_rad), math.sin(placed.feet_yaw_rad)
    np.testing.assert_allclose((c * rel[0] + s * rel[1], -s * rel[0] + c * rel[1], rel[2]), hand.p_feet_m, atol=1e-12)
