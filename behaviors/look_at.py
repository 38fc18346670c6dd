"""`look_at`: turn the gaze (head point: pitch and yaw in the feet frame) toward a point of the world."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from behaviors.base import Behavior, BehaviorParams, Context, Output
from behaviors.servo import rot_z, toward, wrap_rad
from controller.operation.points import OperationView, Twist

GAIN_1_S = 3.0  # [1/s]


@dataclass(frozen=True)
class LookAtParams(BehaviorParams):
    x_m: float = field(default=1.0, metadata={"unit": "m", "min": -20.0, "max": 20.0, "doc": "target, world x"})
    y_m: float = field(default=0.0, metadata={"unit": "m", "min": -20.0, "max": 20.0, "doc": "target, world y"})
    z_m: float = field(default=1.0, metadata={"unit": "m", "min": -5.0, "max": 10.0, "doc": "target, world z"})
    rate_deg_s: float = field(default=30.0, metadata={"unit": "deg/s", "min": 1.0, "max": 90.0,
                                                      "doc": "largest gaze rate"})
    tolerance_deg: float = field(default=0.5, metadata={"unit": "deg", "min": 0.05, "max": 10.0,
                                                        "doc": "done when the gaze is this close"})


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
        self.error0_rad = float(np.abs(self._error(ctx.require_view())).max())

    def nominal_duration_s(self) -> float:
        return getattr(self, "error0_rad", math.pi) / math.radians(self.params.rate_deg_s) + 1.5

    def progress(self, ctx: Context) -> float:
        if ctx.view is None or self.error0_rad == 0.0:
            return 1.0
        return max(0.0, min(1.0, 1.0 - float(np.abs(self._error(ctx.view)).max()) / self.error0_rad))

    def step(self, ctx: Context) -> Output:
        view = ctx.require_view()
        error = self._error(view)
        if float(np.abs(error).max()) <= math.radians(self.params.tolerance_deg):
            return self.succeed("looking at the target", gaze_deg=[round(math.degrees(a), 3) for a in view.gaze_rad])
        rate = toward(error, GAIN_1_S, math.radians(self.params.rate_deg_s))
        return Output({"head": Twist.of((0.0, 0.0, 0.0), (0.0, rate[0], rate[1]))})
