"""locate_can and locate_trash_box on synthetic images (the rendered scene: tests/scenarios/test_perception_expo.py)."""

from __future__ import annotations

import numpy as np
import pytest

import robot.generate as gen
from behaviors.perception import CAN, TRASH_BOX, InvalidImage, locate_can, locate_trash_box
from robot.images import CameraIntrinsics


def test_the_robots_object_models_match_the_scene():
    assert CAN.diameter_m == gen.CAN_DIAMETER_M and CAN.height_m == gen.CAN_HEIGHT_M
    assert TRASH_BOX.hole_m == gen.TRASH_BOX_HOLE_M
    assert TRASH_BOX.lid_m == gen.TRASH_BOX_OUTER_M[:2] and TRASH_BOX.lid_height_m == gen.TRASH_BOX_OUTER_M[2]


def overhead_view(lid_colour, hole_colour=None) -> tuple[np.ndarray, np.ndarray, CameraIntrinsics, np.ndarray]:
    """A synthetic image: a camera 0.8 m straight above a 0.45 x 0.30 m lid (0.60 m up) centred below it."""
    k = CameraIntrinsics(width=320, height=240, fx=300.0, fy=300.0, cx=159.5, cy=119.5)
    T = np.eye(4)
    T[:3, :3] = np.diag([1.0, -1.0, -1.0])  # optical z down, x along world x
    T[:3, 3] = [1.0, 2.0, 1.4]
    depth = np.full((k.height, k.width), 1.4, dtype=np.float32)  # the floor
    rgb = np.full((k.height, k.width, 3), 40, dtype=np.uint8)
    u, v = np.meshgrid(np.arange(k.width), np.arange(k.height))
    x, y = (u - k.cx) * 0.8 / k.fx, -(v - k.cy) * 0.8 / k.fy  # world offsets on the lid plane
    lid = (np.abs(x) <= 0.225) & (np.abs(y) <= 0.15)
    rgb[lid], depth[lid] = lid_colour, 0.8
    if hole_colour is not None:
        hole = (np.abs(x) < 0.14) & (np.abs(y) < 0.06)
        rgb[hole], depth[hole] = hole_colour, 1.35
    return rgb, depth, k, T


def test_a_green_lid_with_a_hole_is_found_in_a_synthetic_overhead_image():
    rgb, depth, k, T = overhead_view((25, 180, 50), hole_colour=(10, 10, 10))
    r = locate_trash_box(rgb, depth, k, T)
    np.testing.assert_allclose(r.position_world_m, [1.0, 2.0, 0.6], atol=0.003)
    assert abs(r.yaw_rad) < 1e-6


def test_a_green_slab_without_a_hole_is_no_trash_box():
    rgb, depth, k, T = overhead_view((25, 180, 50))
    assert locate_trash_box(rgb, depth, k, T) is None


def test_images_and_intrinsics_of_different_sizes_are_refused():
    rgb, depth, k, T = overhead_view((25, 180, 50), hole_colour=(10, 10, 10))
    with pytest.raises(InvalidImage, match="must both be"):
        locate_can(rgb[:100], depth, k, T)
    with pytest.raises(InvalidImage, match="T_world_camera"):
        locate_trash_box(rgb, depth, k, T[:3])
