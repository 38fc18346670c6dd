"""Locate an object of unknown shape on the floor from one colour image and its depth map: segmentation only
([OP] VI, the "unknown trash" of Fig. 8): the largest region of its colour, back-projected to the world; no
model of its shape, so its centre and height come from the visible points alone."""

from __future__ import annotations

import math

import numpy as np

from behaviors.perception.geometry import back_project, transform
from behaviors.perception.locate import SIGMA_FLOOR_M, Recognition, _bbox, _check
from behaviors.perception.segmentation import ORANGE, ColourRange, colour_mask, largest_region
from robot.images import CameraIntrinsics

#: The visible surface of a roundish object lies in front of its axis: on a cylinder of radius r seen from the
#: side, the mean visible point is pi/4 r nearer the camera. The centre is put that far behind the points' mean.
NEAR_SIDE_BIAS = math.pi / 4


def visible_centre_xy(points_xy: np.ndarray, camera_xy) -> tuple[np.ndarray, float]:
    """(centre (2,) [m], radius [m]) of a roundish object from its visible points in x-y: their mean moved
    away from the camera by NEAR_SIDE_BIAS times the radius, the radius half their extent across the view."""
    pts = np.asarray(points_xy, dtype=float)
    mean = pts.mean(axis=0)
    away = mean - np.asarray(camera_xy, dtype=float)
    norm = float(np.linalg.norm(away))
    if norm < 1e-9:
        return mean, 0.0
    away /= norm
    across = pts @ np.array([-away[1], away[0]])
    lo, hi = np.percentile(across, [2, 98])
    radius = float(hi - lo) / 2
    return mean + NEAR_SIDE_BIAS * radius * away, radius


def locate_unknown(rgb, depth_m, intrinsics: CameraIntrinsics, T_world_camera, time_s: float = 0.0,
                   colour: ColourRange = ORANGE, min_pixels: int = 30) -> Recognition | None:
    """The unknown object: the largest region of `colour` with valid depth, in the world. position = (centre x,
    centre y (visible_centre_xy), top height z: the 98th percentile of the points' heights); yaw 0 (no model to
    take an orientation from). None if fewer than `min_pixels` pixels."""
    rgb, depth = _check(rgb, depth_m, intrinsics, T_world_camera)
    valid = np.isfinite(depth) & (depth > 0)
    region = largest_region(colour_mask(rgb, colour) & valid)
    v, u = np.nonzero(region)
    if len(u) < min_pixels:
        return None
    points = transform(T_world_camera, back_project(u, v, depth[v, u], intrinsics))
    T = np.asarray(T_world_camera, dtype=float)
    centre_xy, radius = visible_centre_xy(points[:, :2], T[:2, 3])
    top = float(np.percentile(points[:, 2], 98))
    sigma_xy = max(SIGMA_FLOOR_M, radius / 4)  # the near-side correction is the uncertain part
    cov = np.diag([sigma_xy ** 2, sigma_xy ** 2, SIGMA_FLOOR_M ** 2])
    return Recognition("trash", np.array([centre_xy[0], centre_xy[1], top]), 0.0, cov, _bbox(region), len(u),
                       float(time_s))
