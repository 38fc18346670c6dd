"""`follow_arc`: move a hand along a circle about a vertical axis (a door's hinge) in the feet frame F, turning
it with the circle, by a minimum-jerk angle profile. Feed-forward like `reach` ([OP] V-A): the operator's motion
at the same point adds (Eq. 5). A held door handle makes the hand's path the hinge's circle."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from behaviors.base import NOTHING, Behavior, BehaviorParams, Context, Output, held_by_collision
from behaviors.servo import MinJerkMove, min_jerk_duration_s, rot_z
from controller.interpolation.hoff_arbib import min_jerk
from controller.operation.points import Twist


def arc_point(p0, centre, angle_rad: float) -> np.ndarray:
    """(3,) the point p0 [m] turned by `angle_rad` about the vertical axis through `centre` (x, y) [m]."""
    p0 = np.asarray(p0, dtype=float)
    c = np.array([centre[0], centre[1], p0[2]])
    return c + rot_z(angle_rad) @ (p0 - c)


def arc_twist(p0, centre, angle0_rad: float, angle1_rad: float, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """(linear [m/s], angular [rad/s]) that take a point on the arc from angle0 to angle1 in one tick of dt_s
    (the chord: integrated, the point stays on the circle)."""
    if dt_s <= 0.0:
        raise ValueError(f"dt_s must be > 0, got {dt_s}")
    linear = (arc_point(p0, centre, angle1_rad) - arc_point(p0, centre, angle0_rad)) / dt_s
    return linear, np.array([0.0, 0.0, (angle1_rad - angle0_rad) / dt_s])


@dataclass(frozen=True)
class FollowArcParams(BehaviorParams):
    hand: str = field(default="rhand", metadata={"unit": "-", "choices": ("rhand", "lhand"), "doc": "which hand"})
    centre_x_m: float = field(default=0.56, metadata={"unit": "m", "min": -2.0, "max": 2.0,
                                                      "doc": "the axis (vertical), feet frame x"})
    centre_y_m: float = field(default=-0.35, metadata={"unit": "m", "min": -2.0, "max": 2.0, "doc": "feet frame y"})
    angle_deg: float = field(default=45.0, metadata={"unit": "deg", "min": -150.0, "max": 150.0,
                                                     "doc": "how far to turn about the axis (+: counter-clockwise "
                                                            "seen from above)"})
    speed_deg_s: float = field(default=10.0, metadata={"unit": "deg/s", "min": 1.0, "max": 45.0,
                                                       "doc": "the largest turning rate"})
    tolerance_m: float = field(default=0.03, metadata={"unit": "m", "min": 0.001, "max": 0.2,
                                                       "doc": "succeeds when the hand ends this close to the arc's "
                                                              "end (a held door pulls back)"})


class FollowArc(MinJerkMove, Behavior):
    name = "follow_arc"
    Params = FollowArcParams
    summary = "A hand along a circle about a vertical axis in the feet frame, turning with it (a door's arc)"

    def points(self) -> tuple[str, ...]:
        return (self.params.hand,)

    def start(self, ctx: Context) -> None:
        p = self.params
        self.p0 = np.array(ctx.require_view().points[p.hand].p_feet_m, dtype=float)
        self.centre = (p.centre_x_m, p.centre_y_m)
        self.angle_rad = math.radians(p.angle_deg)
        self.plan_s = min_jerk_duration_s(self.angle_rad, math.radians(p.speed_deg_s), ctx.dt_s)

    def step(self, ctx: Context) -> Output:
        t, dt = ctx.elapsed_s, ctx.dt_s
        if t < self.plan_s:
            a0 = self.angle_rad * float(min_jerk(t / self.plan_s))
            a1 = self.angle_rad * float(min_jerk(min(t + dt, self.plan_s) / self.plan_s))
            linear, angular = arc_twist(self.p0, self.centre, a0, a1, dt)
            return Output({self.params.hand: Twist.of(linear, angular)})
        if not self.settled(t):
            return NOTHING
        view = ctx.require_view()
        end = arc_point(self.p0, self.centre, self.angle_rad)
        at = np.asarray(view.points[self.params.hand].p_feet_m, dtype=float)
        error = float(np.linalg.norm(at - end))
        result = {"error_m": round(error, 5), "p_feet_m": [round(float(v), 5) for v in at]}
        if view.collision_pairs:
            return self.fail(held_by_collision(view), **result)
        if error <= self.params.tolerance_m:
            return self.succeed(f"{self.params.hand} turned {self.params.angle_deg:.0f} deg about the axis, "
                                f"{error * 1e3:.1f} mm from the arc's end", **result)
        return self.fail(f"{self.params.hand} ended {error * 1e3:.1f} mm from the arc's end (the IK limited it, "
                         "or what it holds did not follow)", **result)
