"""The waist point as the reference's BODY height and orientation, which the AutoBalancer realises on its legs:
a target its legs cannot carry is held at the last one they could."""

from __future__ import annotations

import math

import numpy as np

from controller.balance.fall_detector import FallDetectorParams, tilt_rad
from controller.core.types import Reference
from controller.kinematics.fullbody_ik import WALK_LEG_LIMIT_MARGIN_RAD, FullbodyIK, legs_within_limits
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import matrix_to_rpy, rpy_to_matrix
from controller.operation.frame import PlanarFrame
from controller.operation.limits import MOTION_STOP, REACH

#: [rad] a waist target keeps the legs' joints this far inside their limits (campaign seeds 1017, 1018: a 19 deg
#: roll put a hip roll at its limit, the sole tipped onto its edge and the robot fell walking); walking, with the
#: COG over either sole as well (seed 5010: rolled 8.5 deg and pitched 16 deg, the stance hip roll reached its limit
#: on the right foot though 15 deg were left on the left one)
WAIST_LEG_LIMIT_MARGIN_RAD = math.radians(3.0)
#: [rad] a waist target tilts BODY at most this far from the vertical: the loop's fall detector reads BODY past
#: FallDetectorParams.max_tilt_deg (30) as a fall (soak seed 11019: a waist stick on one foot tilted BODY to 30 deg
#: while the robot stood, and the safe stop latched "fallen"); 5 deg are left for BODY's sway about its target
WAIST_MAX_TILT_RAD = math.radians(FallDetectorParams().max_tilt_deg - 5.0)


def ground_z(gait, F: PlanarFrame) -> float:
    """The height [m] the waist's is counted from: F's, or while one sole swings the other's (F would bob)."""
    if gait is None or all(gait.contact):
        return float(F.p[2])
    return float(gait.p_rsole_world[2] if gait.contact[0] else gait.p_lsole_world[2])


class WaistPoint:
    """Checks a new waist target against the AutoBalancer's closed-form legs (once per target object) and turns
    it into the reference's BODY position and rpy."""

    __slots__ = ("_legs", "_lower_rad", "_upper_rad", "_checked")

    def __init__(self) -> None:
        self._legs = FullbodyIK(RobotKinematics())  # the AutoBalancer's closed-form legs
        self._lower_rad = self._legs.kin.q_lower.tolist()
        self._upper_rad = self._legs.kin.q_upper.tolist()
        self._checked = None  # the waist target last found reachable by the legs

    def realise(self, points, ref: Reference, gait, F: PlanarFrame, stopped: bool) -> tuple[np.ndarray, np.ndarray]:
        """(BODY position (3,) [m] in the world, rpy (3,) [rad]) for the waist target of `points`
        (PointTargets); a height or tilt the legs cannot reach is set back to the achieved one (reason "reach")."""
        target = points.targets["waist"]
        R_F = None
        if target is not self._checked and tilt_rad(target.rpy_rad) > WAIST_MAX_TILT_RAD and "waist" in points.achieved:
            target = points.targets["waist"] = points.achieved["waist"]
            points.limited["waist"] = REACH
        if gait is not None and not stopped and target is not self._checked:
            R_F = rpy_to_matrix(target.rpy_rad)
            walking = getattr(gait, "walking", False)
            legs_ok = self._carried(ref, float(F.p[2] + target.height_m), F.R @ R_F, gait, gait.cog_world[:2],
                                    WALK_LEG_LIMIT_MARGIN_RAD if walking else WAIST_LEG_LIMIT_MARGIN_RAD)
            if walking and legs_ok:  # and on either foot alone, where the stance hip rolls most (seed 5010)
                legs_ok = all(self._carried(ref, float(F.p[2] + target.height_m), F.R @ R_F, gait, sole[:2],
                                            WAIST_LEG_LIMIT_MARGIN_RAD)
                              for sole in (gait.p_rsole_world, gait.p_lsole_world))
            if not legs_ok and "waist" in points.achieved:
                target = points.targets["waist"] = points.achieved["waist"]
                points.limited["waist"] = REACH
                R_F = None
            self._checked = target
        if stopped:
            points.limited["waist"] = MOTION_STOP
        points.achieved["waist"] = target
        if gait is not None:  # the AutoBalancer turns BODY yaw by the feet's: the rpy are F's
            rpy = np.array(target.rpy_rad, dtype=float)
        else:
            rpy = matrix_to_rpy(F.R @ (R_F if R_F is not None else rpy_to_matrix(target.rpy_rad)))
        base = np.array(ref.base_pos_world, dtype=float)
        base[2] = ground_z(gait, F) + target.height_m
        return base, rpy

    def _carried(self, ref: Reference, base_z_m: float, R_world_body: np.ndarray, gait, cog_xy, margin_rad: float
                 ) -> bool:
        """The AutoBalancer's legs reach BODY at `base_z_m`, `R_world_body` with the COG over `cog_xy` [m], every
        leg joint at least `margin_rad` inside its limits."""
        res = self._legs.solve(ref.q_rad, base_z_m, R_world_body, cog_xy, (gait.p_rsole_world, gait.R_rsole_world),
                               (gait.p_lsole_world, gait.R_lsole_world))
        return res.reachable and legs_within_limits(res.q_rad, self._lower_rad, self._upper_rad, margin_rad)
