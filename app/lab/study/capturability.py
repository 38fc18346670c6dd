"""Which pushes on a walking HRP-2 the linear inverted pendulum can capture with the ankles alone or with one step
(Koolen et al., "Capturability-based analysis and control of legged locomotion", 2012): the boundary the push map
draws, so that a fall inside it is the controller's and a fall outside it is physics.

The model (each assumption is a simplification the map's reader should know):

- **LIP**: the COM at constant height z, omega = sqrt(g / z); the ZMP anywhere in the support polygon (an ideal
  ankle, no margin: with it the standing bound comes out as measured, 29 / 22 / 41 N s forward / backward /
  sideways against 28 / 20 / 40 absorbed and 29 / 21 / 41 falling); no angular momentum (no hip strategy).
- **The push**: a constant force J / push_s on the COM over push_s, in the robot's frame (x forward, y left).
- **The walk at the push**: the soles flat and parallel (a turn's yaw between them is neglected), y = +-w apart,
  the leading sole one stride (speed x step time) ahead in double support; the nominal ZMP on the stance sole's
  origin in single support and going linearly from the old stance sole to the new one in double support; the
  nominal capture point ahead of the nominal ZMP by speed / omega (the COM over the ZMP at the walk's speed).
- **The gait's timing**: phase 0 is a touchdown of the right foot; each step of `step_time_s` has a double support of
  `double_support_s` after its touchdown (the AutoBalancer's: 1.0 s steps, 0.2 s of double support).
- **0 steps**: one ZMP held in the support polygon at the push (the stance sole, or both soles in double support)
  through the push brings the capture point at the push's end inside that polygon; from there the ankles hold it.
- **1 step**: a sole lands with the capture point inside the hull of it and the stance sole (or inside it). In single
  support the foot in the air lands; no earlier than `min_swing_s` after it lifted, and no later than the plan's own
  touchdown. In double support either foot may lift at once and land `min_touchdown_s` later (the standing
  emergency step's initial double support plus its swing; until the lift the ZMP may be anywhere in both soles).
  The landing is within the leg's reach from the stance
  sole, the standing emergency step's (EmergencyStepParams: 0.55 m forward, 0.40 m back, 0.16-0.45 m sideways on
  the swing leg's side: the soles never cross, which also stands for the hip's inward roll limit). The ZMP is held
  at one point of the stance sole from the lift (or the push) until the touchdown; a touchdown before the push ends
  counts as at its end. Two or more steps are not considered ("not capturable" means: not with one step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from controller.balance.capture_point import (
    HRP2_LEFT_SOLE,
    HRP2_RIGHT_SOLE,
    FootRectangle,
    distance_to_polygon_edge,
    support_polygon,
)
from controller.walking.emergency_step import EmergencyStepParams

GRAVITY_M_S2 = 9.81
SOLES: dict[str, FootRectangle] = {"rleg": HRP2_RIGHT_SOLE, "lleg": HRP2_LEFT_SOLE}
OTHER = {"rleg": "lleg", "lleg": "rleg"}


@dataclass(frozen=True)
class Lip:
    """The linear inverted pendulum of the robot."""

    mass_kg: float  # [kg]
    com_height_m: float  # [m] above the soles
    g_m_s2: float = GRAVITY_M_S2

    def __post_init__(self) -> None:
        if not (self.mass_kg > 0.0 and self.com_height_m > 0.0):
            raise ValueError(f"Lip needs a positive mass and COM height, got {self.mass_kg} kg, {self.com_height_m} m")

    @property
    def omega_1_s(self) -> float:  # [1/s]
        return math.sqrt(self.g_m_s2 / self.com_height_m)


@dataclass(frozen=True)
class GaitTiming:
    """The walk's step timing and the soles' spacing (the AutoBalancer's defaults)."""

    step_time_s: float = 1.0  # [s] one step, its double support included
    double_support_s: float = 0.2  # [s] after each touchdown
    leg_offset_y_m: float = 0.095  # [m] each sole from the feet's middle

    @property
    def cycle_s(self) -> float:  # [s] two steps: right touchdown to right touchdown
        return 2.0 * self.step_time_s


@dataclass(frozen=True)
class StepLimits:
    """The fastest step and the leg's reach, from the standing emergency step's parameters."""

    min_swing_s: float  # [s] lift-off to touchdown, at the fastest
    min_touchdown_s: float  # [s] from both feet loaded to the touchdown of a step
    max_forward_m: float  # [m] landing sole from the stance sole, in its frame
    max_backward_m: float
    min_width_m: float
    max_width_m: float

    @classmethod
    def of(cls, p: EmergencyStepParams | None = None) -> StepLimits:
        p = p or EmergencyStepParams()
        swing = p.step_time_s * (1.0 - p.double_support_ratio)
        return cls(swing, p.initial_double_support_s + swing, p.max_forward_m, p.max_backward_m, p.min_width_m,
                   p.max_width_m)


@dataclass(frozen=True)
class GaitMoment:
    """The support at the push, in the robot's frame [m]: which soles are down and where, the nominal ZMP, and the
    timing of the foot in the air (single support) or of the double support."""

    support: str  # "both", "rleg" or "lleg" (the stance leg)
    leading: str  # the sole that touched down last (the stance sole in single support)
    soles_xy: dict[str, tuple[float, float]]  # the soles on the ground
    zmp_xy: tuple[float, float]
    swing_elapsed_s: float  # [s] since the foot in the air lifted (single support; 0 in double support)
    swing_left_s: float  # [s] until the plan's touchdown (single support; 0 in double support)


def gait_moment(phase: float, speed_m_s: float, timing: GaitTiming = GaitTiming()) -> GaitMoment:
    """The support at `phase` (0..1 of the cycle from a right touchdown) of a walk at `speed_m_s` forward."""
    tau = (phase % 1.0) * timing.cycle_s
    leading = "rleg" if tau < timing.step_time_s else "lleg"  # the sole that touched down last
    t = tau % timing.step_time_s
    w = timing.leg_offset_y_m
    side = {"rleg": -1.0, "lleg": 1.0}
    if t < timing.double_support_s:
        half = 0.5 * speed_m_s * timing.step_time_s
        soles = {leading: (half, side[leading] * w), OTHER[leading]: (-half, side[OTHER[leading]] * w)}
        s = t / timing.double_support_s
        old, new = np.array(soles[OTHER[leading]]), np.array(soles[leading])
        zmp = old + (new - old) * s
        return GaitMoment("both", leading, soles, (float(zmp[0]), float(zmp[1])), 0.0, 0.0)
    origin = (0.0, side[leading] * w)
    return GaitMoment(leading, leading, {leading: origin}, origin, t - timing.double_support_s,
                      timing.step_time_s - t)


@dataclass(frozen=True)
class Capturability:
    """The verdict for one push: `steps` 0 (the ankles), 1 (one step) or None (not with one step); the capture
    point at the push's end and at the touchdown [m] (robot frame), the landing found and the margins [m] (how far
    inside the polygon the capture point ends, negative: outside)."""

    steps: int | None
    cp_push_end_xy: tuple[float, float]
    ankle_margin_m: float
    swing_leg: str | None = None
    touchdown_s: float | None = None  # [s] after the push's start
    cp_touchdown_xy: tuple[float, float] | None = None
    landing_xy: tuple[float, float] | None = None
    step_margin_m: float | None = None

    @property
    def label(self) -> str:
        return {0: "0 steps", 1: "1 step", None: "not capturable"}[self.steps]


def _halfplanes(polygon_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N (K, 2), b (K,)) with the polygon (counter-clockwise) = {p: N p >= b}, N the inward unit normals."""
    v = np.asarray(polygon_xy, dtype=float)
    area2 = float(np.sum(v[:, 0] * np.roll(v[:, 1], -1) - np.roll(v[:, 0], -1) * v[:, 1]))
    if area2 < 0.0:
        v = v[::-1]
    e = np.roll(v, -1, axis=0) - v
    n = np.stack([-e[:, 1], e[:, 0]], axis=1)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return n, np.sum(n * v, axis=1)


def _best_constant_zmp(c: np.ndarray, k: float, zmp_polygon: np.ndarray, target_polygon: np.ndarray
                       ) -> tuple[float, np.ndarray]:
    """max over p in zmp_polygon of how far xi = c - k p lies inside target_polygon (its smallest inward slack over
    the target's edges, an LP): (that margin [m], p). The capture point under a held ZMP is affine in it."""
    Nz, bz = _halfplanes(zmp_polygon)
    Nt, bt = _halfplanes(target_polygon)
    # variables (px, py, t): maximise t; Nt (c - k p) - bt >= t and Nz p >= bz
    a_ub = np.vstack([np.hstack([k * Nt, np.ones((len(Nt), 1))]), np.hstack([-Nz, np.zeros((len(Nz), 1))])])
    b_ub = np.concatenate([Nt @ c - bt, -bz])
    res = linprog([0.0, 0.0, -1.0], A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * 2 + [(None, 1.0)], method="highs")
    if res.status != 0:
        raise RuntimeError(f"capturability LP failed: {res.message}")
    return float(res.x[2]), res.x[:2]


def _reach_box(stance_xy, swing_leg: str, limits: StepLimits) -> np.ndarray:
    """(4, 2) the landing sole origins the leg reaches from the stance sole (axis-aligned: soles parallel)."""
    sx, sy = stance_xy
    side = 1.0 if swing_leg == "lleg" else -1.0
    ys = sorted((sy + side * limits.min_width_m, sy + side * limits.max_width_m))
    x0, x1 = sx - limits.max_backward_m, sx + limits.max_forward_m
    return np.array([[x0, ys[0]], [x1, ys[0]], [x1, ys[1]], [x0, ys[1]]])


def _sole(leg: str, xy) -> np.ndarray:
    return SOLES[leg].corners_world((float(xy[0]), float(xy[1]), 0.0))


def _one_step(c0: np.ndarray, accel: np.ndarray, push_s: float, omega: float, double_support: np.ndarray | None,
              lift_s: float, stance: str, stance_xy, swing: str, touchdown_s: float, limits: StepLimits
              ) -> tuple[float, np.ndarray, np.ndarray, float]:
    """The best single step of `swing` landing touchdown_s after the push's start: one ZMP held in the
    `double_support` polygon until the foot lifts at lift_s (0: in the air already), then one on the stance sole:
    (margin [m], CP at touchdown, landing, touchdown_s). LP over (the two ZMPs, the landing L, t): the CP inside
    the landing sole shrunk by t; then, for a few held stance ZMPs, the hull of both soles with the landing nearest
    the capture point."""
    td = max(touchdown_s, push_s, lift_s)
    # the capture point at touchdown is affine in the two ZMPs: xi = c + k1 p1 + k2 p2
    c, k1, k2, t = np.array(c0, dtype=float), 0.0, 0.0, 0.0
    for t_next in sorted({push_s, lift_s, td} - {0.0}):
        if t_next <= t:
            continue
        e = math.exp(omega * (t_next - t))
        a = accel / omega**2 if t < push_s else np.zeros(2)
        c = e * c - (1.0 - e) * a
        k1, k2 = (e * k1 + (1.0 - e), e * k2) if t < lift_s else (e * k1, e * k2 + (1.0 - e))
        t = t_next
    polygon1 = double_support if double_support is not None else _sole(stance, stance_xy)
    N1, b1 = _halfplanes(polygon1)
    Nz, bz = _halfplanes(_sole(stance, stance_xy))
    Nr, br = _halfplanes(_reach_box(stance_xy, swing, limits))
    rect = SOLES[swing]
    # variables (p1, p2, L, t); xi - L inside the sole rectangle shrunk by t: -rear + t <= (xi - L)_x <= front - t
    rows, rhs = [], []
    for axis, hi, lo in ((0, rect.front_m, -rect.rear_m), (1, rect.left_m, -rect.right_m)):
        e = np.zeros(2)
        e[axis] = 1.0
        rows.append(np.concatenate([k1 * e, k2 * e, -e, [1.0]]))  # c + k1 p1 + k2 p2 - L <= hi - t
        rhs.append(hi - c[axis])
        rows.append(np.concatenate([-k1 * e, -k2 * e, e, [1.0]]))  # -(c + k1 p1 + k2 p2 - L) <= -lo - t
        rhs.append(c[axis] - lo)
    z2 = np.zeros
    a_ub = np.vstack([np.array(rows),
                      np.hstack([-N1, z2((len(N1), 5))]),
                      np.hstack([z2((len(Nz), 2)), -Nz, z2((len(Nz), 3))]),
                      np.hstack([z2((len(Nr), 4)), -Nr, z2((len(Nr), 1))])])
    b_ub = np.concatenate([rhs, -b1, -bz, -br])
    res = linprog([0, 0, 0, 0, 0, 0, -1.0], A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * 6 + [(None, 1.0)],
                  method="highs")
    if res.status != 0:
        raise RuntimeError(f"capturability LP failed: {res.message}")
    p1 = res.x[:2]
    best = (float(res.x[6]), c + k1 * p1 + k2 * res.x[2:4], res.x[4:6])
    box = _reach_box(stance_xy, swing, limits)
    lo, hi = box.min(axis=0), box.max(axis=0)
    corners = _sole(stance, stance_xy)
    for p2 in np.vstack([corners, 0.5 * (corners + np.roll(corners, -1, axis=0)), [stance_xy]]):
        xi = c + k1 * p1 + k2 * p2
        landing = np.clip(xi, lo, hi)
        hull = support_polygon([((stance_xy[0], stance_xy[1], 0.0), SOLES[stance]),
                                ((landing[0], landing[1], 0.0), rect)])
        margin = distance_to_polygon_edge(xi, hull)
        if margin > best[0]:
            best = (margin, xi, landing)
    return best[0], best[1], best[2], td


def push_capturability(impulse_ns: float, direction_rad: float, phase: float, speed_m_s: float, lip: Lip,
                       timing: GaitTiming = GaitTiming(), limits: StepLimits | None = None, push_s: float = 0.1,
                       cp_from_sole_xy: tuple[float, float] | None = None) -> Capturability:
    """Capturable with 0 or 1 step, or not: a push of `impulse_ns` [N s] over `push_s` [s] in direction
    `direction_rad` of the robot's frame (0 forward, pi/2 left) at `phase` of the gait cycle of a walk at
    `speed_m_s` (0 with phase in a double support: standing). The assumptions are the module's.

    `cp_from_sole_xy`: the capture point at the push as measured [m], in the frame of the stance sole (single
    support) or of the sole that landed last (double support), instead of the nominal one (ahead of the nominal
    ZMP by speed / omega): the walk's lateral sway puts it up to 6 cm nearer the stance sole's outer edge."""
    if impulse_ns < 0.0 or push_s <= 0.0:
        raise ValueError(f"impulse_ns must be >= 0 and push_s > 0, got {impulse_ns}, {push_s}")
    limits = limits or StepLimits.of()
    omega = lip.omega_1_s
    u = np.array([math.cos(direction_rad), math.sin(direction_rad)])
    accel = u * impulse_ns / (lip.mass_kg * push_s)  # [m/s^2]
    g = gait_moment(phase, speed_m_s, timing)
    c0 = np.array(g.zmp_xy) + np.array([speed_m_s / omega, 0.0])
    if cp_from_sole_xy is not None:
        c0 = np.array(g.soles_xy[g.leading]) + np.asarray(cp_from_sole_xy, dtype=float)
    polygon = support_polygon([((x, y, 0.0), SOLES[leg]) for leg, (x, y) in g.soles_xy.items()])
    e_push = math.exp(omega * push_s)
    a = accel / omega**2
    ankle_margin, p = _best_constant_zmp((c0 + a) * e_push - a, e_push - 1.0, polygon, polygon)
    xi_end = (c0 + a) * e_push - a - (e_push - 1.0) * p
    end = (float(xi_end[0]), float(xi_end[1]))
    if ankle_margin >= 0.0:
        return Capturability(0, end, ankle_margin)
    if g.support == "both":
        lift = limits.min_touchdown_s - limits.min_swing_s
        options = [(OTHER[leg], g.soles_xy[OTHER[leg]], leg, limits.min_touchdown_s) for leg in g.soles_xy]
    else:
        lift, polygon = 0.0, None
        earliest = max(limits.min_swing_s - g.swing_elapsed_s, 0.0)
        options = [(g.support, g.soles_xy[g.support], OTHER[g.support], min(g.swing_left_s, earliest))]
    best = None
    for stance, stance_xy, swing, td in options:
        margin, xi, landing, td_used = _one_step(c0, accel, push_s, omega, polygon, lift, stance, stance_xy, swing,
                                                 td, limits)
        if best is None or margin > best[0]:
            best = (margin, xi, landing, td_used, swing)
    margin, xi, landing, td_used, swing = best
    return Capturability(1 if margin >= 0.0 else None, end, ankle_margin, swing, td_used,
                         (float(xi[0]), float(xi[1])), (float(landing[0]), float(landing[1])), margin)


def largest_capturable_ns(direction_rad: float, phase: float, speed_m_s: float, lip: Lip, steps: int,
                          timing: GaitTiming = GaitTiming(), limits: StepLimits | None = None, push_s: float = 0.1,
                          high_ns: float = 200.0, tol_ns: float = 0.25,
                          cp_from_sole_xy: tuple[float, float] | None = None) -> float:
    """The largest impulse [N s] (to tol_ns) in this direction and phase that `steps` (0 or 1) steps capture: the
    LIP's boundary across impulses (capturability shrinks as the push grows: bisection)."""
    def ok(j: float) -> bool:
        c = push_capturability(j, direction_rad, phase, speed_m_s, lip, timing, limits, push_s, cp_from_sole_xy)
        return c.steps is not None and c.steps <= steps

    if ok(high_ns):
        return high_ns
    lo, hi = 0.0, high_ns
    while hi - lo > tol_ns:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo
