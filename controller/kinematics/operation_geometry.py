"""The operation IK's plane geometry: the support polygon with its margin, the COM guard box, 3-vectors on floats."""

from __future__ import annotations

import math

import numpy as np

from controller.balance.capture_point import convex_hull_2d, shrink_polygon

# Vectors as 3-tuples (rotations as 3 row tuples, in controller.kinematics.rotations): on 3x3 data plain floats
# are several times faster than numpy's per-call overhead, and this runs a few times per point per 5 ms tick.


def sub3(a, b):
    return a[0] - b[0], a[1] - b[1], a[2] - b[2]


def dot3(a, b) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def clip3(v, limit: float):
    """The 3-vector v shortened to at most `limit` (same direction)."""
    return clip3_flagged(v, limit)[0]


def clip3_flagged(v, limit: float):
    """(v shortened to at most `limit`, whether it was longer)."""
    x, y, z = v
    n2 = x * x + y * y + z * z
    if n2 <= limit * limit:
        return (x, y, z), False
    k = limit / math.sqrt(n2)
    return (x * k, y * k, z * k), True


def split_pose(T_rows):
    """(position, rotation rows) of a 4x4 pose given as nested lists."""
    r0, r1, r2 = T_rows[0], T_rows[1], T_rows[2]
    return (r0[3], r1[3], r2[3]), ((r0[0], r0[1], r0[2]), (r1[0], r1[1], r1[2]), (r2[0], r2[1], r2[2]))


class SupportPolygon:
    """The support polygon of the soles in contact: placo's clockwise vertex list, the inward edge lines
    (for the margin), and the polygon shrunk by `inset_m` (where the COM target must be). Plain floats:
    it is rebuilt at every change of support."""

    def __init__(self, soles, inset_m: float) -> None:
        """soles: ((x [m], y [m], yaw [rad]), FootRectangle) of each sole in contact."""
        corners = []
        for (x, y, yaw), rect in soles:
            c, s = math.cos(yaw), math.sin(yaw)
            for fx, fy in ((-rect.rear_m, -rect.right_m), (rect.front_m, -rect.right_m),
                           (rect.front_m, rect.left_m), (-rect.rear_m, rect.left_m)):
                corners.append((x + c * fx - s * fy, y + s * fx + c * fy))
        ccw = [tuple(v) for v in convex_hull_2d(corners).tolist()]  # counter-clockwise
        self.ccw = ccw
        self.clockwise = [np.array(v) for v in ccw[::-1]]
        self.edges = _edges(ccw)  # (inward normal x, y, offset): inside where n . p >= offset
        # every edge moved in by the margin: the new vertices are where consecutive moved edges meet; valid
        # while no edge vanishes (each keeps its direction), else the general clipping does it
        moved = [(nx, ny, off + inset_m) for nx, ny, off in self.edges]
        safe = []
        for (ax, ay, ad), (bx, by, bd) in zip(moved[-1:] + moved[:-1], moved, strict=True):
            det = ax * by - ay * bx
            safe.append(((ad * by - bd * ay) / det, (ax * bd - bx * ad) / det))
        n = len(safe)
        keeps_direction = all(
            (safe[(i + 1) % n][0] - safe[i][0]) * (ccw[(i + 1) % n][0] - ccw[i][0])
            + (safe[(i + 1) % n][1] - safe[i][1]) * (ccw[(i + 1) % n][1] - ccw[i][1]) > 0.0 for i in range(n))
        if not keeps_direction:
            clipped = shrink_polygon(np.array(ccw), inset_m)
            safe = [tuple(v) for v in clipped.tolist()] or [
                (sum(v[0] for v in ccw) / len(ccw), sum(v[1] for v in ccw) / len(ccw))]
        self.safe = safe
        self.safe_edges = _edges(safe) if len(safe) >= 3 else []

    def margin(self, x: float, y: float) -> float:
        """Smallest distance to an edge line [m]: the distance to the boundary inside, < 0 outside."""
        return min(nx * x + ny * y - off for nx, ny, off in self.edges)

    def nearest_safe(self, x: float, y: float) -> tuple[float, float]:
        """(x, y) if it is inside the margin, else the nearest point of the shrunk polygon."""
        if not self.safe_edges:
            return self.safe[0]
        if min(nx * x + ny * y - off for nx, ny, off in self.safe_edges) >= 0.0:
            return x, y
        best, best_d2 = self.safe[0], math.inf
        v = self.safe
        for (ax, ay), (bx, by) in zip(v, v[1:] + v[:1], strict=True):
            dx, dy = bx - ax, by - ay
            t = max(0.0, min(1.0, ((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy)))
            px, py = ax + t * dx, ay + t * dy
            d2 = (px - x) ** 2 + (py - y) ** 2
            if d2 < best_d2:
                best, best_d2 = (px, py), d2
        return best


class GuardBox:
    """The upper-body mode's COM guard: a square of half-side `half_m` around (x, y), as placo's clockwise
    vertex list, with the margin to its edges."""

    def __init__(self, x: float, y: float, half_m: float) -> None:
        ccw = [(x - half_m, y - half_m), (x + half_m, y - half_m), (x + half_m, y + half_m), (x - half_m, y + half_m)]
        self.clockwise = [np.array(v) for v in ccw[::-1]]
        self.edges = _edges(ccw)
        self._box = (x - half_m, x + half_m, y - half_m, y + half_m)

    def margin(self, x: float, y: float) -> float:
        """min over the edges of n . p - offset, which for this axis-aligned box is exactly the distances to
        its four sides (asked twice a tick: no generator)."""
        x0, x1, y0, y1 = self._box
        return min(y - y0, x1 - x, y1 - y, x - x0)


def _edges(ccw) -> list[tuple[float, float, float]]:
    out = []
    for (ax, ay), (bx, by) in zip(ccw, ccw[1:] + ccw[:1], strict=True):
        length = math.hypot(bx - ax, by - ay)
        nx, ny = -(by - ay) / length, (bx - ax) / length
        out.append((nx, ny, nx * ax + ny * ay))
    return out
