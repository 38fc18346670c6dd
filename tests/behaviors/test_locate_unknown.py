"""The unknown trash located by segmentation alone (behaviors/perception/locate_unknown.py): the near-side
correction of the visible points, and the whole locator on a rendered head-camera image of the trash scene."""

from __future__ import annotations

import math

import numpy as np
import pytest

from behaviors.perception.locate_unknown import locate_unknown, visible_centre_xy
from robot.images import CameraIntrinsics


def _visible_arc(centre, radius, camera, n=201):
    """Points on the half of a circle facing the camera, spaced evenly across the view (as pixels are)."""
    toward = np.asarray(camera, dtype=float) - centre
    a0 = math.atan2(toward[1], toward[0])
    a = a0 + np.arcsin(np.linspace(-1.0, 1.0, n))
    return np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)])


@pytest.mark.parametrize("camera", [(0.0, 0.0), (0.2, 1.5), (3.0, -1.0)])
def test_the_centre_of_a_round_object_comes_from_its_near_side(camera):
    centre = np.array([1.4, 0.1])
    pts = _visible_arc(centre, 0.03, camera)
    got, radius = visible_centre_xy(pts, camera)
    # the points' mean is pi/4 r = 24 mm nearer the camera; corrected, within 1 mm (the radius from 98 % of
    # the extent)
    assert np.linalg.norm(pts.mean(axis=0) - centre) > 0.020
    assert np.linalg.norm(got - centre) < 0.001
    assert radius == pytest.approx(0.03, abs=0.002)


def test_no_trash_colour_in_the_image_locates_nothing():
    intr = CameraIntrinsics(width=64, height=48, fx=60.0, fy=60.0, cx=32.0, cy=24.0)
    rgb = np.full((48, 64, 3), (60, 80, 110), dtype=np.uint8)  # the floor's blue-grey
    assert locate_unknown(rgb, np.ones((48, 64)), intr, np.eye(4)) is None


def test_a_wrong_image_is_refused_naming_it():
    intr = CameraIntrinsics(width=64, height=48, fx=60.0, fy=60.0, cx=32.0, cy=24.0)
    with pytest.raises(ValueError, match="rgb"):
        locate_unknown(np.zeros((10, 10, 3), np.uint8), np.ones((48, 64)), intr, np.eye(4))
