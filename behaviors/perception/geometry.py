"""Geometry pieces of perception: pixel back-projection, rigid transforms, known-radius circle, bounding rectangle."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from behaviors.perception.errors import InvalidImage
from robot.images import CameraIntrinsics


def back_project(u, v, depth_m, intrinsics: CameraIntrinsics) -> np.ndarray:
    """Points (N, 3) in the camera's optical frame (x right, y down, z forward) [m] of pixels (u, v) [px]
    (column, row; centres at integers) with depth along the optical axis `depth_m` [m]."""
    u, v, z = (np.asarray(a, dtype=float).ravel() for a in (u, v, depth_m))
    if not (u.shape == v.shape == z.shape):
        raise InvalidImage(f"u, v and depth must have the same length, got {u.shape}, {v.shape}, {z.shape}")
    k = intrinsics
    return np.column_stack([(u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z])


def project(points_camera, intrinsics: CameraIntrinsics) -> np.ndarray:
    """Pixels (N, 2) (u, v) of points (N, 3) in the optical frame (z > 0) [m]."""
    p = np.atleast_2d(np.asarray(points_camera, dtype=float))
    k = intrinsics
    return np.column_stack([k.fx * p[:, 0] / p[:, 2] + k.cx, k.fy * p[:, 1] / p[:, 2] + k.cy])


def transform(T_a_b, points_b) -> np.ndarray:
    """Points (N, 3) in frame a from points in frame b, T_a_b (4, 4)."""
    T = np.asarray(T_a_b, dtype=float)
    if T.shape != (4, 4):
        raise InvalidImage(f"a pose must be a (4, 4) homogeneous matrix, got shape {T.shape}")
    p = np.atleast_2d(np.asarray(points_b, dtype=float))
    return p @ T[:3, :3].T + T[:3, 3]


def fit_circle_known_radius(points_xy, radius_m: float, centre_guess_xy, iterations: int = 20
                            ) -> tuple[np.ndarray, np.ndarray, float]:
    """Centre (2,) of the circle of radius `radius_m` nearest to the points (N, 2) in least squares (Gauss-
    Newton on |p - c| - r from `centre_guess_xy`), its covariance (2, 2) [m^2] from the residuals, and the
    RMS residual [m]. Start on the far side of the points from the viewer: an arc fits two mirrored circles."""
    p = np.asarray(points_xy, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3:
        raise InvalidImage(f"need at least 3 points (N, 2) for a circle fit, got shape {p.shape}")
    c = np.array(centre_guess_xy, dtype=float)
    for _ in range(iterations):
        d = p - c
        dist = np.maximum(np.linalg.norm(d, axis=1), 1e-12)
        residual = dist - radius_m
        J = -d / dist[:, None]  # d residual / d c
        step = np.linalg.lstsq(J, -residual, rcond=None)[0]
        c += step
        if np.linalg.norm(step) < 1e-9:
            break
    d = p - c
    dist = np.maximum(np.linalg.norm(d, axis=1), 1e-12)
    residual = dist - radius_m
    J = -d / dist[:, None]
    dof = max(len(p) - 2, 1)
    sigma2 = float(residual @ residual) / dof
    cov = sigma2 * np.linalg.pinv(J.T @ J)
    return c, cov, math.sqrt(float(np.mean(residual ** 2)))


def min_area_rectangle(points_xy) -> tuple[np.ndarray, float, tuple[float, float]]:
    """The smallest rectangle around points (N, 2): centre (2,) [m], yaw of its long side in (-pi/2, pi/2]
    [rad], (long, short) side lengths [m]. One of its sides lies along an edge of the points' convex hull."""
    p = np.asarray(points_xy, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 3:
        raise InvalidImage(f"need at least 3 points (N, 2) for a rectangle, got shape {p.shape}")
    try:
        hull = p[ConvexHull(p).vertices]
    except QhullError as err:
        raise InvalidImage(f"points are degenerate (collinear or repeated): {err}") from None
    edges = np.diff(np.vstack([hull, hull[:1]]), axis=0)
    angles = np.unique(np.mod(np.arctan2(edges[:, 1], edges[:, 0]), math.pi / 2))
    best = None
    for a in angles:
        c, s = math.cos(a), math.sin(a)
        R = np.array([[c, s], [-s, c]])  # world -> rectangle axes
        q = hull @ R.T
        lo, hi = q.min(axis=0), q.max(axis=0)
        area = float(np.prod(hi - lo))
        if best is None or area < best[0]:
            best = (area, a, lo, hi, R)
    _, a, lo, hi, R = best
    centre = R.T @ ((lo + hi) / 2)
    size = hi - lo
    yaw = a if size[0] >= size[1] else a + math.pi / 2
    yaw = math.atan2(math.sin(yaw), math.cos(yaw))  # (-pi, pi]
    if yaw <= -math.pi / 2:
        yaw += math.pi
    elif yaw > math.pi / 2:
        yaw -= math.pi
    return centre, yaw, (float(size.max()), float(size.min()))
