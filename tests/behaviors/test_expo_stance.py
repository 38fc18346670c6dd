"""The EXPO behaviours' stance geometry (unit): where take_can stands for a located can given the table's
known near edge and legs, when it judges the can within reach, and how throw_can splits its walk to the box."""

from __future__ import annotations

import math

import numpy as np
import pytest

from behaviors.table_model import KnownTable
from behaviors.take_can import (
    CAN_Y_FEET_RANGE_M,
    FEET_TO_EDGE_MIN_M,
    GRASP_CAN_FEET_M,
    GRASP_CAN_X_MAX_M,
    KNEE_TO_LEG_MIN_M,
    grasp_beside_legs,
    grasp_can_x_feet,
    legs_clear_of_table_legs,
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


# ---- the table's legs ------------------------------------------------------------------------------------
TABLE = KnownTable(near_edge_x_m=2.0)  # legs 0.68-0.72 m either side of y = 0, faces at x = 2.03


def test_the_known_table_places_its_near_legs_as_the_scene_does():
    assert TABLE.near_leg_face_x_m == pytest.approx(2.03)
    (r0, r1), (l0, l1) = TABLE.near_leg_spans_y_m()
    assert (r0, r1, l0, l1) == pytest.approx((-0.72, -0.68, 0.68, 0.72))
    moved = TABLE.shifted(-0.05, 0.02)
    assert moved.near_leg_face_x_m == pytest.approx(1.98)
    assert moved.near_leg_spans_y_m()[1] == pytest.approx((0.70, 0.74))


def test_the_legs_are_clear_of_a_table_leg_only_with_the_clearance_across():
    # the left leg reaches feet y + 0.095 + 0.095, the right leg's inner side feet y - 0.095 + 0.06; the table
    # leg spans 0.68-0.72; 0.03 m clearance
    assert legs_clear_of_table_legs(0.68 - 0.03 - 0.19 - 1e-6, TABLE)
    assert not legs_clear_of_table_legs(0.68 - 0.03 - 0.19 + 0.005, TABLE)
    assert legs_clear_of_table_legs(0.72 + 0.03 + 0.19 + 1e-6, TABLE)  # the whole robot beyond the table's end
    assert not legs_clear_of_table_legs(0.72 + 0.03 + 0.035, TABLE)  # straddling the leg: the right knee on it
    assert not legs_clear_of_table_legs(0.60, TABLE)  # the left foot in line with the leg
    assert not legs_clear_of_table_legs(-0.60, TABLE)  # the right foot in line with the other leg
    assert legs_clear_of_table_legs(0.0, TABLE)


def test_a_can_away_from_the_legs_is_taken_where_the_arm_likes_it():
    assert grasp_beside_legs((2.15, 0.0, 0.75), 0.0, 0.43, TABLE) == pytest.approx((0.43, GRASP_CAN_FEET_M[1]))


def test_a_can_a_little_in_from_the_legs_is_taken_with_the_stance_shifted_inside_them():
    can = (2.20, 0.27, 0.75)  # taken as usual, the left knee would stand in line with the leg
    assert not legs_clear_of_table_legs(stance_for(can, 0.0, 0.43)[1], TABLE)
    x, y = grasp_beside_legs(can, 0.0, 0.43, TABLE)
    assert x == pytest.approx(0.43) and CAN_Y_FEET_RANGE_M[0] <= y <= CAN_Y_FEET_RANGE_M[1]
    assert y > GRASP_CAN_FEET_M[1]  # the can farther left of the feet: the robot stands farther right
    assert legs_clear_of_table_legs(stance_for(can, 0.0, x, y_feet_m=y)[1], TABLE)


@pytest.mark.parametrize("can_y", [0.37, 0.47, 0.60])
def test_a_can_near_a_table_leg_is_taken_from_where_the_knees_keep_off_it(can_y):
    # seed 2005, trial 10 (U 0.47): the left foot stood in line with the leg 0.25 m from its face, its knee met it
    # lifting in place, and the robot fell; no stance of the reach box clears the leg across
    can = (2.20, can_y, 0.75)
    for y_try in np.linspace(*CAN_Y_FEET_RANGE_M, 21):
        assert not legs_clear_of_table_legs(stance_for(can, 0.0, 0.43, y_feet_m=y_try)[1], TABLE)
    x, y = grasp_beside_legs(can, 0.0, 0.43, TABLE)
    assert y == pytest.approx(GRASP_CAN_FEET_M[1])
    feet_x, _ = stance_for(can, 0.0, x, y_feet_m=y)
    assert feet_x == pytest.approx(TABLE.near_leg_face_x_m - KNEE_TO_LEG_MIN_M)


def test_feet_far_enough_back_need_no_clearance_across():
    can = (2.15, 0.47, 0.75)  # the feet 0.40 m back from the leg's face
    assert grasp_beside_legs(can, 0.0, 0.52, TABLE) == pytest.approx((0.52, GRASP_CAN_FEET_M[1]))
