"""The EXPO behaviours' stance geometry (unit): where take_can stands for a located can given the table's
known near edge, when it judges the can within reach, and how throw_can splits its walk to the box."""

from __future__ import annotations

import math

import numpy as np
import pytest

from behaviors.take_can import (
    FEET_TO_EDGE_MIN_M,
    GRASP_CAN_FEET_M,
    GRASP_CAN_X_MAX_M,
    grasp_can_x_feet,
    stance_for,
    within_reach,
)
from behaviors.throw_can import along_then_aside


@pytest.mark.parametrize("in_m, x_m", [(0.10, GRASP_CAN_FEET_M[0]), (0.15, GRASP_CAN_FEET_M[0]),
                                       (0.25, 0.25 + FEET_TO_EDGE_MIN_M), (0.30, GRASP_CAN_X_MAX_M)])
def test_a_can_far_in_from_the_edge_is_taken_farther_out_so_the_feet_keep_off_the_edge(in_m, x_m):
    assert grasp_can_x_feet(in_m) == pytest.approx(x_m)
    assert grasp_can_x_feet(in_m) - in_m >= min(FEET_TO_EDGE_MIN_M, GRASP_CAN_X_MAX_M - in_m) - 1e-12


def test_the_stance_puts_the_can_where_asked_in_the_feet_frame_at_any_heading():
    can = np.array([2.2, 0.4, 0.75])
    for yaw in (0.0, math.radians(30.0), -math.pi / 2):
        x, y = stance_for(can, yaw, 0.5, back_m=0.1)
        c, s = math.cos(yaw), math.sin(yaw)
        d = can[:2] - np.array([x, y])
        assert (c * d[0] + s * d[1], -s * d[0] + c * d[1]) == pytest.approx((0.6, GRASP_CAN_FEET_M[1]))


def test_within_reach_needs_the_reach_box_and_the_feet_clear_of_the_edge():
    assert within_reach((0.43, -0.22, 0.75), 0.15)
    assert not within_reach((0.43, -0.22, 0.75), 0.29)  # feet 0.14 m from the edge: too close
    assert within_reach((0.50, -0.22, 0.75), 0.29)
    assert not within_reach((0.60, -0.22, 0.75), 0.10)  # out of the box
    assert not within_reach((0.43, -0.40, 0.75), 0.15)
    assert within_reach((0.43, -0.22, 0.75))  # no edge given: the box alone


def test_the_walk_to_the_box_splits_into_ahead_and_left():
    # facing -y (world), the goal 1.2 m ahead and 0.29 m to the left (+x)
    ahead, aside = along_then_aside((0.92, 0.23), (1.21, -0.97), -math.pi / 2)
    assert (ahead, aside) == pytest.approx((1.20, 0.29))
