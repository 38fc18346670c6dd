"""Whole-body IK of the AutoBalancer: BODY moved so the COG hits its X-Y target, legs closed-form,
upper body from the planned joint angles ([MLC] III-C 5), hrpsys SimpleFullbodyInverseKinematicsSolver)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from controller.kinematics import RobotKinematics
from controller.layer import Params
from controller.leg_ik import LEG_INDICES, LLEG, RLEG, leg_ik


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
        self._com_minus_base_xy = None  # warm start

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
        if base_xy_guess is not None:
            base_xy = np.array(base_xy_guess, dtype=float)
        elif self._com_minus_base_xy is not None:
            base_xy = np.asarray(com_xy_target) - self._com_minus_base_xy
        else:
            base_xy = 0.5 * (T_world_rsole[0][:2] + T_world_lsole[0][:2])
        reachable = True
        com = np.zeros(3)
        it = 0
        for it in range(1, p.max_iterations + 1):  # noqa: B007 - reported after the loop
            base = np.array([base_xy[0], base_xy[1], base_z_m])
            qr, ok_r = leg_ik(RLEG, base, R_world_body, *T_world_rsole)
            ql, ok_l = leg_ik(LLEG, base, R_world_body, *T_world_lsole)
            q[LEG_INDICES["rleg"]] = qr
            q[LEG_INDICES["lleg"]] = ql
            reachable = ok_r and ok_l
            com = self.com_of(base, R_world_body, q)
            err = np.asarray(com_xy_target) - com[:2]
            if np.linalg.norm(err) < p.com_tolerance_m:
                break
            base_xy = base_xy + p.move_base_gain * err
        else:
            # the last correction was not applied to the legs yet: finish with it
            base = np.array([base_xy[0], base_xy[1], base_z_m])
            q[LEG_INDICES["rleg"]], ok_r = leg_ik(RLEG, base, R_world_body, *T_world_rsole)
            q[LEG_INDICES["lleg"]], ok_l = leg_ik(LLEG, base, R_world_body, *T_world_lsole)
            reachable = ok_r and ok_l
            com = self.com_of(base, R_world_body, q)
        self._com_minus_base_xy = com[:2] - base[:2]
        return FullbodyIKResult(q_rad=q, base_pos_world=base, com_world=com, reachable=reachable, iterations=it)
