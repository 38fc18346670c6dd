"""Locate the can and the trash box's hole in one camera's colour image and depth map, in the world frame."""

# The inputs are the robot's own: an RGB image, the depth map registered to it (the narrow stereo pair's, along
# the optical axis [m]), the camera intrinsics and the robot's estimate of the camera pose T_world_camera
# (optical frame: x right, y down, z forward). Nothing here reads the simulator: errors in T_world_camera pass
# straight into the result, and the covariance covers only what the images can tell.

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from behaviors.perception.errors import InvalidImage
from behaviors.perception.geometry import back_project, fit_circle_known_radius, min_area_rectangle, transform
from behaviors.perception.models import CAN, TRASH_BOX, CanModel, TrashBoxModel
from behaviors.perception.segmentation import GREEN, RED, ColourRange, colour_mask, largest_region
from robot.images import CameraIntrinsics

#: Floor of the reported standard deviation per axis [m] (pixel quantisation and what the fits ignore).
SIGMA_FLOOR_M = 0.002
#: Points this far below the can's top surface are on its side [m] (the top disc is excluded from the fit).
CAN_TOP_BAND_M = 0.010
#: A lid's top-face points lie within this of the fitted top height [m] (the lid plates are 0.01 m thick).
LID_TOP_BAND_M = 0.010
#: Side lengths of the lid further than this from the model mean it is cut off or occluded [m].
LID_SIZE_TOLERANCE_M = 0.03
#: More than this share of lid pixels inside the model's hole means the green region is no lid with a hole.
HOLE_MAX_SHARE = 0.05


@dataclass(frozen=True, slots=True)
class Recognition:
    """An object located in one image: where it is in the world and how sure, and where it was in the image."""

    object_name: str
    position_world_m: np.ndarray  # (3,) can: centre of the cylinder; trash box: centre of the hole, lid top
    yaw_rad: float  # trash box: the hole's long side, (-pi/2, pi/2]; can: 0 (symmetric)
    covariance_m2: np.ndarray  # (3, 3) world frame, from the image evidence (not the camera pose's error)
    bbox_px: tuple[int, int, int, int]  # (u_min, v_min, u_max, v_max), inclusive
    n_pixels: int  # pixels of the object's colour region used
    time_s: float  # time of the image [s]

    def __post_init__(self) -> None:
        for name in ("position_world_m", "covariance_m2"):
            a = np.array(getattr(self, name), dtype=float)
            a.flags.writeable = False
            object.__setattr__(self, name, a)


def _check(rgb, depth_m, intrinsics: CameraIntrinsics, T_world_camera) -> tuple[np.ndarray, np.ndarray]:
    rgb, depth = np.asarray(rgb), np.asarray(depth_m, dtype=float)
    shape = (intrinsics.height, intrinsics.width)
    if rgb.shape[:2] != shape or depth.shape != shape:
        raise InvalidImage(f"rgb {rgb.shape[:2]} and depth {depth.shape} must both be {shape} (the intrinsics')")
    T = np.asarray(T_world_camera, dtype=float)
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise InvalidImage(f"T_world_camera must be a finite (4, 4) pose, got shape {T.shape}")
    return rgb, depth


def _region_points(rgb, depth, intrinsics, T_world_camera, colour: ColourRange):
    """The largest region of a colour with valid depth: (mask, world points (N, 3), depths (N,))."""
    valid = np.isfinite(depth) & (depth > 0)
    region = largest_region(colour_mask(rgb, colour) & valid)
    v, u = np.nonzero(region)
    z = depth[v, u]
    return region, transform(T_world_camera, back_project(u, v, z, intrinsics)), z


def _bbox(region) -> tuple[int, int, int, int]:
    v, u = np.nonzero(region)
    return int(u.min()), int(v.min()), int(u.max()), int(v.max())


def _top_height_m(z, band_m: float) -> tuple[float, np.ndarray]:
    """Height of the highest horizontal surface among points of heights z (robust to a few outliers above),
    and which points lie on it."""
    z_high = float(np.percentile(z, 98))
    candidates = z[z > z_high - band_m]
    top = float(np.median(candidates))
    return top, np.abs(z - top) < band_m


def locate_can(rgb, depth_m, intrinsics: CameraIntrinsics, T_world_camera, time_s: float = 0.0,
               model: CanModel = CAN, colour: ColourRange = RED, min_pixels: int = 30) -> Recognition | None:
    """The can: the largest red region, back-projected, fitted as a vertical cylinder of the model's radius.

    The visible side is an arc of the near half; a circle of the known radius fitted to its points in x-y
    (started one radius beyond their centroid, away from the camera) gives the axis, the top surface gives
    the height: position = (axis x, axis y, top - height / 2). None if fewer than `min_pixels` red pixels.
    """
    rgb, depth = _check(rgb, depth_m, intrinsics, T_world_camera)
    region, points, _ = _region_points(rgb, depth, intrinsics, T_world_camera, colour)
    n = len(points)
    if n < min_pixels:
        return None
    z_top, on_top = _top_height_m(points[:, 2], CAN_TOP_BAND_M / 2)
    side = points[points[:, 2] < z_top - CAN_TOP_BAND_M]
    camera_xy = np.asarray(T_world_camera, dtype=float)[:2, 3]
    if len(side) >= 10:
        mean_xy = side[:, :2].mean(axis=0)
        away = mean_xy - camera_xy
        away /= max(np.linalg.norm(away), 1e-9)
        centre_xy, cov_xy, _ = fit_circle_known_radius(side[:, :2], model.radius_m, mean_xy + model.radius_m * away)
    else:  # seen from above: the top disc's centroid
        top_xy = points[on_top, :2]
        centre_xy = top_xy.mean(axis=0)
        cov_xy = np.cov(top_xy.T) / max(len(top_xy), 1)
    top_z = points[on_top, 2]
    var_z = float(np.var(top_z)) / max(len(top_z), 1)
    cov = np.zeros((3, 3))
    cov[:2, :2] = cov_xy
    cov[2, 2] = var_z
    cov += SIGMA_FLOOR_M ** 2 * np.eye(3)
    position = np.array([centre_xy[0], centre_xy[1], z_top - model.height_m / 2])
    return Recognition("can", position, 0.0, cov, _bbox(region), n, float(time_s))


def locate_trash_box(rgb, depth_m, intrinsics: CameraIntrinsics, T_world_camera, time_s: float = 0.0,
                     model: TrashBoxModel = TRASH_BOX, colour: ColourRange = GREEN, min_pixels: int = 50
                     ) -> Recognition | None:
    """The trash box's hole: the largest green region (the lid around the hole), its top face's points in
    x-y, their smallest enclosing rectangle; the hole is centred in the lid, its long side along the lid's.

    position = (rectangle centre, lid top height), yaw = the long side's. None if fewer than `min_pixels` green
    pixels, or if the region has points where the model's hole is (not a lid with a hole). A lid whose measured
    sides differ from the model's by more than LID_SIZE_TOLERANCE_M (cut off by the image border, occluded)
    is still returned, with that difference in its covariance.
    """
    rgb, depth = _check(rgb, depth_m, intrinsics, T_world_camera)
    region, points, ranges = _region_points(rgb, depth, intrinsics, T_world_camera, colour)
    n = len(points)
    if n < min_pixels:
        return None
    z_top, on_top = _top_height_m(points[:, 2], LID_TOP_BAND_M)
    top_xy = points[on_top, :2]
    if len(top_xy) < 3:
        return None
    centre_xy, yaw, (long_m, short_m) = min_area_rectangle(top_xy)
    c, s = math.cos(yaw), math.sin(yaw)
    R_world_lid = np.array([[c, -s], [s, c]])
    in_lid = (top_xy - centre_xy) @ R_world_lid  # (long, short) coordinates
    hole_half = np.array(model.hole_m) / 2 - 0.01
    inside_hole = np.all(np.abs(in_lid) < hole_half, axis=1)
    if inside_hole.mean() > HOLE_MAX_SHARE:
        return None
    # Pixel footprint on the lid along the view: range / fx stretched by 1 / sin(depression).
    T = np.asarray(T_world_camera, dtype=float)
    ray = np.array([centre_xy[0], centre_xy[1], z_top]) - T[:3, 3]
    sin_depression = max(abs(ray[2]) / max(np.linalg.norm(ray), 1e-9), 0.1)
    footprint_m = float(np.median(ranges)) / intrinsics.fx / sin_depression
    sigma = max(SIGMA_FLOOR_M, footprint_m / 2)
    mismatch = np.array([long_m - model.lid_m[0], short_m - model.lid_m[1]])
    extra = np.where(np.abs(mismatch) > LID_SIZE_TOLERANCE_M, mismatch / 2, 0.0)
    cov_lid = np.diag(sigma ** 2 + extra ** 2)
    cov = np.zeros((3, 3))
    cov[:2, :2] = R_world_lid @ cov_lid @ R_world_lid.T
    cov[2, 2] = max(SIGMA_FLOOR_M, float(np.std(points[on_top, 2]))) ** 2
    position = np.array([centre_xy[0], centre_xy[1], z_top])
    return Recognition("trash_box", position, float(yaw), cov, _bbox(region), n, float(time_s))
