"""Stabilizer force-moment distribution: target ZMP and total Fz split into foot forces by a QP (Eq. 9-14)."""

from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass, field

import numpy as np
import qpsolvers
from scipy import sparse

try:
    import daqp as _daqp
except ImportError:  # daqp not installed: solve_qp reports it
    _daqp = None

from controller.core.errors import ControllerError, InvalidCommand
from controller.core.layer import Params
from controller.core.types import read_only

QP_SOLVERS = ("daqp", "clarabel")  # the backends pyproject pins (qpsolvers names)
#: the solver a QP daqp returns no solution for is solved again with (interior point: slower, rarely needed).
#: Measured: the feet 0.45 m apart in a sideways emergency step, alpha 0 (the right foot's weight 1e6 times the
#: left's) and a target that needs the right foot's load: daqp gave up, and the Stabilizer faulted
FALLBACK_SOLVER = "clarabel"


class ForceDistributionFailed(ControllerError):
    """The QP solver returned no solution (it should not for a target inside or projected onto the hull)."""


@dataclass(frozen=True)
class ForceDistributionWeights(Params):
    """Cost weights of Eq. 11 (hrpsys EEFMQP defaults) and the QP backend."""

    # weight of the per-foot moment about the reference COP, ||G_cop,i f||^2  [cost] / [N m]^2
    cop_weight: float = field(default=1e-3, metadata={"unit": "1/(N m)^2", "min": 0.0, "max": 1e3})
    # weight of the vertex forces, scaled per foot by 1/alpha and 1/(1-alpha)  [cost] / [N]^2
    norm_weight: float = field(default=1e-7, metadata={"unit": "1/N^2", "min": 1e-12, "max": 1e3})
    # alpha is clamped to [alpha_epsilon, 1 - alpha_epsilon] so that 1/alpha and 1/(1-alpha) stay finite
    alpha_epsilon: float = field(default=1e-6, metadata={"unit": "-", "min": 1e-12, "max": 0.1})
    solver: str = field(default="daqp", metadata={"choices": QP_SOLVERS})


@dataclass(frozen=True)
class FootPolygon:
    """A foot sole projected on the ground: vertices (n, 2) [m] and reference COP (2,) [m], world frame."""

    vertices_world: np.ndarray  # (n, 2) [m], n >= 3, any order
    cop_ref_xy: np.ndarray  # (2,) [m], world frame

    def __post_init__(self) -> None:
        vertices = np.array(self.vertices_world, dtype=float)
        cop = np.array(self.cop_ref_xy, dtype=float)
        if vertices.ndim != 2 or vertices.shape[1] != 2 or vertices.shape[0] < 3:
            raise InvalidCommand(
                f"FootPolygon.vertices_world must have shape (n>=3, 2); got {vertices.shape}"
            )
        if cop.shape != (2,):
            raise InvalidCommand(f"FootPolygon.cop_ref_xy must have shape (2,); got {cop.shape}")
        if not (np.all(np.isfinite(vertices)) and np.all(np.isfinite(cop))):
            raise InvalidCommand("FootPolygon vertices and reference COP must be finite")
        read_only(vertices)
        read_only(cop)
        object.__setattr__(self, "vertices_world", vertices)
        object.__setattr__(self, "cop_ref_xy", cop)


@dataclass(frozen=True)
class FootForces:
    """Result of one distribution; arrays are read-only, feet in the order given.

    Moments follow Eq. 13-14 literally, about each foot's *reference COP* p_cop (not the foot origin):
    n_x = -sum_j (p_j,y - p_cop,y) f_j,   n_y = sum_j (p_j,x - p_cop,x) f_j,
    i.e. the foot's COP is p_cop + (n_y, -n_x) / fz (this n is minus the ground-reaction moment about p_cop).
    """

    fz_n: np.ndarray  # (n_feet,) [N]
    n_xy_nm: np.ndarray  # (n_feet, 2) [N m], about cop_ref_xy of each foot, Eq. 13-14 sign
    cop_world_xy: np.ndarray  # (n_feet, 2) [m]; the reference COP where a foot carries no force
    vertex_fz_n: tuple[np.ndarray, ...]  # per foot (n_vertices_i,) [N], >= 0
    zmp_world_xy: np.ndarray  # (2,) [m], the ZMP the forces realise (the target, or its projection)
    projected: bool  # True when the target was outside the support hull and was projected onto it


def alpha_from_zmp(zmp_xy: np.ndarray, rfoot_xy: np.ndarray, lfoot_xy: np.ndarray) -> float:
    """Share of the RIGHT foot in [0, 1] (Kajita 2010 style): 1 with the ZMP at the right foot, 0 at the left.

    The ZMP is projected on the segment from the left to the right foot position [m] and the ratio
    clamped to [0, 1]. Coincident feet give 0.5.
    """
    (r0, r1), (l0, l1), (z0, z1) = rfoot_xy, lfoot_xy, zmp_xy
    r0, r1, l0, l1, z0, z1 = float(r0), float(r1), float(l0), float(l1), float(z0), float(z1)
    d0, d1 = r0 - l0, r1 - l1
    dd = d0 * d0 + d1 * d1
    if dd < 1e-18:
        return 0.5
    return min(1.0, max(0.0, ((z0 - l0) * d0 + (z1 - l1) * d1) / dd))


def convex_hull_ccw(points_xy: np.ndarray) -> np.ndarray:
    """Convex hull (Andrew's monotone chain) of (n, 2) points [m], counter-clockwise, no repeated vertex."""
    pts = sorted(set(map(tuple, np.asarray(points_xy, dtype=float).tolist())))  # by x then y
    if len(pts) < 3:
        return np.array(pts, dtype=float).reshape(-1, 2)

    def half(seq: list[tuple[float, float]]) -> list[tuple[float, float]]:
        out: list[tuple[float, float]] = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0.0:
                out.pop()
            out.append(p)
        return out

    return np.array(half(pts)[:-1] + half(pts[::-1])[:-1])


def nearest_point_in_polygon(point_xy: np.ndarray, hull_ccw: np.ndarray) -> tuple[np.ndarray, bool]:
    """Nearest point [m] of a counter-clockwise convex polygon to `point_xy`, and whether it had to move."""
    return _Polygon(hull_ccw).nearest(np.asarray(point_xy, dtype=float))


class _Polygon:
    """A counter-clockwise convex polygon with its edges precomputed for fast inside tests and projection."""

    def __init__(self, hull_ccw: np.ndarray) -> None:
        self.a = np.asarray(hull_ccw, dtype=float)  # (m, 2) [m]
        self.e = np.concatenate((self.a[1:], self.a[:1])) - self.a  # (m, 2) [m], edge vectors
        self.ee = np.maximum(np.einsum("ij,ij->i", self.e, self.e), 1e-300)  # (m,) [m^2]
        self.tol = 1e-12 * max(float(np.max(np.abs(self.a))), 1.0) ** 2  # [m^2]
        self._edges = tuple(zip(self.a.tolist(), self.e.tolist(), strict=True))  # ((ax, ay), (ex, ey)) floats

    def nearest(self, p: np.ndarray) -> tuple[np.ndarray, bool]:
        px, py = p.tolist()
        neg_tol = -self.tol
        for (ax, ay), (ex, ey) in self._edges:  # inside (the usual case): no array maths
            if ex * (py - ay) - ey * (px - ax) < neg_tol:
                break
        else:
            return p.copy(), False
        rel = p - self.a
        e = self.e
        cross = e[:, 0] * rel[:, 1] - e[:, 1] * rel[:, 0]
        if cross.min() >= -self.tol:
            return p.copy(), False
        t = np.clip((rel[:, 0] * e[:, 0] + rel[:, 1] * e[:, 1]) / self.ee, 0.0, 1.0)
        d = rel - t[:, None] * e  # from each edge's nearest point to p
        k = int(np.argmin(d[:, 0] ** 2 + d[:, 1] ** 2))
        return self.a[k] + t[k] * e[k], True


class ForceDistributionQP:
    """Eq. 9-11 for fixed feet, alpha and weights; `solve(zmp, fz)` only changes the equality's right side.

    Unknowns are the vertex normal forces as fractions s = f / Fz [-] (same minimiser, better scaled):
      min  sum_i cop_weight ||G_cop,i s||^2 + norm_weight s^T W_f s
      s.t. sum_j s_j = 1,  sum_j s_j p_j = zmp   (equivalent to F = G f with F = [Fz, 0, 0], moments
           about the target ZMP, so the realised ZMP is the target),   s >= 0.
    Two feet are ordered (right, left); alpha is the right foot's share.
    """

    def __init__(self, feet: list[FootPolygon] | tuple[FootPolygon, ...], alpha: float = 0.5,
                 weights: ForceDistributionWeights | None = None) -> None:
        if len(feet) not in (1, 2):
            raise InvalidCommand(
                f"feet must hold 1 (single support) or 2 (right, left) FootPolygon; got {len(feet)}"
            )
        if not all(isinstance(foot, FootPolygon) for foot in feet):
            raise InvalidCommand("feet must be FootPolygon instances")
        if not np.isfinite(alpha) or not 0.0 <= alpha <= 1.0:
            raise InvalidCommand(f"alpha is the right foot's share and must be in [0, 1]; got {alpha!r}")
        self.feet = tuple(feet)
        self.alpha = float(alpha)
        self.weights = weights if weights is not None else DEFAULT_WEIGHTS
        w = self.weights
        n_feet = len(self.feet)
        sizes = np.array([len(foot.vertices_world) for foot in self.feet])
        self._split = np.cumsum(sizes)[:-1]
        foot_of_vertex = np.repeat(np.arange(n_feet), sizes)  # (n,)
        p_world = np.vstack([foot.vertices_world for foot in self.feet])  # (n, 2) [m]
        cop_refs = np.array([foot.cop_ref_xy for foot in self.feet])  # (n_feet, 2) [m]
        d = p_world - cop_refs[foot_of_vertex]  # (n, 2) [m], vertex relative to its foot's reference COP
        n = len(p_world)

        self._n_feet = n_feet
        self._foot_of_vertex = foot_of_vertex

        # Eq. 12-14 as matrices: fz = S f, n_x = Nx f, n_y = Ny f, each (n_feet, n)
        self._S = (foot_of_vertex[None, :] == np.arange(n_feet)[:, None]).astype(float)
        self._Nx = self._S * -d[:, 1]
        self._Ny = self._S * d[:, 0]
        self._cop_refs = cop_refs

        # sum_i ||G_cop,i f||^2 = f^T (Nx^T Nx + Ny^T Ny) f since the feet's columns do not overlap
        self._P_cop = w.cop_weight * (self._Nx.T @ self._Nx + self._Ny.T @ self._Ny)
        self._P_cop_symmetric = bool(np.array_equal(self._P_cop, self._P_cop.T))
        self._P_cop_diag = np.diag(self._P_cop).tolist()  # floats, for set_alpha
        self._foot_of_vertex_list = foot_of_vertex.tolist()
        # per-vertex data as floats for the per-tick sums: foot, -d_y, d_x; and each foot's vertex range
        self._vertex_rows = tuple(zip(foot_of_vertex.tolist(), (-d[:, 1]).tolist(), d[:, 0].tolist(), strict=True))
        bounds = np.concatenate(([0], np.cumsum(sizes))).tolist()
        self._bounds = tuple(zip(bounds[:-1], bounds[1:], strict=True))
        self._cop_refs_list = cop_refs.tolist()
        self.set_alpha(self.alpha)
        self._q = np.zeros(n)
        self._A = np.vstack([np.ones(n), p_world.T])  # (3, n)
        self._lb = np.zeros(n)
        self._p_world = p_world
        self._hull = convex_hull_ccw(p_world)
        read_only(self._hull)
        self._polygon = _Polygon(self._hull)
        # daqp's form of the constraints (what qpsolvers' daqp interface builds from lb and A = b):
        # rows 0..n-1 are the bounds 0 <= s_j (< 1e30), rows n.. the equalities (sense 5), A s = b
        self._daqp_upper = np.empty(n + 3)
        self._daqp_upper[:n] = 1e30
        self._daqp_lower = np.full(n + 3, -1e30)
        self._daqp_lower[:n] = self._lb
        self._daqp_sense = np.zeros(n + 3, dtype=ctypes.c_int)
        self._daqp_sense[n:] = 5

    def set_alpha(self, alpha: float) -> None:
        """Change the right/left distribution ratio (only the W_f part of the cost is rebuilt)."""
        if not (math.isfinite(alpha) and 0.0 <= alpha <= 1.0):
            raise InvalidCommand(f"alpha is the right foot's share and must be in [0, 1]; got {alpha!r}")
        self.alpha = float(alpha)
        w = self.weights
        if self._n_feet == 2:
            a = min(max(self.alpha, w.alpha_epsilon), 1.0 - w.alpha_epsilon)
            # The paper writes w_l = 1/(alpha - 1), negative for alpha in (0, 1), which would make the QP
            # non-convex and reward force on the left foot; 1/(1 - alpha) is the intended weight.
            per_foot = (1.0 / a, 1.0 / (1.0 - a))
        else:
            per_foot = (1.0,)
        norm_weight = w.norm_weight
        # P_cop + diag(norm_weight w_f), w_f the weight of each vertex's foot (on floats: same sums)
        diag = [d + norm_weight * per_foot[k] for d, k in zip(self._P_cop_diag, self._foot_of_vertex_list, strict=True)]
        P = self._P_cop.copy()
        n = len(diag)
        P.reshape(-1)[::n + 1] = diag  # P's diagonal
        # rescale the cost: same minimiser, O(1) numbers for the solver
        P /= sorted(diag)[n // 2]
        # symmetric part (P already is when P_cop is: a diagonal term does not change that)
        self._P = P if self._P_cop_symmetric else 0.5 * (P + P.T)

    def _solve_qp(self, b: np.ndarray) -> np.ndarray | None:
        """qpsolvers.solve_qp(P, q, A=A, b=b, lb=lb, solver=...). For daqp, the call qpsolvers makes
        (daqp.solve on the bounds and equalities stacked as below), with the fixed parts built once."""
        if self.weights.solver != "daqp" or _daqp is None:
            return qpsolvers.solve_qp(self._P, self._q, A=self._A, b=b, lb=self._lb, solver=self.weights.solver)
        upper = self._daqp_upper
        upper[-3:] = b  # the equalities' right side; daqp reads, never writes, its arguments
        x, _, exitflag, _ = _daqp.solve(self._P, self._q, self._A, upper, self._daqp_lower, self._daqp_sense,
                                        primal_start=None)
        return x if exitflag > 0 else None

    def __repr__(self) -> str:
        return (f"ForceDistributionQP(n_feet={len(self.feet)}, n_vertices={len(self._p_world)}, "
                f"alpha={self.alpha:.3f}, weights={self.weights!r})")

    @property
    def hull_world(self) -> np.ndarray:
        """Counter-clockwise convex hull (m, 2) [m] of all foot vertices: the feasible ZMP set."""
        return self._hull

    def solve(self, zmp_xy: np.ndarray, total_fz_n: float) -> FootForces:
        """Distribute `total_fz_n` [N] so that the ZMP is `zmp_xy` [m], or the nearest feasible point."""
        zmp = np.asarray(zmp_xy, dtype=float)
        if zmp.shape != (2,) or not (math.isfinite(zmp[0]) and math.isfinite(zmp[1])):
            raise InvalidCommand(f"zmp_xy must be a finite (2,) array [m]; got {zmp_xy!r}")
        finite = math.isfinite(total_fz_n) if isinstance(total_fz_n, float) else np.isfinite(total_fz_n)
        if not finite or total_fz_n < 0.0:
            raise InvalidCommand(f"total_fz_n must be a finite force >= 0 [N]; got {total_fz_n!r}")
        zmp, projected = self._polygon.nearest(zmp)
        b = np.array([1.0, zmp[0], zmp[1]])
        s = self._solve_qp(b)
        if s is None and self.weights.solver != FALLBACK_SOLVER:  # an ill-conditioned cost: the robust solver
            s = qpsolvers.solve_qp(sparse.csc_matrix(self._P), self._q, A=sparse.csc_matrix(self._A), b=b,
                                   lb=self._lb, solver=FALLBACK_SOLVER)
        if s is None:
            raise ForceDistributionFailed(
                f"{self.weights.solver} found no vertex forces for ZMP {zmp} in hull {self._hull.tolist()}; "
                "try solver='clarabel'"
            )
        f = np.maximum(s, 0.0) * float(total_fz_n)  # clip solver round-off below zero  [N]
        # Eq. 12-14 (fz = S f, n_x = Nx f, n_y = Ny f) as per-foot sums over its vertices
        n_feet = self._n_feet
        fz_l, nx_l, ny_l = [0.0] * n_feet, [0.0] * n_feet, [0.0] * n_feet
        for fj, (k, mdy, dx) in zip(f.tolist(), self._vertex_rows, strict=True):
            fz_l[k] += fj
            nx_l[k] += mdy * fj
            ny_l[k] += dx * fj
        cop_l = []
        for k, (cx, cy) in enumerate(self._cop_refs_list):
            if fz_l[k] > 1e-9:  # loaded: COP offset (n_y, -n_x) / fz; unloaded foot: its reference
                cx, cy = cx + ny_l[k] / fz_l[k], cy + -nx_l[k] / fz_l[k]
            cop_l.append((cx, cy))
        fz = np.array(fz_l)
        n_xy = np.array(tuple(zip(nx_l, ny_l, strict=True)))
        cop = np.array(cop_l)
        for arr in (f, fz, n_xy, cop, zmp):
            read_only(arr)
        return FootForces(fz, n_xy, cop, tuple(f[a:b] for a, b in self._bounds), zmp, projected)


DEFAULT_WEIGHTS = ForceDistributionWeights()


def distribute_zmp_to_feet(zmp_xy: np.ndarray, total_fz_n: float, feet: list[FootPolygon], alpha: float = 0.5,
                           weights: ForceDistributionWeights | None = None) -> FootForces:
    """One-shot Eq. 9-14: build the QP for these feet and solve it; keep a ForceDistributionQP to reuse it."""
    return ForceDistributionQP(feet, alpha, weights).solve(zmp_xy, total_fz_n)
