"""COG offset against hand forces (Eq. 6): hand-worked numbers and a static moment balance about the ZMP."""

import numpy as np
import pytest

from controller.balance.hand_force_cog_offset import cog_for_static_balance, cog_offset_against_hand_forces
from controller.core.constants import GRAVITY_M_S2
from controller.core.errors import InvalidCommand

M = 58.0  # [kg]
MG = M * GRAVITY_M_S2  # 58 * 9.80665 = 568.7857 N


def moment_about_zmp(cog_xy, hand_positions, hand_forces_on_robot, zmp_xyz):
    """Horizontal (x, y) moment [N m] of gravity and the hand forces about the ZMP, by cross products."""
    o = np.asarray(zmp_xyz, dtype=float)
    total = np.cross(np.array([*cog_xy, 0.8]) - o, [0.0, 0.0, -MG])
    for p, f in zip(hand_positions, hand_forces_on_robot, strict=True):
        total = total + np.cross(np.asarray(p) - o, f)
    return total[:2]


def test_a_hand_pulled_down_in_front_moves_the_cog_back_by_the_hand_worked_amount():
    # BalanceAgainstHandForce: the environment pulls the right hand down with 50 N, at x = 0.4, y = -0.2,
    # z = 1.0 m; ZMP height 0. Eq. 6's f is minus the force on the robot: f = (0, 0, +50).
    # x_G = (M g * 0 - 0.4 * 50 + 1.0 * 0) / (568.7857 - 50) = -20 / 518.7857 = -0.0385516 m (backward)
    # y_G = (M g * 0 + 0.2 * 50 + 1.0 * 0) / 518.7857 = +10 / 518.7857 = +0.0192758 m (away from the hand)
    cog = cog_offset_against_hand_forces(np.zeros(2), M, [[0.4, -0.2, 1.0]], [[0.0, 0.0, -50.0]], 0.0)
    assert cog == pytest.approx([-0.0385516, 0.0192758], abs=1e-7)


def test_a_horizontal_push_on_the_hand_moves_the_cog_against_it():
    # The environment pushes the hand backward with 30 N at height 1.0 m above a ZMP at z = 0.1 m,
    # with the preview COG at x = 0.02: x_G = (568.7857 * 0.02 + (1.0 - 0.1) * 30) / 568.7857
    #                                       = (11.3757 + 27) / 568.7857 = 0.0674695 m (forward)
    hand, push = [[0.4, 0.0, 1.0]], [[-30.0, 0.0, 0.0]]
    cog = cog_offset_against_hand_forces(np.array([0.02, 0.0]), M, hand, push, 0.1)
    assert cog == pytest.approx([0.0674695, 0.0], abs=1e-7)


def test_zero_hand_force_leaves_the_preview_cog_unchanged():
    cog_pc = np.array([0.013, -0.007])
    hands = [[0.4, -0.2, 1.0], [0.4, 0.2, 1.0]]
    assert np.array_equal(cog_offset_against_hand_forces(cog_pc, M, hands, np.zeros((2, 3)), 0.0), cog_pc)
    assert np.array_equal(cog_offset_against_hand_forces(cog_pc, M, np.zeros((0, 3)), np.zeros((0, 3)), 0.0),
                          cog_pc)


def test_horizontal_hand_forces_are_balanced_exactly_about_the_zmp():
    cog_pc, zmp_z = np.array([0.01, -0.02]), 0.05
    hands = [[0.35, -0.25, 0.9], [0.3, 0.25, 1.1]]
    forces = [[-20.0, 5.0, 0.0], [-10.0, -15.0, 0.0]]
    cog = cog_offset_against_hand_forces(cog_pc, M, hands, forces, zmp_z)
    assert np.allclose(moment_about_zmp(cog, hands, forces, [*cog_pc, zmp_z]), 0.0, atol=1e-9)


def test_vertical_hand_forces_leave_only_eq6s_second_order_moment_and_the_exact_variant_none():
    cog_pc, zmp_z = np.array([0.0, 0.0]), 0.0
    hands, forces = [[0.4, -0.2, 1.0], [0.3, 0.2, 0.9]], [[0.0, 0.0, -50.0], [10.0, -5.0, -20.0]]
    zmp = [*cog_pc, zmp_z]
    uncompensated = moment_about_zmp(cog_pc, hands, forces, zmp)
    cog = cog_offset_against_hand_forces(cog_pc, M, hands, forces, zmp_z)
    residual = moment_about_zmp(cog, hands, forces, zmp)
    # Eq. 6 takes the vertical forces' lever from x_G, not the ZMP: residual = -(x_G - x_pc) sum f_on,z
    # (about x the sign flips: the moment of a vertical force about x is +y f_z, about y it is -x f_z)
    sum_fz = -70.0
    shift = cog - cog_pc
    assert residual == pytest.approx([shift[1] * sum_fz, -shift[0] * sum_fz], abs=1e-9)
    assert np.all(np.abs(residual) < 0.15 * np.abs(uncompensated))
    exact = cog_for_static_balance(cog_pc, M, hands, forces, zmp_z)
    assert np.allclose(moment_about_zmp(exact, hands, forces, zmp), 0.0, atol=1e-9)


def test_the_force_on_the_robot_fed_to_eq6_unchanged_would_give_the_zmp_of_the_uncorrected_cog():
    # documents the sign: Eq. 6 with f = f_on is the static ZMP (zero moment point) of a COG at x_pc
    cog_pc, hands, forces_on = np.zeros(2), [[0.4, -0.2, 1.0]], np.array([[5.0, 0.0, -50.0]])
    wrong = cog_offset_against_hand_forces(cog_pc, M, hands, -forces_on, 0.0)
    assert np.allclose(moment_about_zmp(cog_pc, hands, forces_on, [*wrong, 0.0]), 0.0, atol=1e-9)
    assert wrong[0] > 0.0 > cog_offset_against_hand_forces(cog_pc, M, hands, forces_on, 0.0)[0]


def test_hand_forces_that_lift_the_robot_are_refused():
    with pytest.raises(InvalidCommand, match="lift the robot"):
        cog_offset_against_hand_forces(np.zeros(2), M, [[0.4, 0.0, 1.0]], [[0.0, 0.0, MG + 1.0]], 0.0)
    with pytest.raises(InvalidCommand, match="below M g"):
        cog_offset_against_hand_forces(np.zeros(2), M, [[0.4, 0.0, 1.0]], [[0.0, 0.0, -MG - 1.0]], 0.0)
    with pytest.raises(InvalidCommand, match="one \\(3,\\) position"):
        cog_offset_against_hand_forces(np.zeros(2), M, [[0.4, 0.0, 1.0]], np.zeros((2, 3)), 0.0)
