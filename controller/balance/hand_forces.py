"""Eq. 6 on the robot: the hands where the AutoBalancer's last whole-body solve put them, and the hand forces the
reference carries turned into the COG that keeps the planned ZMP."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from controller.balance.hand_force_cog_offset import cog_offset_against_hand_forces
from controller.core.constants import GRAVITY_M_S2
from controller.core.types import Reference
from controller.kinematics.model import RobotKinematics
from robot.names import FORCE_SENSOR_NAMES

HANDS = (FORCE_SENSOR_NAMES.index("rhsensor"), FORCE_SENSOR_NAMES.index("lhsensor"))


class HandForceOffset:
    """The COG offset against the hands' forces; the hands' positions are read from `kin`'s data (the last solve)
    only when a force needs them."""

    __slots__ = ("kin", "total_mass_kg", "stale", "_frame_ids", "_pos")

    def __init__(self, kin: RobotKinematics, total_mass_kg: float) -> None:
        self.kin = kin
        self.total_mass_kg = total_mass_kg
        self.stale = False  # True once a solve has moved the hands
        self._frame_ids = [kin.model.getFrameId(n) for n in ("rarm_end", "larm_end")]
        self._pos = np.zeros((2, 3))

    def positions(self) -> np.ndarray:
        """World hand positions (2, 3) [m] in the last whole-body solve (zeros before the first)."""
        if self.stale:
            model, data = self.kin.model, self.kin.data
            for i, fid in enumerate(self._frame_ids):
                self._pos[i] = pin.updateFramePlacement(model, data, fid).translation
            self.stale = False
        return self._pos

    def cog_xy(self, ref: Reference, cog_pc_xy: np.ndarray, zmp_z_m: float) -> np.ndarray:
        """The COG (2,) [m] that balances `ref`'s hand forces at the planned ZMP height; `cog_pc_xy` itself when
        the hands carry no force."""
        rows = ref.wrenches.tolist()
        if not any(v for i in HANDS for v in rows[i][:3]):
            return cog_pc_xy
        f = ref.wrenches[list(HANDS), :3]
        return cog_offset_against_hand_forces(cog_pc_xy, self.total_mass_kg, self.positions(), f, zmp_z_m,
                                              GRAVITY_M_S2)
