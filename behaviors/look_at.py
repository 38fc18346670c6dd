"""`look_at`: turn the gaze (head point: pitch and yaw in the feet frame) toward a point of the world along a
minimum-jerk plan at a limited peak rate. Feed-forward ([OP] V-A): the operator's head motion adds to it;
at the end of the plan the gaze is checked against the target."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from behaviors.base import NOTHING, Behavior, BehaviorParams, Context, Output, held_by_collision
from behaviors.servo import min_jerk_duration_s, min_jerk_rate, rot_z, wrap_rad
from controller.interpolation.hoff_arbib import min_jerk
from controller.operation.points import OperationView, Twist

SETTLE_S = 0.2  # [s] after the plan, for the IK to follow before the check


@dataclass(frozen=True)
class LookAtParams(BehaviorParams):
    # "place": a named place (behaviors.places) may give these three, e.g. `look_at table` in the command box
    x_m: float = field(default=1.0, metadata={"unit": "m", "min": -20.0, "max": 20.0, "doc": "target, world x",
                                              "place": "x"})
    y_m: float = field(default=0.0, metadata={"unit": "m", "min": -20.0, "max": 20.0, "doc": "target, world y",
                                              "place": "y"})
    z_m: float = field(default=1.0, metadata={"unit": "m", "min": -5.0, "max": 10.0, "doc": "target, world z",
                                              "place": "z"})
    rate_deg_s: float = field(default=30.0, metadata={"unit": "deg/s", "min": 1.0, "max": 90.0,
                                                      "doc": "peak gaze rate"})
    tolerance_deg: float = field(default=1.0, metadata={"unit": "deg", "min": 0.05, "max": 10.0,
                                                        "doc": "succeeds when the gaze ends this close"})


def gaze_to(view: OperationView, target_world_m: np.ndarray) -> tuple[float, float]:
    """(pitch, yaw) [rad] in the feet frame F of the line from the gaze origin to the target; pitch > 0 down."""
    d_world = np.asarray(target_world_m, dtype=float) - view.points["head"].p_world_m
    d_feet = rot_z(view.feet_yaw_rad).T @ d_world
    return math.atan2(-d_feet[2], math.hypot(d_feet[0], d_feet[1])), math.atan2(d_feet[1], d_feet[0])


class LookAt(Behavior):
    name = "look_at"
    Params = LookAtParams
    summary = "Head toward a world point (x_m, y_m, z_m)"

    def points(self) -> tuple[str, ...]:
        return ("head",)

    def _error(self, view: OperationView) -> np.ndarray:
        p = self.params
        pitch, yaw = gaze_to(view, np.array([p.x_m, p.y_m, p.z_m]))
        return np.array([pitch - view.gaze_rad[0], wrap_rad(yaw - view.gaze_rad[1])])

    def start(self, ctx: Context) -> None:
        self.turn_rad = self._error(ctx.require_view())  # (pitch, yaw) to turn
        self.plan_s = min_jerk_duration_s(float(np.abs(self.turn_rad).max()), math.radians(self.params.rate_deg_s),
                                          ctx.dt_s)

    def nominal_duration_s(self) -> float:
        return getattr(self, "plan_s", 2.0 * math.pi / math.radians(self.params.rate_deg_s)) + SETTLE_S + 0.5

    def progress(self, ctx: Context) -> float:
        return float(min_jerk(ctx.elapsed_s / self.plan_s))

    def step(self, ctx: Context) -> Output:
        t = ctx.elapsed_s
        if t < self.plan_s:
            rate = self.turn_rad * min_jerk_rate(t, ctx.dt_s, self.plan_s)
            return Output({"head": Twist.of((0.0, 0.0, 0.0), (0.0, rate[0], rate[1]))})
        if t < self.plan_s + SETTLE_S:
            return NOTHING
        view = ctx.require_view()
        error_deg = math.degrees(float(np.abs(self._error(view)).max()))
        result = {"gaze_deg": [round(math.degrees(a), 3) for a in view.gaze_rad], "error_deg": round(error_deg, 3)}
        if view.collision_pairs:
            return self.fail(held_by_collision(view), **result)
        if error_deg <= self.params.tolerance_deg:
            return self.succeed(f"looking at the target ({error_deg:.2f} deg off)", **result)
        return self.fail(f"the gaze ended {error_deg:.1f} deg off the target (the IK limited it, or the operator "
                         "moved it)", **result)
