"""Capture point and support-polygon geometry."""

import numpy as np
import pytest

from controller.balance.capture_point import (
    HRP2_LEFT_SOLE,
    HRP2_RIGHT_SOLE,
    FootRectangle,
    capture_point,
    capture_point_error,
    convex_hull_2d,
    distance_to_polygon_edge,
    nearest_point_in_convex_polygon,
    omega,
    point_in_convex_polygon,
    shrink_polygon,
    support_polygon,
)
from controller.core.errors import InvalidCommand

SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])  # CCW unit square [m]


def same_polygon(a, b) -> bool:
    """Same vertex set, whatever the starting vertex."""
    a, b = np.asarray(a), np.asarray(b)
    return len(a) == len(b) and all(np.isclose(np.linalg.norm(b - p, axis=1), 0.0).any() for p in a)


def test_omega_is_sqrt_g_over_z():
    assert omega(0.8, 9.8) == pytest.approx(3.5)
    with pytest.raises(InvalidCommand):
        omega(0.0)


def test_capture_point_is_com_plus_velocity_over_omega():
    # z_c = 0.8 m, g = 9.8 -> omega = 3.5 /s; v = (0.35, -0.7) m/s -> offset (0.1, -0.2) m
    cp = capture_point([0.01, 0.02], [0.35, -0.7], omega(0.8, 9.8))
    assert np.allclose(cp, [0.11, -0.18])


def test_capture_point_error_is_ref_minus_act_with_its_norm():
    err, norm = capture_point_error([0.03, 0.0], [0.0, 0.04])
    assert np.allclose(err, [0.03, -0.04]) and norm == pytest.approx(0.05)


def test_hull_of_a_square_drops_interior_and_edge_points():
    pts = np.vstack([SQUARE, [[0.5, 0.5], [0.5, 0.0], [0.2, 0.7]]])
    hull = convex_hull_2d(pts[::-1])
    assert same_polygon(hull, SQUARE)
    x, y = hull[:, 0], hull[:, 1]
    assert np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) > 0  # counter-clockwise


def test_shrinking_a_rectangle_moves_every_edge_in_by_the_margin():
    rect = np.array([[-0.1, -0.05], [0.2, -0.05], [0.2, 0.05], [-0.1, 0.05]])
    shrunk = shrink_polygon(rect, 0.02)
    assert same_polygon(shrunk, [[-0.08, -0.03], [0.18, -0.03], [0.18, 0.03], [-0.08, 0.03]])


def test_shrinking_by_more_than_the_half_width_leaves_nothing():
    rect = np.array([[-0.1, -0.05], [0.2, -0.05], [0.2, 0.05], [-0.1, 0.05]])
    assert shrink_polygon(rect, 0.06).shape == (0, 2)


def test_point_in_polygon_includes_the_boundary_and_accepts_clockwise_vertices():
    assert point_in_convex_polygon([0.5, 0.5], SQUARE)
    assert point_in_convex_polygon([1.0, 0.3], SQUARE)
    assert not point_in_convex_polygon([1.01, 0.3], SQUARE)
    assert point_in_convex_polygon([0.5, 0.5], SQUARE[::-1])


def test_signed_edge_distance_is_positive_inside_and_negative_outside():
    assert distance_to_polygon_edge([0.5, 0.2], SQUARE) == pytest.approx(0.2)
    assert distance_to_polygon_edge([1.3, 0.5], SQUARE) == pytest.approx(-0.3)
    assert distance_to_polygon_edge([1.3, 1.4], SQUARE) == pytest.approx(-0.5)  # nearest is the corner


def test_nearest_point_outside_is_the_projection_on_the_edge():
    assert np.allclose(nearest_point_in_convex_polygon([1.5, 0.25], SQUARE), [1.0, 0.25])
    assert np.allclose(nearest_point_in_convex_polygon([-1.0, 2.0], SQUARE), [0.0, 1.0])
    assert np.allclose(nearest_point_in_convex_polygon([0.3, 0.4], SQUARE), [0.3, 0.4])


def test_hrp2_soles_span_the_published_mesh_extents():
    assert np.allclose(HRP2_RIGHT_SOLE.corners_foot().min(0), [-0.0936, -0.079])
    assert np.allclose(HRP2_RIGHT_SOLE.corners_foot().max(0), [0.1236, 0.059])
    assert np.allclose(HRP2_LEFT_SOLE.corners_foot().min(0), [-0.0936, -0.059])
    assert np.allclose(HRP2_LEFT_SOLE.corners_foot().mean(0), [0.015, 0.01])


def test_support_polygon_of_two_hrp2_feet_side_by_side():
    poly = support_polygon([((0.0, -0.095, 0.0), HRP2_RIGHT_SOLE), ((0.0, 0.095, 0.0), HRP2_LEFT_SOLE)])
    # x from the heel -0.0936 to the toe 0.1236; y from -0.095 - 0.079 to 0.095 + 0.079
    expected = [[-0.0936, -0.174], [0.1236, -0.174], [0.1236, 0.174], [-0.0936, 0.174]]
    assert same_polygon(poly, expected)
    assert point_in_convex_polygon([0.015, 0.0], poly)  # between the feet is supported


def test_a_yawed_foot_rotates_its_rectangle_about_the_ankle():
    foot = FootRectangle(front_m=0.2, rear_m=0.0, left_m=0.05, right_m=0.05)
    poly = support_polygon([((1.0, 2.0, np.pi / 2), foot)])
    assert same_polygon(poly, [[1.05, 2.0], [1.05, 2.2], [0.95, 2.2], [0.95, 2.0]])


# ---- the same on plain floats (the emergency step's every tick): the numpy functions' floats, bit for bit


def _random_feet(rng):
    yaw = rng.uniform(-3.0, 3.0)
    return [((rng.normal() * 0.3, rng.normal() * 0.3, yaw), HRP2_RIGHT_SOLE),
            ((rng.normal() * 0.3, rng.normal() * 0.3, yaw + rng.normal() * 0.1), HRP2_LEFT_SOLE)]


def test_the_float_polygon_functions_give_the_numpy_ones_floats_bit_for_bit():
    from controller.balance.capture_point import (
        convex_hull_2d,
        convex_hull_xy,
        nearest_point_in_convex_polygon_xy,
        shrink_polygon_xy,
    )

    rng = np.random.default_rng(7)
    for _ in range(300):
        feet = _random_feet(rng)
        corners = np.concatenate([rect.corners_world(pose) for pose, rect in feet])
        hull = convex_hull_2d(corners)
        assert [tuple(v) for v in hull.tolist()] == convex_hull_xy(corners.tolist())
        for poly in (hull, corners[:4]):  # the two soles' hull, one sole's corners
            margin = float(rng.choice([0.0, 0.015, 0.05, 0.3]))
            shrunk = shrink_polygon(poly, margin)
            shrunk_xy = shrink_polygon_xy(poly.tolist(), margin)
            assert [tuple(v) for v in shrunk.tolist()] == shrunk_xy
            if len(shrunk):
                for p in rng.normal(size=(4, 2)) * 0.4:
                    assert tuple(nearest_point_in_convex_polygon(p, shrunk).tolist()) == \
                        nearest_point_in_convex_polygon_xy(*p.tolist(), shrunk_xy)


def test_the_slack_in_the_shrunk_polygon_is_the_distance_inside_its_edges():
    from controller.balance.capture_point import slack_in_shrunk_polygon_m

    square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    assert slack_in_shrunk_polygon_m(0.5, 0.3, square, 0.1) == pytest.approx(0.2)
    assert slack_in_shrunk_polygon_m(0.5, 0.05, square, 0.1) == pytest.approx(-0.05)
    assert slack_in_shrunk_polygon_m(0.5, 0.05, square[::-1], 0.1) == pytest.approx(-0.05)  # clockwise given
    rng = np.random.default_rng(3)
    for _ in range(200):  # its sign is shrink_polygon's inside, away from the boundary
        hull = support_polygon(_random_feet(rng))
        shrunk = shrink_polygon(hull, 0.015)
        p = rng.normal(size=2) * 0.3
        slack = slack_in_shrunk_polygon_m(*p.tolist(), hull.tolist(), 0.015)
        if abs(slack) > 1e-9:
            assert (slack > 0.0) == (len(shrunk) > 0 and distance_to_polygon_edge(p, shrunk) > 0.0)
