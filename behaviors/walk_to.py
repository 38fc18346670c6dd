"""`walk_to`: walk to (x, y, theta) of the world by a goPos from where the feet are, and another for what that
walk left, as leg odometry measures where the feet frame F ended (controller.balance.leg_odometry: the steps
land a little off their plan, 2 % long here)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from behaviors.base import NOTHING, Behavior, BehaviorParams, Context, Output
from behaviors.preview import MotionPreview, Predicted, feet_moved, last_soles, mid_of
from behaviors.servo import rot_z, wrap_rad
from controller.operation.points import OperationView

SETTLE_S = 2.0  # [s] allowed beyond the planned walk (the last double support, the stop)
WALK_START_S = 1.0  # [s] the walking flag rises within this of goPos (or the plan was empty)


@dataclass(frozen=True)
class WalkToParams(BehaviorParams):
    x_m: float = field(default=0.0, metadata={"unit": "m", "min": -20.0, "max": 20.0, "doc": "goal, world x"})
    y_m: float = field(default=0.0, metadata={"unit": "m", "min": -20.0, "max": 20.0, "doc": "goal, world y"})
    theta_deg: float = field(default=0.0, metadata={"unit": "deg", "min": -180.0, "max": 180.0,
                                                    "doc": "goal heading, world yaw"})
    tolerance_m: float = field(default=0.03, metadata={"unit": "m", "min": 0.005, "max": 0.5,
                                                       "doc": "succeeds when the feet frame ends this close"})
    tolerance_deg: float = field(default=3.0, metadata={"unit": "deg", "min": 0.5, "max": 45.0,
                                                        "doc": "and its heading this close"})
    corrections: int = field(default=2, metadata={"unit": "-", "min": 0, "max": 5,
                                                  "doc": "further goPos for what a walk left beyond the tolerances"})


class WalkTo(Behavior):
    name = "walk_to"
    Params = WalkToParams
    summary = "Walk to (x, y, theta) in the world (leg odometry): a goPos, then corrections for what it left"

    def points(self) -> tuple[str, ...]:
        return ("walk",)

    def _errors(self, view: OperationView) -> tuple[np.ndarray, float]:
        """Goal relative to the feet frame F: (dx, dy) in F [m], dtheta [rad]."""
        p = self.params
        d_world = np.array([p.x_m, p.y_m, 0.0]) - np.asarray(view.feet_p_world_m, dtype=float)
        d_world[2] = 0.0
        d_feet = rot_z(view.feet_yaw_rad).T @ d_world
        return d_feet[:2], wrap_rad(math.radians(p.theta_deg) - view.feet_yaw_rad)

    def start(self, ctx: Context) -> None:
        d, dtheta = self._errors(ctx.require_view())
        self.distance0_m = float(np.linalg.norm(d))
        self.plan_s = 0.0
        self.corrections_made = 0
        self._go(ctx, d, dtheta)

    def preview(self, ctx: Context, predicted: Predicted, into: MotionPreview, phase: str) -> Predicted:
        """The first goPos's footsteps, as `start` would ask for them (the corrections depend on where it lands)."""
        d, dtheta = self._errors(predicted.view)
        steps = ctx.commands.plan_go_pos(float(d[0]), float(d[1]), float(dtheta), predicted.soles)
        into.footsteps.extend((phase, s) for s in steps)
        soles = last_soles(steps, predicted.soles)
        p = self.params
        x, y, yaw = mid_of(*soles) if soles is not None else (p.x_m, p.y_m, math.radians(p.theta_deg))
        return Predicted(feet_moved(predicted.view, x, y, yaw), soles)

    def _go(self, ctx: Context, d: np.ndarray, dtheta: float) -> None:
        """One goPos to the goal as the feet frame sees it now."""
        self.walk_plan_s = float(ctx.commands.go_pos(float(d[0]), float(d[1]), float(dtheta)))
        self.plan_version = ctx.commands.walk_plan_version()
        self.plan_s += self.walk_plan_s
        self.walk_started_s = ctx.elapsed_s
        self.seen_walking = False

    def nominal_duration_s(self) -> float:  # each walk and its settling
        return getattr(self, "plan_s", 0.0) + SETTLE_S * (1 + getattr(self, "corrections_made", 0))

    def progress(self, ctx: Context) -> float:
        if ctx.view is None or self.distance0_m == 0.0:
            return min(1.0, ctx.elapsed_s / self.nominal_duration_s())
        d, _ = self._errors(ctx.view)
        return max(0.0, min(1.0, 1.0 - float(np.linalg.norm(d)) / self.distance0_m))

    def step(self, ctx: Context) -> Output:
        view = ctx.require_view()
        self.seen_walking = self.seen_walking or view.walking
        since_s = ctx.elapsed_s - self.walk_started_s
        if view.walking or (not self.seen_walking and since_s < min(self.walk_plan_s, WALK_START_S)):
            return NOTHING
        d, dtheta = self._errors(view)
        dist, dyaw_deg = float(np.linalg.norm(d)), math.degrees(abs(dtheta))
        p = self.params
        arrived = dist <= p.tolerance_m and dyaw_deg <= p.tolerance_deg
        if not arrived and self.corrections_made < p.corrections:
            self.corrections_made += 1
            self._go(ctx, d, dtheta)
            return NOTHING
        result = {"error_m": round(dist, 4), "error_deg": round(dyaw_deg, 3), "corrections": self.corrections_made,
                  "feet_world": [round(float(view.feet_p_world_m[0]), 4), round(float(view.feet_p_world_m[1]), 4),
                                 round(math.degrees(view.feet_yaw_rad), 3)]}
        if arrived:
            return self.succeed(f"arrived within {dist * 100:.1f} cm and {dyaw_deg:.1f} deg"
                                + (f" ({self.corrections_made} correction{'s' if self.corrections_made > 1 else ''})"
                                   if self.corrections_made else ""), **result)
        why = ("its walk was re-planned by another command meanwhile (goPos, goVelocity, footsteps, a catching "
               "step or goStop)" if ctx.commands.walk_plan_version() != self.plan_version else
               "the footsteps landed as planned: the walk's accuracy limit")  # (soak seed 10114: an operator's goPos)
        return self.fail(f"stopped {dist * 100:.1f} cm and {dyaw_deg:.1f} deg from the goal "
                         f"(tolerance {p.tolerance_m * 100:g} cm, {p.tolerance_deg:g} deg) after "
                         f"{self.corrections_made} correction(s): {why}", **result)

    def stop(self, ctx: Context) -> None:
        ctx.commands.walk_stop()
