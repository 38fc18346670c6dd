"""`reach`: move a hand to a pose given in the feet frame F, at a limited linear and angular speed, through
the hand's operational point (the whole-body IK keeps the balance)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from behaviors.base import Behavior, BehaviorParams, Context, Output
from behaviors.servo import rotation_vector, toward
from controller.kinematics.rotations import rpy_to_matrix
from controller.operation.points import OperationView, Twist

GAIN_1_S = 2.0  # [1/s]


@dataclass(frozen=True)
class ReachParams(BehaviorParams):
    hand: str = field(default="rhand", metadata={"unit": "-", "choices": ("rhand", "lhand"), "doc": "which hand"})
    x_m: float = field(default=0.35, metadata={"unit": "m", "min": -1.0, "max": 1.5, "doc": "goal, feet frame x"})
    y_m: float = field(default=-0.25, metadata={"unit": "m", "min": -1.5, "max": 1.5, "doc": "goal, feet frame y"})
    z_m: float = field(default=0.9, metadata={"unit": "m", "min": 0.0, "max": 2.0, "doc": "goal, feet frame z"})
    keep_orientation: bool = field(default=True, metadata={"unit": "-", "doc": "true: the hand keeps its "
                                                           "orientation and roll/pitch/yaw are ignored"})
    roll_deg: float = field(default=0.0, metadata={"unit": "deg", "min": -180.0, "max": 180.0})
    pitch_deg: float = field(default=0.0, metadata={"unit": "deg", "min": -180.0, "max": 180.0})
    yaw_deg: float = field(default=0.0, metadata={"unit": "deg", "min": -180.0, "max": 180.0})
    speed_m_s: float = field(default=0.1, metadata={"unit": "m/s", "min": 0.01, "max": 0.3,
                                                    "doc": "largest hand speed"})
    angular_speed_deg_s: float = field(default=30.0, metadata={"unit": "deg/s", "min": 1.0, "max": 90.0})
    tolerance_m: float = field(default=0.003, metadata={"unit": "m", "min": 0.0005, "max": 0.05})
    tolerance_deg: float = field(default=1.0, metadata={"unit": "deg", "min": 0.1, "max": 10.0})


class Reach(Behavior):
    name = "reach"
    Params = ReachParams
    summary = "A hand to a pose in the feet frame (position, and optionally roll/pitch/yaw)"

    def points(self) -> tuple[str, ...]:
        return (self.params.hand,)

    def _errors(self, view: OperationView) -> tuple[np.ndarray, np.ndarray]:
        pose = view.points[self.params.hand]
        p = self.params
        e_p = np.array([p.x_m, p.y_m, p.z_m]) - pose.p_feet_m
        e_R = rotation_vector(pose.R_feet_point, self.R_goal) if self.R_goal is not None else np.zeros(3)
        return e_p, e_R

    def start(self, ctx: Context) -> None:
        p = self.params
        self.R_goal = None if p.keep_orientation else rpy_to_matrix(np.radians([p.roll_deg, p.pitch_deg, p.yaw_deg]))
        e_p, e_R = self._errors(ctx.require_view())
        self.distance0_m, self.angle0_rad = float(np.linalg.norm(e_p)), float(np.linalg.norm(e_R))

    def nominal_duration_s(self) -> float:
        p = self.params
        linear = getattr(self, "distance0_m", 1.0) / p.speed_m_s
        angular = getattr(self, "angle0_rad", 0.0) / math.radians(p.angular_speed_deg_s)
        return max(linear, angular) + 1.5

    def progress(self, ctx: Context) -> float:
        if ctx.view is None:
            return 0.0
        e_p, e_R = self._errors(ctx.view)
        done = [1.0 - float(np.linalg.norm(e)) / e0 for e, e0 in ((e_p, self.distance0_m), (e_R, self.angle0_rad))
                if e0 > 0.0]
        return max(0.0, min(1.0, min(done))) if done else 1.0

    def step(self, ctx: Context) -> Output:
        view = ctx.require_view()
        e_p, e_R = self._errors(view)
        dist, angle = float(np.linalg.norm(e_p)), float(np.linalg.norm(e_R))
        p = self.params
        if dist <= p.tolerance_m and angle <= math.radians(p.tolerance_deg):
            pos = view.points[p.hand].p_feet_m
            return self.succeed(f"{p.hand} within {dist * 1000:.1f} mm and {math.degrees(angle):.2f} deg",
                                error_m=round(dist, 5), error_deg=round(math.degrees(angle), 3),
                                p_feet_m=[round(float(v), 5) for v in pos])
        v = toward(e_p, GAIN_1_S, p.speed_m_s)
        w = toward(e_R, GAIN_1_S, math.radians(p.angular_speed_deg_s))
        return Output({p.hand: Twist.of(v, w)})
