"""The operation IK's plane geometry: the support polygon's margin and nearest safe point, the guard box, 3-vectors."""

import math

import numpy as np
import pytest

from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE, distance_to_polygon_edge, support_polygon
from controller.kinematics.operation_geometry import GuardBox, SupportPolygon, clip3, clip3_flagged, split_pose

SOLES = [((0.0, -0.1, 0.0), HRP2_RIGHT_SOLE), ((0.0, 0.1, 0.2), HRP2_LEFT_SOLE)]


def test_the_margin_is_the_distance_to_the_support_polygons_edge_inside_and_negative_outside():
    poly = SupportPolygon(SOLES, 0.04)
    hull = support_polygon(SOLES)
    for x, y in ((0.0, 0.0), (0.05, -0.02), (0.1, 0.15)):
        assert poly.margin(x, y) == pytest.approx(distance_to_polygon_edge(np.array((x, y)), hull), abs=1e-12)
    assert poly.margin(0.0, 0.0) > 0.0 > poly.margin(0.5, 0.0)


def test_the_nearest_safe_point_keeps_an_inside_point_and_brings_an_outside_one_to_the_inset():
    poly = SupportPolygon(SOLES, 0.04)
    assert poly.nearest_safe(0.01, 0.0) == (0.01, 0.0)
    x, y = poly.nearest_safe(0.5, 0.0)
    assert poly.margin(x, y) == pytest.approx(0.04, abs=1e-9)


def test_an_inset_larger_than_the_polygon_leaves_one_safe_point_inside_it():
    poly = SupportPolygon([((0.0, 0.0, 0.0), HRP2_RIGHT_SOLE)], 0.2)
    x, y = poly.nearest_safe(1.0, 1.0)
    assert poly.margin(x, y) > 0.0


def test_the_guard_box_margin_is_the_distance_to_its_nearest_side():
    box = GuardBox(0.01, -0.02, 0.04)
    assert box.margin(0.01, -0.02) == pytest.approx(0.04)
    assert box.margin(0.04, -0.02) == pytest.approx(0.01)
    assert box.margin(0.06, -0.02) == pytest.approx(-0.01)
    assert len(box.clockwise) == 4


def test_a_vector_is_shortened_to_the_limit_keeping_its_direction():
    assert clip3_flagged((3.0, 0.0, 4.0), 10.0) == ((3.0, 0.0, 4.0), False)
    v, clipped = clip3_flagged((3.0, 0.0, 4.0), 1.0)
    assert clipped and math.hypot(*v) == pytest.approx(1.0) and v[0] / v[2] == pytest.approx(0.75)
    assert clip3((3.0, 0.0, 4.0), 1.0) == v


def test_a_pose_splits_into_its_position_and_rotation_rows():
    T = np.arange(16.0).reshape(4, 4).tolist()
    assert split_pose(T) == ((3.0, 7.0, 11.0), ((0.0, 1.0, 2.0), (4.0, 5.0, 6.0), (8.0, 9.0, 10.0)))
