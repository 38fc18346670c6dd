"""Capture-point emergency step: when the ankles cannot bring the measured capture point back into the support
polygon, which leg steps, where it lands, and the reference ZMP with which the LIP from the measured state ends
balanced ([MLC] II-B leaves stepping to future work; issue 13.3)."""

from __future__ import annotations

import copy
import functools
import math
from dataclasses import dataclass, field

import numpy as np

from controller.balance.capture_point import (
    HRP2_LEFT_SOLE,
    HRP2_RIGHT_SOLE,
    FootRectangle,
    convex_hull_xy,
    distance_to_polygon_edge,
    nearest_point_in_convex_polygon,
    nearest_point_in_convex_polygon_xy,
    shrink_polygon,
    shrink_polygon_xy,
    slack_in_shrunk_polygon_m,
    support_polygon,
)
from controller.core.errors import InvalidCommand, InvalidState
from controller.core.layer import Params
from controller.interpolation.hoff_arbib import min_jerk
from controller.walking.footsteps import Footstep
from controller.walking.gait_generator import GaitParams

__all__ = ["EmergencyStepParams", "EmergencyStepPlan", "SupportRegion", "clamp_landing", "landing_for",
           "lip_capture_point", "needs_step", "stance_zmp", "swing_leg_for"]

SOLES: dict[str, FootRectangle] = {"rleg": HRP2_RIGHT_SOLE, "lleg": HRP2_LEFT_SOLE}


@dataclass(frozen=True)
class EmergencyStepParams(Params):
    """When to step and how: the AutoBalancer's `emergency_step` parameters (AutoBalancerParams.emergency_step),
    each unit and range declared here once."""

    # standing, when the measured capture point is farther than cp_margin_m outside the support polygon (the
    # ankles cannot bring it back), one step where it will be; the EmergencyStopper holds the motion, the robot
    # ends standing with its feet apart (issue 13.3). False: no step (the walking capture step neither)
    enabled: bool = field(default=True, metadata={"unit": "-"})
    # the step is taken when the measured capture point is farther than this outside the support polygon of the
    # soles (negative: still inside); the LIP's CP cannot come back from outside whatever the ankles do
    cp_margin_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.05, "max": 0.1})
    # the planned ZMP keeps this far inside the sole edges (where the ankles can still put it)
    zmp_margin_m: float = field(default=0.015, metadata={"unit": "m", "min": 0.0, "max": 0.05})
    # double support before the swing (the ZMP goes to the stance sole), the step (swing and the double support
    # after it), the share of the step after the landing, the double support that ends standing
    initial_double_support_s: float = field(default=0.05, metadata={"unit": "s", "min": 0.005, "max": 0.5})
    step_time_s: float = field(default=0.3, metadata={"unit": "s", "min": 0.2, "max": 1.5})
    double_support_ratio: float = field(default=0.2, metadata={"unit": "-", "min": 0.05, "max": 0.5})
    final_double_support_s: float = field(default=1.5, metadata={"unit": "s", "min": 0.2, "max": 5.0})
    step_height_m: float = field(default=0.04, metadata={"unit": "m", "min": 0.01, "max": 0.1})
    # the landing sole relative to the stance sole, in its frame: reach forward and backward, and sideways at
    # least min_width_m (the soles do not overlap nor cross) and at most max_width_m
    max_forward_m: float = field(default=0.55, metadata={"unit": "m", "min": 0.0, "max": 0.7})
    max_backward_m: float = field(default=0.4, metadata={"unit": "m", "min": 0.0, "max": 0.7})
    min_width_m: float = field(default=0.16, metadata={"unit": "m", "min": 0.14, "max": 0.4})
    max_width_m: float = field(default=0.45, metadata={"unit": "m", "min": 0.16, "max": 0.7})
    # the sole's centre lands this far beyond the capture point predicted at touchdown, along its motion
    landing_offset_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.05, "max": 0.1})
    # once the foot is down the ZMP moves over this time to the capture point (at once: the CP is past the old
    # stance sole; a ZMP left behind it while the load shifts lets the CP run on past the new sole)
    zmp_shift_s: float = field(default=0.03, metadata={"unit": "s", "min": 0.005, "max": 0.3})
    # the landing follows the measured capture point until this long before the planned touchdown
    replan_until_s: float = field(default=0.1, metadata={"unit": "s", "min": 0.0, "max": 0.5})
    # BODY is lowered by this while the step is taken (the legs reach farther), and raised again once the robot
    # stands
    base_lowering_m: float = field(default=0.04, metadata={"unit": "m", "min": 0.0, "max": 0.1})

    def validate(self) -> None:
        super().validate()
        if self.min_width_m > self.max_width_m:
            raise InvalidCommand(f"EmergencyStepParams.min_width_m={self.min_width_m} > max_width_m="
                                 f"{self.max_width_m}; the lateral range must not be empty")


# ---------------------------------------------------------------------------------------- pure pieces


def lip_capture_point(cp_world_xy, zmp_world_xy, omega_1_s: float, t_s: float) -> np.ndarray:
    """The LIP's capture point t_s [s] on with the ZMP held at zmp_world_xy: xi(t) = zmp + (xi0 - zmp) e^(omega t),
    from xi_dot = omega (xi - zmp) [m], (2,)."""
    zmp = np.asarray(zmp_world_xy, dtype=float)
    return zmp + (np.asarray(cp_world_xy, dtype=float) - zmp) * math.exp(omega_1_s * t_s)


def needs_step(cp_world_xy, support_polygon_xy, margin_m: float) -> bool:
    """The capture point is farther than margin_m [m] outside the support polygon (M, 2): the ZMP, confined to
    the polygon, cannot be put beyond it, so by xi_dot = omega (xi - zmp) it only moves away."""
    return distance_to_polygon_edge(cp_world_xy, support_polygon_xy) < -margin_m


class SupportRegion:
    """A convex support polygon prepared for a test every tick: how far a point lies outside it [m]. Scalar maths
    over its few edges (the standing robot's trigger test costs a few microseconds)."""

    def __init__(self, polygon_xy) -> None:
        self.polygon_xy = np.asarray(polygon_xy, dtype=float).reshape(-1, 2)  # (M, 2) counter-clockwise [m]
        self._edges = []  # (ax, ay, nx, ny): a vertex and the edge's inward unit normal
        pts = self.polygon_xy.tolist()
        for (ax, ay), (bx, by) in zip(pts, pts[1:] + pts[:1], strict=True):
            length = math.hypot(bx - ax, by - ay)
            if length > 1e-12:
                self._edges.append((ax, ay, -(by - ay) / length, (bx - ax) / length))

    @classmethod
    def of_soles(cls, right, left) -> SupportRegion:
        """The region of HRP-2's two soles given as (position (3,), rotation (3, 3)) in the world."""
        feet = [((float(p[0]), float(p[1]), math.atan2(float(R[1, 0]), float(R[0, 0]))), rect)
                for (p, R), rect in ((right, HRP2_RIGHT_SOLE), (left, HRP2_LEFT_SOLE))]
        return cls(support_polygon(feet))

    def outside_m(self, x_m: float, y_m: float) -> float:
        """Signed distance [m] of the point from the polygon's boundary, positive outside, negative inside."""
        violation = max(-((x_m - ax) * nx + (y_m - ay) * ny) for ax, ay, nx, ny in self._edges)
        if violation <= 0.0:  # inside: the nearest edge line is the nearest boundary
            return violation
        return -distance_to_polygon_edge((x_m, y_m), self.polygon_xy)


def swing_leg_for(cp_from_feet_mid_xy, fz_rleg_n: float, fz_lleg_n: float) -> str:
    """The leg that steps, for the capture point's offset from the feet's mid-point in the feet frame (x
    forward, y left) [m]: sideways (|y| > |x|) the leg on the side it moves to; forward or backward the less
    loaded one (measured vertical force [N]), the left one on a tie."""
    dx, dy = (float(v) for v in cp_from_feet_mid_xy)
    if abs(dy) > abs(dx):
        return "lleg" if dy > 0.0 else "rleg"
    return "rleg" if fz_rleg_n < fz_lleg_n else "lleg"


def sole_corners_world(leg: str, x_m: float, y_m: float, yaw_rad: float) -> np.ndarray:
    """(4, 2) corners [m] of HRP-2's sole of `leg` with its frame at (x, y, yaw) in the world."""
    return SOLES[leg].corners_world((x_m, y_m, yaw_rad))


def stance_zmp(cp_world_xy, leg: str, sole_xy, sole_yaw_rad: float, margin_m: float) -> np.ndarray:
    """The ZMP while the other foot swings: the point of the stance sole (shrunk by margin_m) nearest the capture
    point, the farthest the ankle can push against it [m], (2,)."""
    corners = sole_corners_world(leg, float(sole_xy[0]), float(sole_xy[1]), sole_yaw_rad)
    return nearest_point_in_convex_polygon(cp_world_xy, shrink_polygon(corners, margin_m))


def clamp_landing(target_world_xy, stance_xy, stance_yaw_rad: float, swing_leg: str,
                  params: EmergencyStepParams) -> np.ndarray:
    """The landing sole origin [m] (2,) nearest target_world_xy that the leg reaches from the stance sole: in the
    stance sole's frame forward at most max_forward_m, backward at most max_backward_m, and on the swing leg's
    side between min_width_m and max_width_m (the soles never overlap nor cross)."""
    return np.array(_clamp_landing_xy(float(target_world_xy[0]), float(target_world_xy[1]), float(stance_xy[0]),
                                      float(stance_xy[1]), stance_yaw_rad, swing_leg, params))


def _clamp_landing_xy(tx_m: float, ty_m: float, sx_m: float, sy_m: float, stance_yaw_rad: float, swing_leg: str,
                      params: EmergencyStepParams) -> tuple[float, float]:
    """clamp_landing on floats (it runs every tick of a catch)."""
    c, s = math.cos(stance_yaw_rad), math.sin(stance_yaw_rad)
    dx, dy = tx_m - sx_m, ty_m - sy_m
    u, v = c * dx + s * dy, -s * dx + c * dy
    u = min(max(u, -params.max_backward_m), params.max_forward_m)
    side = 1.0 if swing_leg == "lleg" else -1.0  # the left foot lands at +y of the right one
    v = side * min(max(side * v, params.min_width_m), params.max_width_m)
    return sx_m + c * u - s * v, sy_m + s * u + c * v


def landing_for(cp_touchdown_xy, zmp_stance_xy, stance_xy, stance_yaw_rad: float, swing_leg: str,
                params: EmergencyStepParams) -> np.ndarray:
    """The landing sole origin [m] (2,) for the capture point predicted at touchdown: the sole's centre
    landing_offset_m beyond it along its motion (away from the stance ZMP), clamped to the leg's reach
    (clamp_landing)."""
    return np.array(_landing_xy(float(cp_touchdown_xy[0]), float(cp_touchdown_xy[1]), float(zmp_stance_xy[0]),
                                float(zmp_stance_xy[1]), float(stance_xy[0]), float(stance_xy[1]), stance_yaw_rad,
                                swing_leg, params))


def _landing_xy(cx_m: float, cy_m: float, zx_m: float, zy_m: float, sx_m: float, sy_m: float,
                stance_yaw_rad: float, swing_leg: str, params: EmergencyStepParams) -> tuple[float, float]:
    """landing_for on floats (it runs every tick of a catch): capture point at touchdown (cx, cy), stance ZMP
    (zx, zy), stance sole (sx, sy) [m]."""
    mx, my = cx_m - zx_m, cy_m - zy_m
    norm = float(np.hypot(mx, my))  # numpy's hypot, not math's: the floats landing_for always had
    if norm > 1e-9:
        f = params.landing_offset_m / norm
        cx_m, cy_m = cx_m + f * mx, cy_m + f * my
    rect = SOLES[swing_leg]  # the sole's centre in its own frame, turned by the stance yaw (no turning step)
    ox, oy = 0.5 * (rect.front_m - rect.rear_m), 0.5 * (rect.left_m - rect.right_m)
    c, s = math.cos(stance_yaw_rad), math.sin(stance_yaw_rad)
    return _clamp_landing_xy(cx_m - (c * ox - s * oy), cy_m - (s * ox + c * oy), sx_m, sy_m, stance_yaw_rad,
                             swing_leg, params)


# ---------------------------------------------------------------------------------------- one step, planned


def _swing_samples(n_step: int, ratio_after: float) -> int:
    """Samples of a step of n_step samples that swing: the gait generator swings while its sample time
    (i + 1) dt < (1 - ratio_after) T."""
    return int(math.ceil((1.0 - ratio_after) * n_step - 1e-9)) - 1


@functools.lru_cache(maxsize=64)
def cp_weights(a: float, n: int) -> np.ndarray:
    """(n,) weights (a - 1) a^(n - 1 - i) [-] of the ZMP of the n samples i = 0 .. n - 1 in the LIP's capture point
    n samples on: xi_n = a^n xi_0 - sum_i w_i zmp_i (xi+ = a xi - (a - 1) zmp). Per (a, n): a catch asks for the
    same few every tick."""
    w = (a - 1.0) * a ** np.arange(n - 1, -1, -1)
    w.flags.writeable = False
    return w


@functools.lru_cache(maxsize=64)
def zmp_path_weights(n_lift: int, touchdown_k: int, n_step_end: int, n_end: int,
                     n_shift: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The min-jerk ratios [-] of an emergency step's reference ZMP, as (m, 1) columns over the samples of each
    phase: the lift (samples 0 .. min(n_lift, touchdown_k) - 1, start to stance ZMP), the shift after touchdown
    (touchdown_k .. n_step_end - 1, stance ZMP to the landing's) and the final double support (n_step_end ..
    n_end - 1, to the feet's middle). They depend on the timing alone: a re-plan reuses them."""
    lift = min_jerk((np.arange(0, min(n_lift, touchdown_k)) + 1) / n_lift)[:, None]
    shift = min_jerk((np.arange(touchdown_k, n_step_end) + 1 - touchdown_k) / n_shift)[:, None]
    final = min_jerk((np.arange(n_step_end, n_end) + 1 - n_step_end) / max(n_end - n_step_end, 1))[:, None]
    for w in (lift, shift, final):
        w.flags.writeable = False
    return lift, shift, final


@functools.lru_cache(maxsize=64)
def zmp_path_column(n_lift: int, touchdown_k: int, n_step_end: int, n_end: int,
                    n_shift: int) -> tuple[np.ndarray, tuple[int, int, int, int]]:
    """zmp_path_weights end to end, (n_end, 1), with 0 for the samples held on the stance sole, and the four phases'
    sample counts (lift, held, shift, final): every sample's ZMP is start + w (end - start) of its phase."""
    lift, shift, final = zmp_path_weights(n_lift, touchdown_k, n_step_end, n_end, n_shift)
    held = np.zeros((touchdown_k - len(lift), 1))
    column = np.concatenate((lift, held, shift, final))
    column.flags.writeable = False
    return column, (len(lift), len(held), len(shift), len(final))


def _fill_path(out_xy: np.ndarray, k_from: int, lo: int, hi: int, weights: np.ndarray, w0: int, start_xy: np.ndarray,
               end_xy: np.ndarray) -> None:
    """Rows of samples max(lo, k_from) .. hi - 1 of out_xy (row 0: sample k_from) = start + w (end - start), w the
    weights from sample w0 on (numpy's floats of start + w * (end - start), in place)."""
    lo = max(lo, k_from)
    if hi <= lo:
        return
    rows = out_xy[lo - k_from:hi - k_from]
    np.multiply(weights[lo - w0:hi - w0], end_xy - start_xy, out=rows)
    rows += start_xy


class EmergencyStepPlan:
    """One emergency step from the tick it is triggered to standing with the feet apart: the swing leg lands where
    the capture point will be, re-planned from the measured CP until `replan_until_s` before touchdown (or where
    it touched down early); the footsteps for the gait generator, their timing in control ticks, and the
    reference ZMP of every tick: to the stance sole (nearest the CP), held there through the swing, to the capture
    point predicted at touchdown (inside the new support polygon: the CP held there stops), then to the feet's
    middle.

    Sample k counts the gait generator's samples from the plan's start (k = 0: the first one handed out).
    """

    def __init__(self, params: EmergencyStepParams, dt_s: float, stance: Footstep, swing: Footstep,
                 cp_world_xy, zmp_world_xy, omega_1_s: float) -> None:
        if stance.leg == swing.leg:
            raise InvalidCommand(f"stance and swing are both {stance.leg}; give one foot of each leg")
        self.params = params
        self.dt_s = dt_s
        self.stance, self.swing = stance, swing
        self.omega_1_s = float(omega_1_s)
        self.n_lift = max(1, round(params.initial_double_support_s / dt_s))  # the swing's first sample
        n_step = max(2, round(params.step_time_s / dt_s))
        self.n_touchdown = self.n_lift + _swing_samples(n_step, params.double_support_ratio)  # planned touchdown
        self.n_step_end = self.n_lift + n_step
        self.n_end = self.n_step_end + max(1, round(params.final_double_support_s / dt_s))
        self.n_freeze = self.n_touchdown - round(params.replan_until_s / dt_s)
        self.landed_k: int | None = None  # the sample the foot touched down before n_touchdown, if it did
        self.revision = 0  # counts replan and land calls: a re-plan made ahead on a copy is valid for one revision
        self.z_m = stance.z
        self._a = math.exp(self.omega_1_s * self.dt_s)  # the LIP's CP over one tick: xi+ = a xi - (a - 1) zmp
        # the soles' corners and the stance sole shrunk by the margin, as (x, y) pairs: fixed for the plan
        rect = SOLES[swing.leg]
        c, s_ = np.cos(stance.yaw), np.sin(stance.yaw)
        self._stance_corners = SOLES[stance.leg].corners_world((stance.x, stance.y, stance.yaw)).tolist()
        self._swing_corners_turned = (rect.corners_foot() @ np.array([[c, -s_], [s_, c]]).T).tolist()
        self._stance_poly = shrink_polygon_xy(self._stance_corners, params.zmp_margin_m)
        self._zmp_after: tuple | None = None  # (landing, CP at touchdown, its ZMP after touchdown)
        self.zmp_start_xy = np.asarray(zmp_world_xy, dtype=float)[:2].copy()
        cx, cy = np.asarray(cp_world_xy, dtype=float)[:2].tolist()
        self.zmp_stance_xy = np.array(nearest_point_in_convex_polygon_xy(cx, cy, self._stance_poly))
        self._cp_measured = (0, np.asarray(cp_world_xy, dtype=float)[:2].copy())  # (sample, CP [m])
        self.cp_touchdown_xy = self._cp_at(self.n_touchdown)
        self.landing_xy = np.array(self._landing())

    def __repr__(self) -> str:
        return (f"EmergencyStepPlan({self.swing.leg} to {self.landing_xy.round(3).tolist()}; samples "
                f"lift/touchdown/end {self.n_lift}/{self.touchdown_k}/{self.n_end})")

    # ---- what the gait generator walks
    def footsteps(self) -> list[Footstep]:
        """[the stance sole where it is (the initial double support), the swing sole where it lands]."""
        first = self.stance.replaced(step_height_m=0.0, toe_angle_rad=0.0, heel_angle_rad=0.0,
                                     step_time_s=self.n_lift * self.dt_s)
        x, y = self.landing_xy.tolist()
        step = self.swing.replaced(x=x, y=y, z=self.z_m, roll=0.0, pitch=0.0, yaw=self.stance.yaw,
                                   step_height_m=self.params.step_height_m, toe_angle_rad=0.0, heel_angle_rad=0.0,
                                   step_time_s=(self.n_step_end - self.n_lift) * self.dt_s)
        return [first, step]

    def gait_params(self, base: GaitParams) -> GaitParams:
        """The gait's timing for this plan: no double support before the swing, the plan's after it and at the end;
        the trapezoid orbit (its horizontal speed peaks at 4/3 of the mean, the cycloid's at 2: a fast step within
        the joints' speed limit)."""
        return base.replaced(double_support_ratio_before=0.0,
                             double_support_ratio_after=self.params.double_support_ratio,
                             final_double_support_s=(self.n_end - self.n_step_end) * self.dt_s,
                             orbit_type="trapezoid")

    @property
    def touchdown_k(self) -> int:
        """The sample the foot touched (or touches) down."""
        return self.n_touchdown if self.landed_k is None else self.landed_k

    def swinging(self, k: int) -> bool:
        """Sample k is in the swing (the foot in the air as planned, not touched down early)."""
        return self.n_lift <= k < self.n_touchdown and self.landed_k is None

    # ---- re-planning
    def replan(self, k: int, cp_world_xy) -> bool:
        """The capture point measured before sample k: until the touchdown the stance ZMP follows it (the point of
        the sole nearest it: a capture point still inside the sole stays where it is instead of running away from
        a ZMP chosen when it was elsewhere), and until n_freeze the landing too. True when either moved (by more
        than 1 mm)."""
        self.revision += 1
        if k >= self.n_touchdown or self.landed_k is not None:
            return False
        cx, cy = float(cp_world_xy[0]), float(cp_world_xy[1])  # floats: a tick's maths on 2-D points
        zx, zy = nearest_point_in_convex_polygon_xy(cx, cy, self._stance_poly)  # stance_zmp
        ox, oy = self.zmp_stance_xy.tolist()
        moved = float(np.hypot(zx - ox, zy - oy)) > 1e-3
        if moved:
            self.zmp_stance_xy = np.array((zx, zy))
        if k >= self.n_freeze:
            return moved
        self._cp_measured = (k, np.array((cx, cy)))
        self.cp_touchdown_xy = self._cp_at(self.n_touchdown)
        lx, ly = self._landing()
        ox, oy = self.landing_xy.tolist()
        if float(np.hypot(lx - ox, ly - oy)) <= 1e-3:
            return moved
        self.landing_xy = np.array((lx, ly))
        return True

    def replanned(self, k: int, cp_world_xy) -> tuple[EmergencyStepPlan, bool]:
        """replan(k, cp_world_xy) on a copy, this plan unchanged: (the copy, replan's result), for `adopt` later.
        A shallow copy is enough: the plan rebinds what it changes and never writes into its arrays."""
        other = copy.copy(self)
        return other, other.replan(k, cp_world_xy)

    def adopt(self, other: EmergencyStepPlan) -> None:
        """Take the state of `other`, a copy `replanned` made of this plan at its current revision: the same
        attributes, the same floats, as replanning this plan would have given."""
        if other.revision != self.revision + 1:
            raise InvalidState(f"adopt: the copy was replanned from revision {other.revision - 1}, "
                               f"this plan is at {self.revision}")
        self.__dict__.update(other.__dict__)

    def land(self, k: int, landing_world_xy) -> None:
        """The foot touched the ground at sample k (before the planned touchdown) at landing_world_xy [m]."""
        self.revision += 1
        self.cp_touchdown_xy = self._cp_at(k)
        self.landed_k = k
        self.landing_xy = np.asarray(landing_world_xy, dtype=float)[:2].copy()

    def _landing(self) -> tuple[float, float]:
        s = self.stance
        (cx, cy), (zx, zy) = self.cp_touchdown_xy.tolist(), self.zmp_stance_xy.tolist()
        return _landing_xy(cx, cy, zx, zy, s.x, s.y, s.yaw, self.swing.leg, self.params)  # landing_for

    def _cp_at(self, k: int) -> np.ndarray:
        """The LIP's capture point before sample k, from the last one measured, the ZMP following this plan's path
        until touchdown (each sample's ZMP held over its tick: xi+ = a xi - (a - 1) zmp, a = e^(omega dt)) [m]."""
        km, cp = self._cp_measured
        if k <= km:
            return cp.copy()
        a = self._a
        zmp = np.empty((k - km, 2))  # the reference ZMP of samples km .. k - 1: to the stance sole, then there
        zmp[:] = self.zmp_stance_xy
        lift = zmp_path_weights(self.n_lift, self.n_touchdown, self.n_step_end, self.n_end, 1)[0]
        _fill_path(zmp, km, 0, min(self.n_lift, k), lift, 0, self.zmp_start_xy, self.zmp_stance_xy)
        return a ** (k - km) * cp - cp_weights(a, k - km) @ zmp

    # ---- the reference ZMP
    def support_polygon_after(self) -> np.ndarray:
        """(M, 2) [m] the support polygon of the two soles once the foot is down."""
        return np.array(self._support_after_xy())

    def _support_after_xy(self) -> list[tuple[float, float]]:
        """support_polygon_after as (x, y) pairs: the landing sole's corners are its turned corners moved there."""
        x, y = self.landing_xy.tolist()
        return convex_hull_xy(self._stance_corners + [(cx + x, cy + y) for cx, cy in self._swing_corners_turned])

    def zmp_after_touchdown_xy(self) -> np.ndarray:
        """Where the ZMP goes once both feet are down: the capture point predicted at touchdown, inside the support
        polygon shrunk by the margin (the CP held there stops) [m], (2,)."""
        landing, cp = self.landing_xy.tolist(), self.cp_touchdown_xy.tolist()
        cache = self._zmp_after
        if cache is None or cache[0] != landing or cache[1] != cp:  # a stance ZMP's re-plan keeps both
            hull, margin = self._support_after_xy(), self.params.zmp_margin_m
            if slack_in_shrunk_polygon_m(*cp, hull, margin) > 1e-9:  # inside for sure: the CP itself, as exactly
                zmp = cp
            else:  # near or past an edge: the exact shrunk polygon's nearest point
                zmp = nearest_point_in_convex_polygon_xy(*cp, shrink_polygon_xy(hull, margin))
            cache = self._zmp_after = (landing, cp, np.array(zmp))
        return cache[2].copy()

    def feet_middle_xy(self) -> np.ndarray:
        """The final ZMP: midway between the two soles' origins [m], (2,) (the gait's end without ZMP offsets)."""
        x, y = self.landing_xy.tolist()
        return np.array((0.5 * (self.stance.x + x), 0.5 * (self.stance.y + y)))

    def zmp(self, k_from: int) -> np.ndarray:
        """(n_end - k_from, 3) reference ZMP [m] of samples k_from .. n_end - 1: affine in the four points (start,
        stance, after touchdown, feet's middle) with weights of the timing alone (zmp_path_weights)."""
        td, n_lift, n_step_end, n_end = self.touchdown_k, self.n_lift, self.n_step_end, self.n_end
        n_shift = min(max(1, round(self.params.zmp_shift_s / self.dt_s)), max(n_step_end - td, 1))
        column, counts = zmp_path_column(n_lift, td, n_step_end, n_end, n_shift)
        z = self.z_m
        (x0, y0), (xs, ys) = self.zmp_start_xy.tolist(), self.zmp_stance_xy.tolist()
        (xl, yl), (xm, ym) = self.zmp_after_touchdown_xy().tolist(), self.feet_middle_xy().tolist()
        # the phases: to the stance sole, held there, to the capture point once the foot is down, to the feet's middle
        start = np.array(((x0, y0, z), (xs, ys, z), (xs, ys, z), (xl, yl, z)))
        end = np.array(((xs, ys, z), (xs, ys, z), (xl, yl, z), (xm, ym, z)))
        left, rows = k_from, []  # the phases' samples from k_from on
        for c in counts:
            rows.append(max(c - left, 0))
            left = max(left - c, 0)
        out = np.repeat(start, rows, axis=0)
        out += column[k_from:] * np.repeat(end - start, rows, axis=0)
        return out
