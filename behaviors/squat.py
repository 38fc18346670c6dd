"""`squat`: the waist down by a height h (or up, h < 0) along a minimum-jerk plan at a limited peak speed,
through the waist point. Feed-forward ([OP] V-A): the operator's waist motion adds to it; at the end of the
plan the height is checked against the goal."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from behaviors.base import NOTHING, Behavior, BehaviorParams, Context, Output
from behaviors.preview import MotionPreview, Predicted, line_in_world, point_moved
from behaviors.servo import min_jerk_duration_s, min_jerk_rate
from controller.interpolation.hoff_arbib import min_jerk
from controller.operation.points import Twist

SETTLE_S = 0.3  # [s] after the plan, for the IK and the AutoBalancer to follow before the check


@dataclass(frozen=True)
class SquatParams(BehaviorParams):
    depth_m: float = field(default=0.15, metadata={"unit": "m", "min": -0.05, "max": 0.25,
                                                   "doc": "how far the waist goes down (negative: up)"})
    speed_m_s: float = field(default=0.05, metadata={"unit": "m/s", "min": 0.005, "max": 0.2,
                                                     "doc": "peak waist speed"})
    tolerance_m: float = field(default=0.005, metadata={"unit": "m", "min": 0.0005, "max": 0.05,
                                                        "doc": "succeeds when the waist ends this close"})


class Squat(Behavior):
    name = "squat"
    Params = SquatParams
    summary = "Waist down by depth_m (the waist point's height, feet frame; the operator's motion adds)"

    def points(self) -> tuple[str, ...]:
        return ("waist",)

    def nominal_duration_s(self) -> float:
        return getattr(self, "plan_s", 2.0 * abs(self.params.depth_m) / self.params.speed_m_s) + SETTLE_S + 0.5

    def preview(self, ctx: Context, predicted: Predicted, into: MotionPreview, phase: str) -> Predicted:
        """The waist's vertical line down by depth_m (the plan `start` makes)."""
        waist = predicted.view.points["waist"]
        end = waist.p_feet_m - np.array((0.0, 0.0, self.params.depth_m))
        into.hand_paths.append((phase, "waist", line_in_world(predicted.view, waist.p_feet_m, end)))
        view = point_moved(predicted.view, "waist", end, waist.R_feet_point)
        view = dataclasses.replace(view, waist_height_m=predicted.view.waist_height_m - self.params.depth_m)
        return Predicted(view, predicted.soles)

    def start(self, ctx: Context) -> None:
        self.h0_m = ctx.require_view().waist_height_m
        self.goal_m = self.h0_m - self.params.depth_m
        self.plan_s = min_jerk_duration_s(self.params.depth_m, self.params.speed_m_s, ctx.dt_s)

    def progress(self, ctx: Context) -> float:
        return float(min_jerk(ctx.elapsed_s / self.plan_s))

    def step(self, ctx: Context) -> Output:
        t = ctx.elapsed_s
        if t < self.plan_s:
            return Output({"waist": Twist.of((0.0, 0.0, -self.params.depth_m * min_jerk_rate(t, ctx.dt_s,
                                                                                             self.plan_s)))})
        if t < self.plan_s + SETTLE_S:
            return NOTHING
        h = ctx.require_view().waist_height_m
        error = h - self.goal_m
        result = {"waist_height_m": round(h, 4), "down_m": round(self.h0_m - h, 4)}
        if abs(error) <= self.params.tolerance_m:
            return self.succeed(f"waist at {h:.3f} m ({self.h0_m - h:+.3f} m down)", **result)
        return self.fail(f"the waist ended {error * 1000:+.1f} mm from its goal (the IK limited it, or the "
                         "operator moved it)", **result)
