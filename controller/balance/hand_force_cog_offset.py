"""AutoBalancer COG offset that balances external hand forces (paper Eq. 6), for x and y at once."""

from __future__ import annotations

import numpy as np

from controller.core.constants import GRAVITY_M_S2
from controller.core.errors import InvalidCommand


def _check(cog_pc_xy, hand_positions_world, hand_forces_on_robot_world_n, total_mass_kg):
    cog = np.asarray(cog_pc_xy, dtype=float)
    p = np.asarray(hand_positions_world, dtype=float).reshape(-1, 3)
    f = np.asarray(hand_forces_on_robot_world_n, dtype=float).reshape(-1, 3)
    if cog.shape != (2,):
        raise InvalidCommand(f"cog_pc_xy must have shape (2,) [m]; got {cog.shape}")
    if p.shape != f.shape:
        raise InvalidCommand(f"one (3,) position [m] per (3,) force [N]; got {p.shape} and {f.shape}")
    if not total_mass_kg > 0.0:
        raise InvalidCommand(f"total_mass_kg must be > 0 [kg]; got {total_mass_kg!r}")
    if not total_mass_kg * GRAVITY_M_S2 - f[:, 2].sum() > 0.0:
        raise InvalidCommand("hand forces lift the robot (sum f_on,z >= M g); no COG balances it on its feet")
    return cog, p, f


def cog_offset_against_hand_forces(cog_pc_xy: np.ndarray, total_mass_kg: float,
                                   hand_positions_world: np.ndarray, hand_forces_on_robot_world_n: np.ndarray,
                                   zmp_z_m: float, g: float = GRAVITY_M_S2) -> np.ndarray:
    """Eq. 6: the COG (2,) [m] that keeps the planned ZMP while the hands are pushed or pulled.

    x_G = (M g x_pc + sum_i(-x_i f_iz + (z_i - z_zmp) f_ix)) / (M g - sum_i f_iz), same with y, f_iy.
    Inputs: preview COG x_pc (2,) [m], hand positions (k, 3) [m] and forces (k, 3) [N] ON the robot
    hand by the environment, world frame; k = 0 is allowed. Eq. 6 uses f = -(force on the robot):
      moments about the ZMP p (where the ground reaction has none), f_on on the robot, y axis:
      M g (x_G - x_p) + sum_i [(z_i - z_p) f_on,ix - (x_i - x_p) f_on,iz] = 0;
      x_p = x_pc, f = -f_on and the f_z lever (x_i - x_p) taken as (x_i - x_G) give Eq. 6 exactly.
    (With f = f_on, Eq. 6 is the static ZMP of a COG at x_pc, hrpsys's "static balance point", whose
    denominator is the foot load: used as the COG target it moves the COG the wrong way.)
    The lever approximation leaves a moment of -(x_G - x_pc) * sum f_on,iz about x_pc; see
    `cog_for_static_balance` for the exact balance.
    """
    cog, p, f_on = _check(cog_pc_xy, hand_positions_world, hand_forces_on_robot_world_n, total_mass_kg)
    f = -f_on  # the paper's f: force the hand exerts on the environment  [N]
    mg = total_mass_kg * g  # [N]
    denominator = mg - f[:, 2].sum()  # [N], = M g + sum f_on,z
    if not denominator > 0.0:
        raise InvalidCommand(
            f"Eq. 6 is singular (M g + sum f_on,z = {denominator:.1f} N <= 0); "
            "downward hand forces on the robot must stay below M g"
        )
    lever_z = p[:, 2] - zmp_z_m  # (k,) [m]
    numerator = mg * cog + (-p[:, :2] * f[:, 2:3] + lever_z[:, None] * f[:, :2]).sum(axis=0)  # (2,) [N m]
    return numerator / denominator


def cog_for_static_balance(cog_pc_xy: np.ndarray, total_mass_kg: float, hand_positions_world: np.ndarray,
                           hand_forces_on_robot_world_n: np.ndarray, zmp_z_m: float,
                           g: float = GRAVITY_M_S2) -> np.ndarray:
    """Exact variant of Eq. 6: the COG (2,) [m] whose total static moment about the ZMP at x_pc is zero.

    x_G = x_pc + sum_i [(x_i - x_pc) f_on,iz - (z_i - z_zmp) f_on,ix] / (M g), f_on the force on the robot.
    """
    cog, p, f_on = _check(cog_pc_xy, hand_positions_world, hand_forces_on_robot_world_n, total_mass_kg)
    lever_z = p[:, 2] - zmp_z_m  # (k,) [m]
    moment = ((p[:, :2] - cog) * f_on[:, 2:3] - lever_z[:, None] * f_on[:, :2]).sum(axis=0)  # (2,) [N m]
    return cog + moment / (total_mass_kg * g)
