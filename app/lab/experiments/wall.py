"""[MLC] IV-C 1, Fig. 8-10: hands pushed into a rigid wall (scene `wall`), ImpedanceController off; the
disturbances a study varies (wall distance, push height, direction and speed)."""

from __future__ import annotations

import math

import numpy as np

from app.lab.experiments.common import Disturbance, DisturbanceParam, Event, Experiment, Rig, move_hands, pose_with
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
#: The pushes of Fig. 9: 0.25 m forward in 4 s (alpha), 0.25 m leftward in 2 s (beta).
FORWARD_PUSH_M, FORWARD_PUSH_S = 0.25, 4.0
LEFT_PUSH_M, LEFT_PUSH_S = 0.25, 2.0
#: When the hands are raised or lowered before the forward push (the reach ends at 2 s, the push starts at 3 s),
#: and in how long [s].
HEIGHT_CHANGE_AT_S, HEIGHT_CHANGE_S = 2.0, 0.8

#: What a study may vary ([MLC] gives one distance, height and speed; these are the planner's or the operator's
#: plausible mistakes around them). At the defaults the pushes are the paper's. The robot put down farther from
#: the wall is a simulator operation before it settles: its own sensors cannot tell (the same as moving the wall).
#: The height and yaw ranges are what the arms reach (measured: +0.07 m up, -20 deg or 30 deg of yaw are refused,
#: setTargetPose out of reach).
FORWARD_DISTURBANCES = {
    "wall_gap_m": DisturbanceParam(0.0, -0.04, 0.10, "m", "the front wall this much farther from the hands than "
                                   "the 0.05 m of the paper's set-up (negative: nearer)"),
    "push_height_m": DisturbanceParam(0.0, -0.10, 0.05, "m", "both hands raised by this before the push"),
    "push_yaw_deg": DisturbanceParam(0.0, -15.0, 15.0, "deg", "the push turned this much to the left of "
                                     "straight ahead"),
    "push_speed_m_s": DisturbanceParam(FORWARD_PUSH_M / FORWARD_PUSH_S, 0.03, 0.15, "m/s",
                                       "the push's speed (its 0.25 m at this speed)"),
}
LEFT_DISTURBANCES = {
    "wall_gap_m": DisturbanceParam(0.0, -0.06, 0.10, "m", "the left wall this much farther from the hand than "
                                   "the 0.10 m of the set-up (negative: nearer)"),
    "push_speed_m_s": DisturbanceParam(LEFT_PUSH_M / LEFT_PUSH_S, 0.0625, 0.25, "m/s",
                                       "the push's speed (its 0.25 m at this speed)"),
}


def place_forward(rig: Rig, disturbance: Disturbance) -> None:
    """The robot put down `wall_gap_m` farther back from the front wall."""
    if disturbance["wall_gap_m"] != 0.0:
        rig.plant.translate_robot((-disturbance["wall_gap_m"], 0.0))


def place_left(rig: Rig, disturbance: Disturbance) -> None:
    """The robot put down `wall_gap_m` farther right of the left wall."""
    if disturbance["wall_gap_m"] != 0.0:
        rig.plant.translate_robot((0.0, -disturbance["wall_gap_m"]))


def wall_push_forward(rig: Rig, variant: str, disturbance: Disturbance) -> list[Event]:
    """Fig. 9 (alpha): both hands 0.25 m forward in 4 s, into the wall in front."""
    yaw = math.radians(disturbance["push_yaw_deg"])
    delta = FORWARD_PUSH_M * np.array([math.cos(yaw), math.sin(yaw), 0.0])
    push_s = FORWARD_PUSH_M / disturbance["push_speed_m_s"]
    events = [
        (0.0, lambda: rig.service.set_joint_angles(pose_with(rig, REACH_FORWARD_DEG), 2.0)),
        (3.0, lambda: move_hands(rig, ("rarm", "larm"), delta, push_s)),
    ]
    dz = disturbance["push_height_m"]
    if dz != 0.0:
        events.insert(1, (HEIGHT_CHANGE_AT_S,
                          lambda: move_hands(rig, ("rarm", "larm"), np.array([0.0, 0.0, dz]), HEIGHT_CHANGE_S)))
    return events


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


def wall_push_left(rig: Rig, variant: str, disturbance: Disturbance) -> list[Event]:
    """Fig. 9 (beta): the left hand 0.25 m leftward in 2 s, into the wall at the left."""

    def push() -> None:
        goals, times = left_push_plan(rig, LEFT_PUSH_M / disturbance["push_speed_m_s"])
        rig.service.set_group_sequence("larm", goals, times)

    return [
        (0.0, lambda: rig.service.set_joint_angles(pose_with(rig, REACH_LEFT_DEG), 2.0)),
        (3.0, push),
    ]


EXPERIMENTS: dict[str, Experiment] = {
    "wall-push-forward": Experiment("wall", wall_push_forward, 12.0, wall_push_forward.__doc__,
                                    disturbances=FORWARD_DISTURBANCES, place=place_forward),
    "wall-push-left": Experiment("wall", wall_push_left, 10.0, wall_push_left.__doc__,
                                 disturbances=LEFT_DISTURBANCES, place=place_left),
}
