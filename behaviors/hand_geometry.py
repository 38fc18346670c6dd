"""Where the right hand holds the 65 mm can, in the robot's own model: the grasp orientation in the feet frame
and the can's centre relative to the hand's operational point (rarm_end, the 85 mm grasp centre)."""

from __future__ import annotations

import math

import numpy as np

import robot.generate as gen
from behaviors.perception.models import CAN

#: The hand reaches forward and 30 deg down, the jaws closing across the upright can (the grasp check,
#: tests/scenarios/test_expo_grasp.py): rpy of the hand in the feet frame F [deg].
HAND_PITCH_DEG = 30.0
GRASP_ABOVE_CENTRE_M = 0.015  # [m] grip this far above the can's middle: the jaw tips clear the table top
PRE_GRASP_BACK_M = 0.10  # [m] the pre-grasp is this far back along the approach


def grasp_rotation_feet() -> np.ndarray:
    """(3, 3) the hand's orientation in F for the grasp: fingers along the approach, jaws closing along y."""
    a = math.radians(HAND_PITCH_DEG)
    approach = np.array([math.cos(a), 0.0, -math.sin(a)])
    z_hand = -approach
    x_hand = np.array([0.0, 1.0, 0.0])
    return np.column_stack([x_hand, np.cross(z_hand, x_hand), z_hand])


def approach_feet() -> np.ndarray:
    """(3,) unit direction in F the open hand moves along onto the can."""
    return -grasp_rotation_feet()[:, 2]


def _can_in_hand_m() -> np.ndarray:
    params = gen.load_parameters()
    c_85, _ = gen.grasp_centre(params, "RARM")  # where rarm_end is
    c_can, _ = gen.grasp_centre(params, "RARM", CAN.radius_m)  # the can against the fixed jaw
    return np.array(c_can) - np.array(c_85)


#: (3,) the held can's centre relative to rarm_end, in the hand frame [m].
CAN_IN_HAND_M = _can_in_hand_m()


def hand_point_for_can(can_centre: np.ndarray, R_hand: np.ndarray) -> np.ndarray:
    """Where rarm_end goes (same frame as `can_centre`, R_hand the hand's orientation in it) for the grasp."""
    return np.asarray(can_centre, dtype=float) + np.array([0.0, 0.0, GRASP_ABOVE_CENTRE_M]) - R_hand @ CAN_IN_HAND_M


def can_from_hand_point(p_hand: np.ndarray, R_hand: np.ndarray) -> np.ndarray:
    """The held can's centre from rarm_end's pose (the inverse of hand_point_for_can)."""
    return np.asarray(p_hand, dtype=float) + R_hand @ CAN_IN_HAND_M - np.array([0.0, 0.0, GRASP_ABOVE_CENTRE_M])
