"""ImpedanceController layer ([MLC] III-B, Eq. 3): per hand, m x'' + d x' + k x = f - f_seq from the wrist
F/T sensor, the SequencePlayer's hand pose as the spring centre, the arm re-solved by IK."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from controller.core.errors import InvalidCommand, InvalidState
from controller.core.layer import Layer, Params, SharedStatus, Status, described
from controller.core.types import Reference, TickContext
from controller.interpolation.blend import Transition
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import cross3
from robot.names import FORCE_SENSOR_NAMES, JOINT_GROUPS

LIMBS = {"rarm": ("rhsensor", "rarm_end"), "larm": ("lhsensor", "larm_end")}


@dataclass(frozen=True)
class ImpedanceParams(Params):
    """hrpsys ImpedanceController defaults (translation: M_p, D_p, K_p; rotation: M_r, D_r, K_r)."""

    m_p: float = field(default=10.0, metadata={"unit": "kg", "min": 0.01, "max": 1e4})
    d_p: float = field(default=200.0, metadata={"unit": "N s/m", "min": 0.0, "max": 1e6})
    k_p: float = field(default=400.0, metadata={"unit": "N/m", "min": 1.0, "max": 1e6})
    m_r: float = field(default=5.0, metadata={"unit": "kg m^2", "min": 0.01, "max": 1e4})
    d_r: float = field(default=100.0, metadata={"unit": "N m s/rad", "min": 0.0, "max": 1e6})
    k_r: float = field(default=200.0, metadata={"unit": "N m/rad", "min": 1.0, "max": 1e6})
    transition_time_s: float = field(default=2.0, metadata={"unit": "s", "min": 0.01, "max": 10.0})
    max_displacement_m: float = field(default=0.2, metadata={"unit": "m", "min": 0.0, "max": 1.0})
    max_rotation_deg: float = field(default=45.0, metadata={"unit": "deg", "min": 0.0, "max": 180.0})


@dataclass(frozen=True, slots=True)
class ImpedanceLimbStatus:
    """One hand of the ImpedanceController."""

    active: bool = field(metadata=described("impedance control of this hand is on"))
    weight: float = field(metadata=described("start/stop blend weight, 0..1", "-"))
    displacement_m: tuple[float, float, float] = field(metadata=described("hand deviation from the plan", "m"))
    rotation_rad: tuple[float, float, float] = field(metadata=described("hand rotation from the plan (rotation vector)",
                                                                        "rad"))


@dataclass(frozen=True, slots=True)
class ImpedanceControllerStatus(Status):
    rarm: ImpedanceLimbStatus = field(metadata=described("the right hand"))
    larm: ImpedanceLimbStatus = field(metadata=described("the left hand"))


class ImpedanceState:
    """Second-order impedance of one end effector: deviation (position, rotation vector) and its rate."""

    def __init__(self) -> None:
        self.dp = np.zeros(3)
        self.vp = np.zeros(3)
        self.dr = np.zeros(3)
        self.vr = np.zeros(3)

    def step(self, p: ImpedanceParams, force_diff: np.ndarray, moment_diff: np.ndarray, dt: float) -> None:
        """Semi-implicit Euler of M a + D v + K x = f (exact static deviation f / K)."""
        self.vp += (force_diff - p.d_p * self.vp - p.k_p * self.dp) / p.m_p * dt
        self.dp += self.vp * dt
        self.vr += (moment_diff - p.d_r * self.vr - p.k_r * self.dr) / p.m_r * dt
        self.dr += self.vr * dt
        n = np.linalg.norm(self.dp)
        if n > p.max_displacement_m:
            self.dp *= p.max_displacement_m / n
        a = np.linalg.norm(self.dr)
        if a > math.radians(p.max_rotation_deg):
            self.dr *= math.radians(p.max_rotation_deg) / a


class _Limb:
    def __init__(self, name: str) -> None:
        self.name = name
        self.sensor, self.frame = LIMBS[name]
        self.sensor_index = FORCE_SENSOR_NAMES.index(self.sensor)
        # the six arm joints: *ARM_JOINT6 (the gripper, the group's last joint) moves no hand frame and
        # passes through from the plan, so open/close commands work while the impedance runs
        self.joints = np.array(JOINT_GROUPS[name][:-1])
        self.active = False
        self.weight = 0.0
        self.transition: Transition | None = None  # start / stop blend of the weight
        self.imp = ImpedanceState()
        self.q: np.ndarray | None = None  # last IK solution (arm joints)
        self.status_part = SharedStatus()  # its part of ImpedanceController.status()


class ImpedanceController(Layer):
    """Each started hand yields to the measured force around the planned pose; no force, no deviation."""

    name = "ic"
    description = "ImpedanceController: hand impedance from the wrist F/T sensors (Eq. 3)"

    def __init__(self, params: ImpedanceParams | None = None, kinematics: RobotKinematics | None = None) -> None:
        super().__init__()
        self.params = {name: params or ImpedanceParams() for name in LIMBS}
        self.kin = kinematics or RobotKinematics()
        self.limbs = {name: _Limb(name) for name in LIMBS}
        model = self.kin.model
        self._frame_ids = {name: (model.getFrameId(lb.frame), model.getFrameId(lb.sensor))
                           for name, lb in self.limbs.items()}
        self._last_out: Reference | None = None  # repeated while the hard e-stop holds the chain

    def _limb(self, name: str) -> _Limb:
        if name not in self.limbs:
            raise InvalidCommand(f"unknown limb {name!r}; valid: {sorted(self.limbs)}")
        return self.limbs[name]

    def set_params(self, limb: str, params: ImpedanceParams) -> None:
        self._limb(limb)
        self.params[limb] = params

    def start(self, limb: str) -> None:
        lb = self._limb(limb)
        if lb.active:
            raise InvalidState(f"impedance control of {limb} is already active")
        lb.active = True
        lb.imp = ImpedanceState()
        lb.transition = Transition(lb.weight, 1.0, self.params[limb].transition_time_s, "sigmoid")

    def stop(self, limb: str) -> None:
        lb = self._limb(limb)
        if not lb.active:
            raise InvalidState(f"impedance control of {limb} is not active")
        lb.active = False
        lb.transition = Transition(lb.weight, 0.0, self.params[limb].transition_time_s, "sigmoid")

    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        if not self.enabled:
            return ref
        if not any(lb.active or lb.weight > 0.0 for lb in self.limbs.values()):
            self._last_out = None
            return ref
        if ctx.hold and self._last_out is not None:
            return self._last_out  # the hard e-stop: no force is integrated into a command that is not played
        q_out = np.array(ref.q_rad, dtype=float)
        kin = self.kin
        # one kinematic pass for the planned posture: the hand and sensor frames of every working limb
        kin.update_joints_rpy(ref.base_pos_world, ref.base_rpy_rad, ref.q_rad)
        est = ctx.estimate
        targets = []
        for lb in self.limbs.values():
            if not (lb.active or lb.weight > 0.0):
                continue
            p = self.params[lb.name]
            if lb.transition is not None:
                lb.weight = lb.transition.step(ctx.dt_s)
                if lb.transition.done:
                    lb.transition = None
            # the planned hand pose (spring centre) and the measured-minus-planned wrench at the hand
            frame_id, sensor_id = self._frame_ids[lb.name]
            T_ee = kin.frame_homogeneous(frame_id)
            p_ee, R_ee = T_ee[:3, 3], T_ee[:3, :3]
            p_s = kin.frame_homogeneous(sensor_id)[:3, 3]
            f_act = est.wrenches_ext_world[lb.sensor_index, :3]
            tau_act = est.wrenches_ext_world[lb.sensor_index, 3:] + cross3(p_s - p_ee, f_act)
            f_ref = ref.wrenches[lb.sensor_index, :3]
            tau_ref = ref.wrenches[lb.sensor_index, 3:]
            if lb.active:
                lb.imp.step(p, f_act - f_ref, tau_act - tau_ref, ctx.dt_s)
            targets.append((lb, p_ee + lb.imp.dp, pin.exp3(lb.imp.dr) @ R_ee))
        for lb, target_p, target_R in targets:
            q_seed = q_out.copy()
            if lb.q is not None:
                q_seed[lb.joints] = lb.q
            # out of reach (or not converged this tick): the closest posture found, never a frozen arm,
            # so the planned motion (an EmergencyStopper revert too) keeps reaching the hand
            q_ik = self.kin_ik(lb.name, q_seed, ref, target_p, target_R)
            lb.q = q_ik[lb.joints]
            q_out[lb.joints] = (1.0 - lb.weight) * ref.q_rad[lb.joints] + lb.weight * lb.q
            if not lb.active and lb.weight <= 0.0:
                lb.q = None
        self._last_out = ref.with_(q_rad=q_out)
        return self._last_out

    def kin_ik(self, limb: str, q_seed, ref: Reference, target_p, target_R) -> np.ndarray:
        return self.kin.limb_ik(limb, q_seed, ref.base_pos_world, ref.base_rpy_rad, target_p, target_R,
                                max_iter=8, pos_tol_m=2e-5, rot_tol_rad=2e-4, best_effort=True)

    def status(self) -> ImpedanceControllerStatus:
        parts = {}
        for name, lb in self.limbs.items():
            dp, dr = lb.imp.dp, lb.imp.dr
            parts[name] = lb.status_part.get((lb.active, lb.weight, dp.tobytes(), dr.tobytes()), lambda lb=lb: (
                ImpedanceLimbStatus(active=lb.active, weight=round(lb.weight, 4),
                                    displacement_m=tuple(lb.imp.dp.tolist()), rotation_rad=tuple(lb.imp.dr.tolist()))))
        return ImpedanceControllerStatus(enabled=self.enabled, **parts)
