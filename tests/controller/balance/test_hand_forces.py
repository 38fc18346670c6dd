"""Eq. 6 on the robot: the COG offset reads the hands from the last solve only when a hand carries a force."""

import numpy as np
import pytest

from controller.balance.hand_force_cog_offset import cog_offset_against_hand_forces
from controller.balance.hand_forces import HANDS, HandForceOffset
from controller.core.types import Reference
from controller.kinematics.model import RobotKinematics
from robot.names import JOINT_NAMES


def reference(wrenches: np.ndarray) -> Reference:
    return Reference(q_rad=np.zeros(len(JOINT_NAMES)), base_pos_world=np.zeros(3), base_rpy_rad=np.zeros(3),
                     zmp_base=np.zeros(3), wrenches=wrenches)


def test_no_hand_force_leaves_the_cog_as_planned_and_reads_no_hand():
    kin = RobotKinematics()
    hands = HandForceOffset(kin, kin.total_mass)
    hands.stale = True
    cog = np.array((0.01, -0.02))
    assert hands.cog_xy(reference(np.zeros((4, 6))), cog, 0.0) is cog
    assert hands.stale  # nothing read


def test_a_hand_force_offsets_the_cog_by_eq_6_at_the_hands_of_the_last_solve():
    kin = RobotKinematics()
    kin.configuration(np.zeros(3), np.eye(3), np.zeros(len(JOINT_NAMES)))  # a solve's kinematics
    hands = HandForceOffset(kin, kin.total_mass)
    hands.stale = True
    w = np.zeros((4, 6))
    w[HANDS[0], :3] = (0.0, 0.0, -30.0)
    cog = np.array((0.01, -0.02))
    out = hands.cog_xy(reference(w), cog, 0.0)
    assert not hands.stale
    expected = cog_offset_against_hand_forces(cog, kin.total_mass, hands.positions(), w[list(HANDS), :3], 0.0)
    assert out == pytest.approx(expected, abs=1e-15)
    assert not np.allclose(out, cog)
