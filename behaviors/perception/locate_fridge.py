"""Locate the fridge door's handle in one camera's colour image and depth map: the handle bar's axis (a vertical
cylinder of known radius, the yellow region) and the door's turn (the blue door face's direction in x-y)."""

# As in behaviors.perception.locate: the inputs are the robot's own (image, depth, intrinsics, its estimate of the
# camera pose); the model of the fridge is the robot's copy (FridgeModel), nothing here reads the simulator.

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from behaviors.perception.locate import SIGMA_FLOOR_M, Recognition, _bbox, _check, _region_points
from behaviors.perception.segmentation import ColourRange
from robot.images import CameraIntrinsics

#: The handle is yellow, the door blue (robot/scene_fridge.py's colours).
YELLOW = ColourRange(hue_deg=50.0, hue_tolerance_deg=15.0)
BLUE = ColourRange(hue_deg=220.0, hue_tolerance_deg=20.0)
#: [m] points this close below the bar's highest are on its top disc
TOP_DISC_BAND_M = 0.004


@dataclass(frozen=True, slots=True)
class FridgeModel:
    """The fridge the robot knows: where the handle is on the door relative to the hinge, and its size."""

    handle_radius_m: float = 0.02
    handle_length_m: float = 0.30  # the bar's visible length (its top is what the image shows best)
    handle_from_hinge_m: float = 0.22  # along the door, from the hinge's axis to the bar's axis
    handle_off_door_m: float = 0.075  # the bar's axis in front of the door's inner face (door 0.03 + 0.045)


FRIDGE = FridgeModel()


def door_yaw_rad(points_xy, camera_xy, columns_px=None) -> float:
    """The yaw [rad] of the door's normal pointing away from the camera (into the fridge), from the door face's
    points (N, 2): the line through them in x-y is along the door. The depth's noise lies along the lines of
    sight, so with `columns_px` (N,) (each point's image column) the line is fitted to each column's median
    point instead of the points themselves."""
    p = np.asarray(points_xy, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3:
        raise ValueError(f"need at least 3 door points (N, 2), got shape {p.shape}")
    if columns_px is not None:
        cols = np.asarray(columns_px)
        p = np.array([np.median(p[cols == u], axis=0) for u in np.unique(cols)])
        if len(p) < 3:
            raise ValueError(f"need door points in at least 3 image columns, got {len(p)}")
    centred = p - p.mean(axis=0)
    _, _, vt = np.linalg.svd(centred, full_matrices=False)
    along = vt[0]
    normal = np.array([along[1], -along[0]])
    if normal @ (p.mean(axis=0) - np.asarray(camera_xy, dtype=float)) < 0:
        normal = -normal
    return math.atan2(normal[1], normal[0])


def hinge_from_handle_xy(handle_xy, yaw_rad: float, model: FridgeModel = FRIDGE) -> np.ndarray:
    """(2,) the hinge's axis in x-y [m] from the handle's axis and the door normal's yaw (the hinge is on the
    door's right as seen from the front: along -y of the door's frame)."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    # the handle in the door's frame (x along the normal, into the fridge; y along the door from the hinge)
    local = np.array([-model.handle_off_door_m, model.handle_from_hinge_m])
    return np.asarray(handle_xy, dtype=float) - np.array([c * local[0] - s * local[1], s * local[0] + c * local[1]])


def locate_fridge_handle(rgb, depth_m, intrinsics: CameraIntrinsics, T_world_camera, time_s: float = 0.0,
                         model: FridgeModel = FRIDGE, min_pixels: int = 30) -> Recognition | None:
    """The handle: the largest yellow region fitted as a vertical cylinder of the model's radius (position: the
    top of its axis: the head, looking down on it from the standing robot, sees the top best and the bottom
    not at all); yaw: the door's normal from the largest blue region. None if either has fewer than `min_pixels`
    pixels."""
    rgb, depth = _check(rgb, depth_m, intrinsics, T_world_camera)
    region, points, _ = _region_points(rgb, depth, intrinsics, T_world_camera, YELLOW)
    door_region, door, _ = _region_points(rgb, depth, intrinsics, T_world_camera, BLUE)
    if len(points) < min_pixels or len(door) < min_pixels:
        return None
    camera_xy = np.asarray(T_world_camera, dtype=float)[:2, 3]
    top = float(np.percentile(points[:, 2], 99))
    # the bar's top disc (seen from above, whole): its centroid is on the axis; the side below it mixes with the
    # posts that hold the bar off the door
    disc = points[points[:, 2] > top - TOP_DISC_BAND_M]
    if len(disc) < 10:
        return None
    centre_xy = disc[:, :2].mean(axis=0)
    cov_xy = np.cov(disc[:, :2].T) / len(disc)
    cov = np.zeros((3, 3))
    cov[:2, :2] = cov_xy
    cov += SIGMA_FLOOR_M ** 2 * np.eye(3)
    position = np.array([centre_xy[0], centre_xy[1], top])
    # the door's face beside the handle's height (not its top face), by image column
    _, door_u = np.nonzero(door_region)
    face = np.abs(door[:, 2] - (top - model.handle_length_m / 2)) < model.handle_length_m / 2
    if np.count_nonzero(face) < min_pixels:
        return None
    yaw = door_yaw_rad(door[face, :2], camera_xy, door_u[face])
    return Recognition("fridge_handle", position, yaw, cov, _bbox(region), len(points), float(time_s))
