"""Whole-body IK of the AutoBalancer: BODY moved so the COG hits its X-Y target, legs closed-form,
upper body from the planned joint angles ([MLC] III-C 5), hrpsys SimpleFullbodyInverseKinematicsSolver)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from controller.core.layer import Params
from controller.kinematics.leg_ik import LEG_INDICES, LLEG, RLEG, as_floats, leg_ik_floats
from controller.kinematics.model import RobotKinematics

_RLEG = LEG_INDICES["rleg"]
_LLEG = LEG_INDICES["lleg"]


def _as_slice(idx: np.ndarray) -> slice | np.ndarray:
    """Consecutive indices as a slice (cheaper to assign through), others unchanged."""
    i = idx.tolist()
    return slice(i[0], i[-1] + 1) if i == list(range(i[0], i[0] + len(i))) else idx


_RLEG_SLICE = _as_slice(_RLEG)
_LLEG_SLICE = _as_slice(_LLEG)


@dataclass(frozen=True)
class FullbodyIKParams(Params):
    move_base_gain: float = field(default=1.0, metadata={"unit": "-", "min": 0.05, "max": 1.5})
    max_iterations: int = field(default=4, metadata={"unit": "-", "min": 1, "max": 50})
    com_tolerance_m: float = field(default=1e-4, metadata={"unit": "m", "min": 1e-9, "max": 1e-2})


@dataclass(frozen=True)
class FullbodyIKResult:
    q_rad: np.ndarray  # (30,)
    base_pos_world: np.ndarray  # (3,)
    com_world: np.ndarray  # (3,)
    reachable: bool
    iterations: int


class FullbodyIK:
    """Solves for BODY x-y and both legs; BODY z and orientation are given (from the SequencePlayer)."""

    def __init__(self, kinematics: RobotKinematics, params: FullbodyIKParams | None = None) -> None:
        self.kin = kinematics
        self.params = params or FullbodyIKParams()
        self._com_minus_base_xy: tuple[float, float] | None = None  # warm start [m]
        self._leg_q_slices = None  # (kinematics, rleg, lleg) positions in pinocchio's configuration

    def com_of(self, base_pos_world, R_world_body, q_rad) -> np.ndarray:
        kin = self.kin
        qp = kin.configuration(base_pos_world, R_world_body, q_rad)
        return pin.centerOfMass(kin.model, kin.data, qp, False).copy()

    def solve(self, q_upper_rad: np.ndarray, base_z_m: float, R_world_body: np.ndarray, com_xy_target: np.ndarray,
              T_world_rsole: tuple[np.ndarray, np.ndarray], T_world_lsole: tuple[np.ndarray, np.ndarray],
              base_xy_guess: np.ndarray | None = None) -> FullbodyIKResult:
        """q_upper_rad: joint vector whose non-leg joints are kept; soles as (position, rotation)."""
        p = self.params
        q = np.array(q_upper_rad, dtype=float)
        tx, ty = np.asarray(com_xy_target, dtype=float)[:2].tolist()
        if base_xy_guess is not None:
            bx, by = np.array(base_xy_guess, dtype=float)[:2].tolist()
        elif self._com_minus_base_xy is not None:
            dx, dy = self._com_minus_base_xy  # the last solution's COG - BODY offset
            bx, by = tx - dx, ty - dy
        else:
            bx, by = (0.5 * (T_world_rsole[0][:2] + T_world_lsole[0][:2])).tolist()
        reachable = True
        com = np.zeros(3)
        it = 0
        kin = self.kin
        model, data = kin.model, kin.data
        # pinocchio configuration: orientation fixed for the whole solve, legs and BODY x-y updated in place
        qp = kin.configuration((0.0, 0.0, base_z_m), R_world_body, q)
        cache = self._leg_q_slices
        if cache is None or cache[0] is not kin:
            cache = self._leg_q_slices = (kin, _as_slice(kin.idx_q[_RLEG]), _as_slice(kin.idx_q[_LLEG]))
        idx_r, idx_l = cache[1], cache[2]
        R_rows = as_floats(R_world_body)
        rsole = (as_floats(T_world_rsole[0]), as_floats(T_world_rsole[1]))
        lsole = (as_floats(T_world_lsole[0]), as_floats(T_world_lsole[1]))
        tol = p.com_tolerance_m
        gain = p.move_base_gain
        bz = float(base_z_m)
        def legs_at(bx: float, by: float):
            """Both legs' IK for BODY at (bx, by, bz), written into qp; (q right, q left, reachable, COM)."""
            base_l = [bx, by, bz]
            qr, ok_r = leg_ik_floats(RLEG, base_l, R_rows, *rsole)
            ql, ok_l = leg_ik_floats(LLEG, base_l, R_rows, *lsole)
            qp[0], qp[1], qp[2] = bx, by, bz
            qp[idx_r] = qr
            qp[idx_l] = ql
            return qr, ql, ok_r and ok_l, pin.centerOfMass(model, data, qp, False)

        for it in range(1, p.max_iterations + 1):  # noqa: B007 - reported after the loop
            qr, ql, reachable, com = legs_at(bx, by)
            ex, ey = tx - com[0], ty - com[1]
            if math.hypot(ex, ey) < tol:
                break
            bx, by = bx + gain * ex, by + gain * ey
        else:
            # the last correction was not applied to the legs yet: finish with it
            qr, ql, reachable, com = legs_at(bx, by)
        com = np.array(com)
        q[_RLEG_SLICE] = qr
        q[_LLEG_SLICE] = ql
        base = np.array((bx, by, bz))
        cx, cy, _ = com.tolist()
        self._com_minus_base_xy = (cx - bx, cy - by)
        return FullbodyIKResult(q_rad=q, base_pos_world=base, com_world=com, reachable=reachable, iterations=it)



#: [rad] walking swings the legs' joints up to ~10 deg past their standing angles (measured: the ankle roll, walks
#: at the velocity limits): a walk starts only with this much range left in every leg joint
WALK_LEG_LIMIT_MARGIN_RAD = math.radians(12.0)


def nearest_leg_limit(q_rad, q_lower_rad, q_upper_rad) -> tuple[int, float]:
    """The leg joint of q_rad (30,) nearest a position limit and how far inside it is [rad] (negative: past it)."""
    best = (-1, math.inf)
    for idx in (_RLEG, _LLEG):
        for i in idx:
            m = min(q_rad[i] - q_lower_rad[i], q_upper_rad[i] - q_rad[i])
            if m < best[1]:
                best = (int(i), float(m))
    return best


def legs_within_limits(q_rad, q_lower_rad, q_upper_rad, margin_rad: float) -> bool:
    """Both legs' joints of q_rad (30,) at least margin_rad inside their position limits: a leg pose past one is
    clamped downstream and the sole no longer lies flat (the robot tips onto its edge)."""
    return nearest_leg_limit(q_rad, q_lower_rad, q_upper_rad)[1] >= margin_rad
