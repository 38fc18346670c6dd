"""Capture point of the linear inverted pendulum and the convex-polygon geometry of the support region."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from controller.core.constants import GRAVITY_M_S2
from controller.core.errors import InvalidCommand
from controller.core.layer import Params

_EPS = 1e-12  # [m] geometric tolerance


# ---------------------------------------------------------------------------- capture point (LIP)


def omega(com_height_m: float, g: float = GRAVITY_M_S2) -> float:
    """Natural frequency sqrt(g / z_c) of the linear inverted pendulum [1/s]."""
    if com_height_m <= 0.0:
        raise InvalidCommand(f"com_height_m={com_height_m}; use a positive COG height [m]")
    return float(np.sqrt(g / com_height_m))


def capture_point(com_world_xy, com_vel_world_xy, omega_1_s: float) -> np.ndarray:
    """xi = x + xdot / omega [m], (2,) or (..., 2)."""
    return np.asarray(com_world_xy, dtype=float) + np.asarray(com_vel_world_xy, dtype=float) / omega_1_s


def capture_point_error(ref_cp_world_xy, act_cp_world_xy) -> tuple[np.ndarray, float]:
    """(ref_cp - act_cp [m], its norm [m]), the sign hrpsys uses for diffCapturePoint."""
    err = np.asarray(ref_cp_world_xy, dtype=float) - np.asarray(act_cp_world_xy, dtype=float)
    return err, float(np.linalg.norm(err))


# ---------------------------------------------------------------------------- convex polygons
# Polygons are (M, 2) arrays of vertices [m], convex, counter-clockwise, first vertex not repeated.


def _cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def convex_hull_2d(points) -> np.ndarray:
    """Convex hull (M, 2), counter-clockwise from the lowest-x vertex, collinear points dropped.

    Andrew's monotone chain; fewer than three distinct points are returned as they are (sorted).
    """
    pts = np.unique(np.asarray(points, dtype=float).reshape(-1, 2), axis=0)  # sorted by x, then y
    if len(pts) < 3:
        return pts

    def half(seq):
        chain: list[np.ndarray] = []
        for p in seq:
            while len(chain) >= 2 and _cross(chain[-2], chain[-1], p) <= _EPS:
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def _as_ccw(vertices) -> np.ndarray:
    v = np.asarray(vertices, dtype=float).reshape(-1, 2)
    if len(v) < 3:
        raise InvalidCommand(f"polygon with {len(v)} vertices; give at least 3 (M, 2) vertices")
    pts = v.tolist()
    area2 = sum(ax * by - bx * ay for (ax, ay), (bx, by) in zip(pts, pts[1:] + pts[:1], strict=True))  # [m^2]
    return v[::-1] if area2 < 0.0 else v


def _edges(v: np.ndarray):
    """Start points (M, 2), edge vectors (M, 2) and inward unit normals (M, 2) of a CCW polygon."""
    d = np.roll(v, -1, axis=0) - v
    length = np.linalg.norm(d, axis=1, keepdims=True)
    inward = np.stack([-d[:, 1], d[:, 0]], axis=1) / np.maximum(length, _EPS)
    return v, d, inward


def shrink_polygon(vertices, margin_m: float) -> np.ndarray:
    """The convex polygon offset inward by `margin_m` [m] (every edge moved in); (0, 2) if nothing is left.

    Computed as the original polygon clipped by each edge's shifted half-plane, so a margin larger
    than the inradius degrades gracefully to an empty polygon.
    """
    v = _as_ccw(vertices)
    if margin_m < 0.0:
        raise InvalidCommand(f"margin_m={margin_m}; use a margin >= 0 [m] (this shrinks, never grows)")
    starts, _, normals = _edges(v)
    poly = v
    for a, n in zip(starts, normals, strict=True):
        if len(poly) == 0:
            break
        s = (poly - a) @ n - margin_m  # >= 0 inside the shifted half-plane
        out = []
        for i in range(len(poly)):
            j = (i + 1) % len(poly)
            if s[i] >= 0.0:
                out.append(poly[i])
            if (s[i] >= 0.0) != (s[j] >= 0.0):
                t = s[i] / (s[i] - s[j])
                out.append(poly[i] + t * (poly[j] - poly[i]))
        poly = np.array(out).reshape(-1, 2)
    hull = convex_hull_2d(poly) if len(poly) else poly
    return hull if len(hull) >= 3 else np.zeros((0, 2))


def distance_to_polygon_edge(p_xy, vertices) -> float:
    """Signed distance [m] from the point to the polygon boundary: positive inside, negative outside.

    Scalar maths over the few vertices of a support polygon (it runs every tick)."""
    v = _as_ccw(vertices).tolist()
    px, py = np.asarray(p_xy, dtype=float).reshape(2).tolist()
    inside_m = math.inf  # smallest distance to an edge's line, inward positive
    boundary_m = math.inf  # distance to the nearest boundary point
    for (ax, ay), (bx, by) in zip(v, v[1:] + v[:1], strict=True):
        dx, dy = bx - ax, by - ay
        length2 = dx * dx + dy * dy
        length = math.sqrt(length2)
        inside_m = min(inside_m, (dx * (py - ay) - dy * (px - ax)) / max(length, _EPS))
        t = min(1.0, max(0.0, ((px - ax) * dx + (py - ay) * dy) / max(length2, _EPS)))
        boundary_m = min(boundary_m, math.hypot(px - (ax + t * dx), py - (ay + t * dy)))
    return inside_m if inside_m >= 0.0 else -boundary_m


def point_in_convex_polygon(p_xy, vertices, tol_m: float = 1e-12) -> bool:
    """True if the point is inside or on the boundary (within `tol_m` [m])."""
    return distance_to_polygon_edge(p_xy, vertices) >= -tol_m


def _nearest_on_boundary(p: np.ndarray, v: np.ndarray) -> np.ndarray:
    starts, d, _ = _edges(v)
    t = np.einsum("ij,ij->i", p - starts, d) / np.maximum(np.einsum("ij,ij->i", d, d), _EPS)
    candidates = starts + np.clip(t, 0.0, 1.0)[:, None] * d  # (M, 2)
    return candidates[np.argmin(np.linalg.norm(candidates - p, axis=1))]


def nearest_point_in_convex_polygon(p_xy, vertices) -> np.ndarray:
    """The point itself if inside, otherwise its projection on the nearest edge [m], (2,)."""
    v = _as_ccw(vertices)
    p = np.asarray(p_xy, dtype=float).reshape(2)
    if point_in_convex_polygon(p, v):
        return p.copy()
    return _nearest_on_boundary(p, v)



# ---------------------------------------------------------------------------- the same on plain floats
# The emergency step re-plans every tick: numpy's per-call overhead on these few vertices costs more than the
# maths. These take and give lists of (x, y) tuples and give the same floats as their numpy twins above (the
# one dot product numpy does with BLAS, which fuses multiply-adds, stays numpy's).


def convex_hull_xy(points) -> list[tuple[float, float]]:
    """convex_hull_2d on (x, y) pairs [m]: counter-clockwise from the lowest-x vertex, collinear points dropped."""
    pts = sorted(set((float(x), float(y)) for x, y in points))  # np.unique's order: by x, then y

    def half(seq):
        chain: list[tuple[float, float]] = []
        for bx, by in seq:
            while len(chain) >= 2:
                (ox, oy), (ax, ay) = chain[-2], chain[-1]
                if (ax - ox) * (by - oy) - (ay - oy) * (bx - ox) > _EPS:
                    break
                chain.pop()
            chain.append((bx, by))
        return chain

    if len(pts) < 3:
        return pts
    lower, upper = half(pts), half(pts[::-1])
    return lower[:-1] + upper[:-1]


def _ccw_xy(vertices) -> list[tuple[float, float]]:
    v = [(float(x), float(y)) for x, y in vertices]
    if len(v) < 3:
        raise InvalidCommand(f"polygon with {len(v)} vertices; give at least 3 (M, 2) vertices")
    area2 = sum(ax * by - bx * ay for (ax, ay), (bx, by) in zip(v, v[1:] + v[:1], strict=True))  # [m^2]
    return v[::-1] if area2 < 0.0 else v


def _edges_xy(v: list[tuple[float, float]]) -> list[tuple[float, float, float, float, float, float]]:
    """(ax, ay, dx, dy, nx, ny) per edge of a CCW polygon: start, edge vector, inward unit normal (_edges)."""
    out = []
    for (ax, ay), (bx, by) in zip(v, v[1:] + v[:1], strict=True):
        dx, dy = bx - ax, by - ay
        length = max(math.sqrt(dx * dx + dy * dy), _EPS)
        out.append((ax, ay, dx, dy, -dy / length, dx / length))
    return out


def shrink_polygon_xy(vertices, margin_m: float) -> list[tuple[float, float]]:
    """shrink_polygon on (x, y) pairs [m]: the convex polygon offset inward by margin_m; [] if nothing is left."""
    if margin_m < 0.0:
        raise InvalidCommand(f"margin_m={margin_m}; use a margin >= 0 [m] (this shrinks, never grows)")
    v = _ccw_xy(vertices)
    poly = v
    for ax, ay, _, _, nx, ny in _edges_xy(v):
        if not poly:
            break
        # (poly - a) @ n as numpy computes it (BLAS): the same floats as shrink_polygon
        s = ((np.array(poly) - (ax, ay)) @ np.array((nx, ny)) - margin_m).tolist()
        out = []
        m = len(poly)
        for i in range(m):
            j = (i + 1) % m
            if s[i] >= 0.0:
                out.append(poly[i])
            if (s[i] >= 0.0) != (s[j] >= 0.0):
                t = s[i] / (s[i] - s[j])
                (px, py), (qx, qy) = poly[i], poly[j]
                out.append((px + t * (qx - px), py + t * (qy - py)))
        poly = out
    hull = convex_hull_xy(poly) if poly else poly
    return hull if len(hull) >= 3 else []


def slack_in_shrunk_polygon_m(x_m: float, y_m: float, vertices, margin_m: float) -> float:
    """How far [m] the point lies inside the convex polygon shrunk by margin_m (shrink_polygon is the polygon cut
    by each edge moved in by it): its least distance to those moved edges' lines, negative outside. Plain floats:
    a point inside by far more than their rounding is inside the shrunk polygon, whatever its vertices' last bits."""
    return min((x_m - ax) * nx + (y_m - ay) * ny for ax, ay, _, _, nx, ny in _edges_xy(_ccw_xy(vertices))) - margin_m


def nearest_point_in_convex_polygon_xy(x_m: float, y_m: float, vertices) -> tuple[float, float]:
    """nearest_point_in_convex_polygon on floats: the point itself if inside, else its projection on the nearest
    edge [m]."""
    edges = _edges_xy(_ccw_xy(vertices))
    # point_in_convex_polygon (distance_to_polygon_edge >= -1e-12), its floats
    inside_m, boundary_m = math.inf, math.inf
    for ax, ay, dx, dy, _, _ in edges:
        length2 = dx * dx + dy * dy
        inside_m = min(inside_m, (dx * (y_m - ay) - dy * (x_m - ax)) / max(math.sqrt(length2), _EPS))
        t = min(1.0, max(0.0, ((x_m - ax) * dx + (y_m - ay) * dy) / max(length2, _EPS)))
        boundary_m = min(boundary_m, math.hypot(x_m - (ax + t * dx), y_m - (ay + t * dy)))
    if (inside_m if inside_m >= 0.0 else -boundary_m) >= -1e-12:
        return (x_m, y_m)
    best, best_d = (x_m, y_m), math.inf
    for ax, ay, dx, dy, _, _ in edges:
        t = ((x_m - ax) * dx + (y_m - ay) * dy) / max(dx * dx + dy * dy, _EPS)
        t = min(max(t, 0.0), 1.0)
        cx, cy = ax + t * dx, ay + t * dy
        ex, ey = cx - x_m, cy - y_m
        d = math.sqrt(ex * ex + ey * ey)
        if d < best_d:  # the first of equals, as argmin
            best, best_d = (cx, cy), d
    return best


# ---------------------------------------------------------------------------- feet and support polygon


@dataclass(frozen=True)
class FootRectangle(Params):
    """Sole rectangle in the ankle frame: extents from the ankle along +x, -x, +y, -y [m]."""

    front_m: float = field(default=0.1356, metadata={"unit": "m", "min": 0.0, "max": 1.0})
    rear_m: float = field(default=0.1056, metadata={"unit": "m", "min": 0.0, "max": 1.0})
    left_m: float = field(default=0.059, metadata={"unit": "m", "min": 0.0, "max": 1.0})
    right_m: float = field(default=0.079, metadata={"unit": "m", "min": 0.0, "max": 1.0})

    def corners_foot(self) -> np.ndarray:
        """(4, 2) counter-clockwise corners in the ankle frame [m]."""
        return np.array(
            [
                [-self.rear_m, -self.right_m],
                [self.front_m, -self.right_m],
                [self.front_m, self.left_m],
                [-self.rear_m, self.left_m],
            ]
        )

    def corners_world(self, foot_pose_world) -> np.ndarray:
        """(4, 2) corners [m] for an ankle pose (x [m], y [m], yaw [rad]) in the world."""
        x, y, yaw = (float(c) for c in foot_pose_world)
        c, s = np.cos(yaw), np.sin(yaw)
        R = np.array([[c, -s], [s, c]])
        return self.corners_foot() @ R.T + np.array([x, y])


# HRP-2 soles in the sole frame (directly below the ankle):
# the model's sole box (robot/robot_model.py): 0.2172 x 0.138 m centred at (0.015, -+0.01) m from the
# ankle's vertical, so the right sole spans x -0.0936..0.1236, y -0.079..0.059 (outside is -y);
# the left sole is mirrored.
HRP2_RIGHT_SOLE = FootRectangle(front_m=0.1236, rear_m=0.0936, left_m=0.059, right_m=0.079)
HRP2_LEFT_SOLE = FootRectangle(front_m=0.1236, rear_m=0.0936, left_m=0.079, right_m=0.059)


def support_polygon(feet: Iterable[tuple[object, FootRectangle]]) -> np.ndarray:
    """Convex hull (M, 2) [m] of the soles in contact, given as (ankle pose (x, y, yaw), FootRectangle)."""
    corners = [rect.corners_world(pose) for pose, rect in feet]
    if not corners:
        raise InvalidCommand("support_polygon of no feet; give at least one (pose, FootRectangle)")
    return convex_hull_2d(np.concatenate(corners))
