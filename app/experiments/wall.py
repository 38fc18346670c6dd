"""[MLC] IV-C 1, Fig. 8-10: hands pushed into a rigid wall (scene `wall`), ImpedanceController off."""

from __future__ import annotations

import math

import numpy as np

from app.experiments.common import Event, Experiment, Rig, move_hands, pose_with
from controller.interpolation.hoff_arbib import min_jerk
from robot.names import JOINT_GROUPS

# Reference poses of the pushes (the `home` keyframe plus these), from which the scene's walls are placed:
#   REACH_FORWARD_DEG: both hands in front of the chest, elbows bent, palms forward (the start of the
#     [ES Fig. 9 alpha] push, which stays within reach 0.25 m further on); hand sites (rarm_end,
#     larm_end) at x = 0.300 / 0.309, y = -/+0.37, z = 1.00 m; the foremost hand geoms (fixed jaws)
#     at about x = 0.35 m.
#   REACH_LEFT_DEG: left hand at the side at shoulder height pointing left, upper arm 60 deg below the
#     horizontal, elbow bent 120 deg in the vertical y-z plane (upper arm twisted 90 deg), wrist 60 deg: the
#     start of the [ES Fig. 9 beta] push; larm_end at (0.040, 0.693, 1.211) m, the outermost geom (fixed
#     jaw) at y = 0.725 m. REACH_LEFT_STRETCHED_DEG, the same arm stretched sideways, is the end of that push:
#     larm_end 0.25 m further left at y = 0.943 m (the farthest the left hand reaches), the same x and z.
# [ES] gives no wall distance. The front wall is 0.05 m beyond the foremost hand geom (contact after 0.05 m of
# the 0.25 m push, 0.20 m pressed into the wall): at 0.10 m the robot ended tilted back on its heels, propped
# by its hands, with the COG 2 cm inside the heel edge, and did not fall as the paper's robot did. The left
# wall is 0.10 m beyond the left hand at the start of the push (0.15 m pressed into it). It used to start from
# the stretched arm with the wall 0.10 m beyond it: the hand cannot go any further left from there (the
# setTargetPose of the push fails, 0.23 m out of reach), so the wall was never touched.
# tests/robot/test_model_files.py checks these numbers against the generated wall scene.

REACH_FORWARD_DEG = {
    "RARM_JOINT0": 42.0, "RARM_JOINT1": -10.0, "RARM_JOINT2": -18.6, "RARM_JOINT3": -122.1, "RARM_JOINT4": -19.8,
    "RARM_JOINT5": -6.5,
    "LARM_JOINT0": 42.0, "LARM_JOINT1": 10.0, "LARM_JOINT2": 18.6, "LARM_JOINT3": -122.1, "LARM_JOINT4": 19.8,
    "LARM_JOINT5": -6.5,
}
REACH_LEFT_DEG = {"LARM_JOINT0": 0.0, "LARM_JOINT1": 30.0, "LARM_JOINT2": 90.0, "LARM_JOINT3": -120.0,
                  "LARM_JOINT4": 0.0, "LARM_JOINT5": 60.0}
REACH_LEFT_STRETCHED_DEG = {"LARM_JOINT0": 0.0, "LARM_JOINT1": 90.0, "LARM_JOINT2": 90.0, "LARM_JOINT3": 0.0,
                            "LARM_JOINT4": 0.0, "LARM_JOINT5": 0.0}
FRONT_REACH_CLEARANCE_M = 0.05
LEFT_REACH_CLEARANCE_M = 0.10

#: Via points of the leftward push (a planner's straight hand line, sampled as joint angles).
LEFT_PUSH_VIA_POINTS = 10


def wall_push_forward(rig: Rig, variant: str) -> list[Event]:
    """Fig. 9 (alpha): both hands 0.25 m forward in 4 s, into the wall in front."""
    return [
        (0.0, lambda: rig.service.set_joint_angles(pose_with(rig, REACH_FORWARD_DEG), 2.0)),
        (3.0, lambda: move_hands(rig, ("rarm", "larm"), np.array([0.25, 0.0, 0.0]), 4.0)),
    ]


def left_arm_deg(phi_deg: float) -> dict[str, float]:
    """The left arm as a planar two-link (upper arm = forearm = 0.25 m) in the y-z plane through the shoulder:
    upper arm `phi_deg` below the horizontal, elbow bent 2 phi, wrist phi, so the hand points left at
    shoulder height, 2 L cos(phi) + hand length from the shoulder. 60 deg: REACH_LEFT_DEG; 0: stretched."""
    return {**REACH_LEFT_STRETCHED_DEG, "LARM_JOINT1": 90.0 - phi_deg, "LARM_JOINT3": -2.0 * phi_deg,
            "LARM_JOINT5": phi_deg}


def left_push_plan(rig: Rig, time_s: float) -> tuple[np.ndarray, list[float]]:
    """Fig. 9 (beta) as a planner gives it: larm joint angles (k, 7) that move the hand along a straight line
    from REACH_LEFT_DEG to the stretched arm, 0.25 m leftward, minimum-jerk spaced, `time_s` [s] in all."""
    k = LEFT_PUSH_VIA_POINTS
    phi0 = REACH_LEFT_DEG["LARM_JOINT5"]
    r0 = math.cos(math.radians(phi0))  # wrist distance from the shoulder / 2 L
    s = min_jerk(np.arange(1, k + 1) / k)
    idx = np.array(JOINT_GROUPS["larm"])
    goals = [pose_with(rig, left_arm_deg(math.degrees(math.acos(min(1.0, r0 + (1.0 - r0) * si)))))[idx]
             for si in s]
    return np.array(goals), [time_s / k] * k


def wall_push_left(rig: Rig, variant: str) -> list[Event]:
    """Fig. 9 (beta): the left hand 0.25 m leftward in 2 s, into the wall at the left."""

    def push() -> None:
        goals, times = left_push_plan(rig, 2.0)
        rig.service.set_group_sequence("larm", goals, times)

    return [
        (0.0, lambda: rig.service.set_joint_angles(pose_with(rig, REACH_LEFT_DEG), 2.0)),
        (3.0, push),
    ]


EXPERIMENTS: dict[str, Experiment] = {
    "wall-push-forward": Experiment("wall", wall_push_forward, 12.0, wall_push_forward.__doc__),
    "wall-push-left": Experiment("wall", wall_push_left, 10.0, wall_push_left.__doc__),
}
