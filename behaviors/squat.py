"""`squat`: the waist down by a height h (or up, h < 0) at a limited speed, through the waist point."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from behaviors.base import Behavior, BehaviorParams, Context, Output
from behaviors.servo import toward
from controller.operation.points import Twist

GAIN_1_S = 2.0  # [1/s] proportional approach near the goal


@dataclass(frozen=True)
class SquatParams(BehaviorParams):
    depth_m: float = field(default=0.15, metadata={"unit": "m", "min": -0.05, "max": 0.25,
                                                   "doc": "how far the waist goes down (negative: up)"})
    speed_m_s: float = field(default=0.05, metadata={"unit": "m/s", "min": 0.005, "max": 0.2,
                                                     "doc": "largest waist speed"})
    tolerance_m: float = field(default=0.003, metadata={"unit": "m", "min": 0.0005, "max": 0.05,
                                                        "doc": "done when the waist height is this close"})


class Squat(Behavior):
    name = "squat"
    Params = SquatParams
    summary = "Waist down by depth_m (the waist point's height, feet frame)"

    def points(self) -> tuple[str, ...]:
        return ("waist",)

    def nominal_duration_s(self) -> float:
        p = self.params
        return abs(p.depth_m) / p.speed_m_s + 1.5

    def start(self, ctx: Context) -> None:
        self.h0_m = ctx.require_view().waist_height_m
        self.goal_m = self.h0_m - self.params.depth_m

    def progress(self, ctx: Context) -> float:
        if self.params.depth_m == 0.0 or ctx.view is None:
            return 1.0
        return max(0.0, min(1.0, (self.h0_m - ctx.view.waist_height_m) / self.params.depth_m))

    def step(self, ctx: Context) -> Output:
        h = ctx.require_view().waist_height_m
        error = self.goal_m - h
        if abs(error) <= self.params.tolerance_m:
            return self.succeed(f"waist at {h:.3f} m ({self.h0_m - h:+.3f} m down)", waist_height_m=round(h, 4))
        vz = float(toward(np.array([error]), GAIN_1_S, self.params.speed_m_s)[0])
        return Output({"waist": Twist.of((0.0, 0.0, vz))})
