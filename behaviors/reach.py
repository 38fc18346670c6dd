"""`reach`: move a hand to a pose given in the feet frame F along a minimum-jerk straight line (the rotation
about one fixed axis), through the hand's operational point. The behaviour's twist is the plan's own rate
(feed-forward, [OP] V-A): whatever the operator adds at the same point is summed and stays (Eq. 5), so
"reach, and a bit higher" is the reach plus the operator's offset. At the end of the plan the hand is
checked against the goal."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from behaviors.base import NOTHING, Behavior, BehaviorParams, Context, Output, held_by_collision
from behaviors.preview import MotionPreview, Predicted, line_in_world, point_moved
from behaviors.servo import MinJerkMove, min_jerk_duration_s, min_jerk_rate, rotation_vector
from controller.kinematics.rotations import matrix_to_rpy, rpy_to_matrix
from controller.operation.points import OperationView, Twist


@dataclass(frozen=True)
class ReachParams(BehaviorParams):
    hand: str = field(default="rhand", metadata={"unit": "-", "choices": ("rhand", "lhand"), "doc": "which hand"})
    x_m: float = field(default=0.3, metadata={"unit": "m", "min": -1.0, "max": 1.5, "doc": "goal, feet frame x"})
    y_m: float = field(default=-0.3, metadata={"unit": "m", "min": -1.5, "max": 1.5, "doc": "goal, feet frame y"})
    z_m: float = field(default=0.7, metadata={"unit": "m", "min": 0.0, "max": 2.0, "doc": "goal, feet frame z"})
    keep_orientation: bool = field(default=True, metadata={"unit": "-", "doc": "true: the hand keeps its "
                                                           "orientation and roll/pitch/yaw are ignored"})
    roll_deg: float = field(default=0.0, metadata={"unit": "deg", "min": -180.0, "max": 180.0})
    pitch_deg: float = field(default=0.0, metadata={"unit": "deg", "min": -180.0, "max": 180.0})
    yaw_deg: float = field(default=0.0, metadata={"unit": "deg", "min": -180.0, "max": 180.0})
    speed_m_s: float = field(default=0.1, metadata={"unit": "m/s", "min": 0.01, "max": 0.3,
                                                    "doc": "largest hand speed along the plan"})
    angular_speed_deg_s: float = field(default=30.0, metadata={"unit": "deg/s", "min": 1.0, "max": 90.0})
    tolerance_m: float = field(default=0.005, metadata={"unit": "m", "min": 0.0005, "max": 0.1,
                                                        "doc": "succeeds when the plan ends this close"})
    tolerance_deg: float = field(default=2.0, metadata={"unit": "deg", "min": 0.1, "max": 20.0})


class Reach(MinJerkMove, Behavior):
    name = "reach"
    Params = ReachParams
    summary = "A hand to a pose in the feet frame (minimum-jerk line; the operator's motion adds to it)"

    def points(self) -> tuple[str, ...]:
        return (self.params.hand,)

    def _errors(self, view: OperationView) -> tuple[np.ndarray, np.ndarray]:
        pose = view.points[self.params.hand]
        p = self.params
        e_p = np.array([p.x_m, p.y_m, p.z_m]) - pose.p_feet_m
        R_goal = self.R_goal if self.R_goal is not None else self.R0
        return e_p, rotation_vector(pose.R_feet_point, R_goal)

    def _plan_from(self, view: OperationView) -> None:
        """The whole move from where the hand is in `view`: its start orientation, goal orientation, and the
        position and rotation to go (F)."""
        p = self.params
        self.R0 = np.array(view.points[p.hand].R_feet_point)
        self.R_goal = None if p.keep_orientation else rpy_to_matrix(np.radians([p.roll_deg, p.pitch_deg, p.yaw_deg]))
        self.dp_m, self.dw_rad = self._errors(view)

    def preview(self, ctx: Context, predicted: Predicted, into: MotionPreview, phase: str) -> Predicted:
        """The hand's straight line (the plan `start` makes), and the hand at its goal."""
        self._plan_from(predicted.view)
        p0 = predicted.view.points[self.params.hand].p_feet_m
        into.hand_paths.append((phase, self.params.hand, line_in_world(predicted.view, p0, p0 + self.dp_m)))
        R_end = self.R_goal if self.R_goal is not None else self.R0
        view = point_moved(predicted.view, self.params.hand, p0 + self.dp_m, R_end)
        return Predicted(view, predicted.soles)

    def start(self, ctx: Context) -> None:
        p = self.params
        self._plan_from(ctx.require_view())  # the whole move, in F
        self.plan_s = max(min_jerk_duration_s(float(np.linalg.norm(self.dp_m)), p.speed_m_s, ctx.dt_s),
                          min_jerk_duration_s(float(np.linalg.norm(self.dw_rad)), math.radians(p.angular_speed_deg_s),
                                              ctx.dt_s))

    def step(self, ctx: Context) -> Output:
        t, dt = ctx.elapsed_s, ctx.dt_s
        if t < self.plan_s:
            rate = min_jerk_rate(t, dt, self.plan_s)  # [1/s], sums to 1
            return Output({self.params.hand: Twist.of(self.dp_m * rate, self.dw_rad * rate)})
        if not self.settled(t):
            return NOTHING
        view = ctx.require_view()
        e_p, e_R = self._errors(view)
        dist, angle = float(np.linalg.norm(e_p)), math.degrees(float(np.linalg.norm(e_R)))
        p = self.params
        result = {"error_m": round(dist, 5), "error_deg": round(angle, 3),
                  "p_feet_m": [round(float(v), 5) for v in view.points[p.hand].p_feet_m]}
        if view.collision_pairs:
            return self.fail(held_by_collision(view), **result)
        if dist <= p.tolerance_m and angle <= p.tolerance_deg:
            return self.succeed(f"{p.hand} within {dist * 1000:.1f} mm and {angle:.2f} deg of the goal", **result)
        return self.fail(f"{p.hand} ended {dist * 1000:.1f} mm and {angle:.1f} deg from the goal (the IK limited "
                         "it, or the operator moved it)", **result)


def reach_pose(hand: str, p_feet, R_feet=None, speed_m_s: float = 0.1, tolerance_m: float = 0.01,
               tolerance_deg: float = 3.0) -> Reach:
    """A `reach` of `hand` to `p_feet` [m, F], to the orientation `R_feet` (3, 3) or keeping its own (None): the
    step a plan yields for each of its hand poses."""
    kw = {}
    if R_feet is not None:
        roll, pitch, yaw = np.degrees(matrix_to_rpy(R_feet))
        kw = {"keep_orientation": False, "roll_deg": float(roll), "pitch_deg": float(pitch), "yaw_deg": float(yaw)}
    return Reach(ReachParams(hand=hand, x_m=float(p_feet[0]), y_m=float(p_feet[1]), z_m=float(p_feet[2]),
                             speed_m_s=speed_m_s, tolerance_m=tolerance_m, tolerance_deg=tolerance_deg, **kw))
