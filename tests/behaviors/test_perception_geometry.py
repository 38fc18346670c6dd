"""Perception's geometry and segmentation pieces on synthetic data: back-projection, fits, colour masks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from behaviors.perception import InvalidImage
from behaviors.perception.geometry import (
    back_project,
    fit_circle_known_radius,
    min_area_rectangle,
    project,
    transform,
)
from behaviors.perception.segmentation import GREEN, RED, colour_mask, hsv, largest_region
from robot.images import CameraIntrinsics

K = CameraIntrinsics(width=640, height=480, fx=1000.0, fy=1010.0, cx=319.5, cy=239.5)


def rot_z(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_back_projection_inverts_projection():
    rng = np.random.default_rng(0)
    points = np.column_stack([rng.uniform(-0.3, 0.3, 50), rng.uniform(-0.2, 0.2, 50), rng.uniform(0.5, 3.0, 50)])
    uv = project(points, K)
    np.testing.assert_allclose(back_project(uv[:, 0], uv[:, 1], points[:, 2], K), points, atol=1e-12)


def test_the_principal_point_back_projects_onto_the_optical_axis():
    np.testing.assert_allclose(back_project([319.5], [239.5], [2.0], K), [[0.0, 0.0, 2.0]])
    # one pixel right and down: x right, y down in the optical frame
    np.testing.assert_allclose(back_project([320.5], [240.5], [2.0], K), [[2.0 / 1000, 2.0 / 1010, 2.0]])


def test_back_projection_refuses_mismatched_lengths():
    with pytest.raises(InvalidImage, match="same length"):
        back_project([1, 2], [1], [1.0, 1.0], K)


def test_transform_applies_rotation_then_translation():
    T = np.eye(4)
    T[:3, :3] = rot_z(math.pi / 2)
    T[:3, 3] = [1.0, 2.0, 3.0]
    np.testing.assert_allclose(transform(T, [[1.0, 0.0, 0.0]]), [[1.0, 3.0, 3.0]], atol=1e-12)
    with pytest.raises(InvalidImage, match="4, 4"):
        transform(np.eye(3), [[0.0, 0.0, 0.0]])


def visible_arc(centre_xy, radius_m, viewer_xy, n: int = 200) -> np.ndarray:
    """Points of a circle that a viewer at viewer_xy sees (the near side)."""
    c, v = np.asarray(centre_xy, dtype=float), np.asarray(viewer_xy, dtype=float)
    to_viewer = math.atan2(v[1] - c[1], v[0] - c[0])
    half = math.acos(radius_m / np.linalg.norm(v - c))  # tangent points
    a = np.linspace(to_viewer - half, to_viewer + half, n)
    return c + radius_m * np.column_stack([np.cos(a), np.sin(a)])


def test_a_known_radius_circle_fit_recovers_the_axis_of_a_cylinder_seen_from_one_side():
    rng = np.random.default_rng(1)
    centre = np.array([2.2, -0.3])
    arc = visible_arc(centre, 0.0325, viewer_xy=(1.3, 0.0)) + rng.normal(0.0, 0.0005, (200, 2))
    # the near-side points' centroid is ~2/pi r in front of the axis: start one radius behind it
    mean = arc.mean(axis=0)
    away = (mean - [1.3, 0.0]) / np.linalg.norm(mean - [1.3, 0.0])
    assert np.linalg.norm(mean - centre) == pytest.approx(0.0325 * 2 / math.pi, rel=0.1)
    fitted, cov, rms = fit_circle_known_radius(arc, 0.0325, mean + 0.0325 * away)
    assert np.linalg.norm(fitted - centre) < 0.0005  # 0.5 mm with 0.5 mm point noise
    assert rms == pytest.approx(0.0005, rel=0.2)
    assert np.all(np.sqrt(np.diag(cov)) < 0.0005)


def test_circle_fit_needs_three_points():
    with pytest.raises(InvalidImage, match="at least 3"):
        fit_circle_known_radius([[0.0, 0.0], [1.0, 0.0]], 0.1, (0.0, 0.1))


def lid_points(centre_xy, yaw_rad, lid=(0.45, 0.30), hole=(0.28, 0.12), step_m: float = 0.004) -> np.ndarray:
    """A grid over a rectangle with a rectangular hole in its middle, rotated by yaw and moved to centre."""
    xs = np.linspace(-lid[0] / 2, lid[0] / 2, round(lid[0] / step_m) + 1)
    ys = np.linspace(-lid[1] / 2, lid[1] / 2, round(lid[1] / step_m) + 1)
    g = np.array([(x, y) for x in xs for y in ys])
    g = g[~((np.abs(g[:, 0]) < hole[0] / 2) & (np.abs(g[:, 1]) < hole[1] / 2))]
    return g @ rot_z(yaw_rad)[:2, :2].T + centre_xy


@pytest.mark.parametrize("yaw_deg", [0.0, 30.0, -60.0, 89.0])
def test_the_smallest_rectangle_around_a_lid_gives_its_centre_yaw_and_sides(yaw_deg):
    centre = np.array([1.4, -2.0])
    fitted, yaw, (long_m, short_m) = min_area_rectangle(lid_points(centre, math.radians(yaw_deg)))
    np.testing.assert_allclose(fitted, centre, atol=1e-6)
    assert math.degrees(yaw) == pytest.approx(yaw_deg, abs=1e-6)
    assert (long_m, short_m) == (pytest.approx(0.45), pytest.approx(0.30))


def test_rectangle_yaw_is_folded_into_minus_90_to_90_degrees():
    _, yaw, _ = min_area_rectangle(lid_points((0.0, 0.0), math.radians(170.0)))
    assert math.degrees(yaw) == pytest.approx(-10.0, abs=1e-6)


def test_collinear_points_have_no_rectangle():
    with pytest.raises(InvalidImage, match="degenerate"):
        min_area_rectangle([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])


def test_hsv_of_pure_colours():
    rgb = np.array([[[255, 0, 0], [0, 255, 0], [0, 0, 255], [128, 128, 128]]], dtype=np.uint8)
    hue, saturation, value = hsv(rgb)
    np.testing.assert_allclose(hue[0], [0.0, 120.0, 240.0, 0.0])
    np.testing.assert_allclose(saturation[0], [1.0, 1.0, 1.0, 0.0])
    np.testing.assert_allclose(value[0], [1.0, 1.0, 1.0, 128 / 255], rtol=1e-6)


def test_the_red_mask_takes_lit_and_shaded_can_red_but_not_the_beige_table_or_the_robot():
    # rendered colours: lit can, shaded can, table top, robot grey, robot blue joint, floor, lid green
    rgb = np.array([[[255, 20, 20], [70, 4, 4], [255, 245, 210], [200, 200, 205], [60, 75, 110], [40, 60, 80],
                     [25, 180, 50]]], dtype=np.uint8)
    np.testing.assert_array_equal(colour_mask(rgb, RED)[0], [True, True, False, False, False, False, False])
    np.testing.assert_array_equal(colour_mask(rgb, GREEN)[0], [False, False, False, False, False, False, True])


def test_colour_mask_refuses_float_images():
    with pytest.raises(InvalidImage, match="uint8"):
        colour_mask(np.zeros((2, 2, 3)), RED)


def test_largest_region_keeps_only_the_biggest_blob():
    mask = np.zeros((10, 10), dtype=bool)
    mask[1:3, 1:3] = True  # 4 pixels
    mask[5:9, 5:9] = True  # 16 pixels
    kept = largest_region(mask)
    assert kept.sum() == 16 and kept[6, 6] and not kept[1, 1]
    assert not largest_region(np.zeros((3, 3), dtype=bool)).any()
