"""[MLC] IV-C 1, Fig. 8-10: hands pushed into a rigid wall (scene `wall`), ImpedanceController off."""

from __future__ import annotations

import math

import numpy as np

from app.experiments.common import Event, Experiment, Rig, move_hands, pose_with
from robot.generate import REACH_FORWARD_DEG, REACH_LEFT_DEG, REACH_LEFT_STRETCHED_DEG
from robot.names import JOINT_GROUPS

#: Via points of the leftward push (a planner's straight hand line, sampled as joint angles).
LEFT_PUSH_VIA_POINTS = 10


def wall_push_forward(rig: Rig, variant: str) -> list[Event]:
    """Fig. 9 (alpha): both hands 0.25 m forward in 4 s, into the wall in front."""
    return [
        (0.0, lambda: rig.service.set_joint_angles(pose_with(rig, REACH_FORWARD_DEG), 2.0)),
        (3.0, lambda: move_hands(rig, ("rarm", "larm"), np.array([0.25, 0.0, 0.0]), 4.0)),
    ]


def minimum_jerk(tau: np.ndarray) -> np.ndarray:
    """Fraction of a minimum-jerk move done at normalised time `tau` in [0, 1]."""
    return tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)


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
    s = minimum_jerk(np.arange(1, k + 1) / k)
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
