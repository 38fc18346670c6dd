"""AutoBalancer layer ([MLC] III-C): footsteps and reference ZMP from the gait planner, COG by preview
control (Eq. 5), COG offset against hand forces (Eq. 6), whole-body IK with feet, COG X-Y, base height
and orientation; when not walking it keeps the COG over the feet while the upper body moves."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from controller.errors import InvalidState
from controller.fullbody_ik import FullbodyIK
from controller.hand_force_cog_offset import cog_offset_against_hand_forces
from controller.hoff_arbib import hoff_arbib
from controller.kinematics import RobotKinematics
from controller.layer import Layer, Params
from controller.preview_control import PreviewController, PreviewControlParams, PreviewQueue
from controller.rotations import rpy_to_matrix
from controller.types import GaitState, Reference, TickContext
from robot.names import FORCE_SENSOR_NAMES

G = 9.80665
HANDS = (FORCE_SENSOR_NAMES.index("rhsensor"), FORCE_SENSOR_NAMES.index("lhsensor"))


@dataclass(frozen=True)
class AutoBalancerParams(Params):
    transition_time_s: float = field(default=2.0, metadata={"unit": "s", "min": 0.01, "max": 10.0})
    # ZMP (and COG when standing) offset from each sole frame, in the sole frame (hrpsys default_zmp_offsets)
    zmp_offset_x_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.1, "max": 0.1})
    zmp_offset_y_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.05, "max": 0.05})
    use_hand_force_offset: bool = field(default=True, metadata={"unit": "-"})
    preview_q: float = field(default=1.0, metadata={"unit": "-", "min": 1e-6, "max": 1e6})
    preview_r: float = field(default=1e-6, metadata={"unit": "-", "min": 1e-12, "max": 1.0})


class AutoBalancer(Layer):
    """Overwrites the legs of the planned posture so the feet follow the gait and the COG follows the
    preview controller; the upper body keeps the SequencePlayer's angles. Active from the start,
    blended in over transition_time_s; `stop()` blends back to the plain plan."""

    name = "abc"
    description = "AutoBalancer: gait, preview-control COG, hand-force offset, whole-body IK"

    def __init__(self, initial: Reference, dt_s: float, params: AutoBalancerParams | None = None,
                 kinematics: RobotKinematics | None = None, active: bool = True) -> None:
        super().__init__()
        self.params = params or AutoBalancerParams()
        self.dt_s = dt_s
        self.kin = kinematics or RobotKinematics()
        self.ik = FullbodyIK(self.kin)
        self.total_mass = self.kin.total_mass
        self.kin.update_rpy(initial.base_pos_world, initial.base_rpy_rad, initial.q_rad)
        self.rsole = self.kin.frame_pose("rleg_end")
        self.lsole = self.kin.frame_pose("lleg_end")
        com = self.kin.com_world()
        ground_z = 0.5 * (self.rsole[0][2] + self.lsole[0][2])
        self.com_height_m = float(com[2] - ground_z)
        self.preview = PreviewController(PreviewControlParams(
            dt_s=dt_s, com_height_m=self.com_height_m, q=self.params.preview_q, r=self.params.preview_r))
        target = self.standing_zmp()
        self.preview.reset(target[:2])
        self.queue = PreviewQueue(self.preview.preview_length, target[:2])
        self._hand_pos = np.zeros((2, 3))
        self._hand_frame_ids = [self.kin.model.getFrameId(n) for n in ("rarm_end", "larm_end")]
        # blend between the plain plan (0) and the balanced posture (1)
        self.active = False
        self._weight = 0.0
        self._blend = None  # (Segment, elapsed)
        self.has_ik_failed = False
        self.last_gait: GaitState | None = None
        if active:
            self.start()

    # ---- operations --------------------------------------------------------------------------
    def start(self) -> None:
        if self.active:
            raise InvalidState("AutoBalancer is already active")
        self.active = True
        self._blend = [hoff_arbib(np.array([self._weight]), np.array([1.0]), self.params.transition_time_s), 0.0]

    def stop(self) -> None:
        if not self.active:
            raise InvalidState("AutoBalancer is not active")
        self.active = False
        self._blend = [hoff_arbib(np.array([self._weight]), np.array([0.0]), self.params.transition_time_s), 0.0]

    def set_params(self, params: AutoBalancerParams) -> None:
        self.params = params

    # ---- pieces ----------------------------------------------------------------------------------
    def standing_zmp(self) -> np.ndarray:
        """Mid-point of the two sole frames plus the per-foot offset, (3,) [m]."""
        off = np.array([self.params.zmp_offset_x_m, 0.0, 0.0])
        r = self.rsole[0] + self.rsole[1] @ (off - [0.0, self.params.zmp_offset_y_m, 0.0])
        left = self.lsole[0] + self.lsole[1] @ (off + [0.0, self.params.zmp_offset_y_m, 0.0])
        return 0.5 * (r + left)

    def _hand_force_offset(self, ref: Reference, cog_pc_xy: np.ndarray, zmp_z: float) -> np.ndarray:
        if not self.params.use_hand_force_offset:
            return cog_pc_xy
        f = ref.wrenches[list(HANDS), :3]
        if not np.any(f):
            return cog_pc_xy
        return cog_offset_against_hand_forces(cog_pc_xy, self.total_mass, self._hand_pos, f, zmp_z, G)

    # ---- tick ------------------------------------------------------------------------------------
    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        if self._blend is not None:
            seg, elapsed = self._blend
            elapsed = min(elapsed + ctx.dt_s, seg.duration_s)
            self._weight = float(seg.sample(elapsed)[0][0])
            self._blend = None if elapsed >= seg.duration_s else [seg, elapsed]
        if self._weight <= 0.0 and not self.active:
            self.last_gait = None
            return ref
        zmp = self.standing_zmp()
        self.queue.push(zmp[:2])
        cog_xy, cog_vel_xy, _, _ = self.preview.update(self.queue.view)
        cog_abc_xy = self._hand_force_offset(ref, cog_xy, zmp[2])
        R_body = rpy_to_matrix(ref.base_rpy_rad)
        res = self.ik.solve(ref.q_rad, float(ref.base_pos_world[2]), R_body, cog_abc_xy, self.rsole, self.lsole)
        self.has_ik_failed = not res.reachable
        for i, fid in enumerate(self._hand_frame_ids):
            self._hand_pos[i] = pin.updateFramePlacement(self.kin.model, self.kin.data, fid).translation
        gait = GaitState(
            walking=False, support="both", contact=(True, True),
            p_rsole_world=self.rsole[0], R_rsole_world=self.rsole[1],
            p_lsole_world=self.lsole[0], R_lsole_world=self.lsole[1],
            zmp_world=zmp, cog_world=np.array([cog_abc_xy[0], cog_abc_xy[1], res.com_world[2]]),
            cog_vel_world=np.array([cog_vel_xy[0], cog_vel_xy[1], 0.0]),
            cog_pc_world=np.array([cog_xy[0], cog_xy[1], res.com_world[2]]),
        )
        self.last_gait = gait
        w = self._weight
        q = res.q_rad if w >= 1.0 else (1.0 - w) * ref.q_rad + w * res.q_rad
        base = res.base_pos_world if w >= 1.0 else (1.0 - w) * ref.base_pos_world + w * res.base_pos_world
        zmp_base = R_body.T @ (zmp - base)
        return ref.with_(q_rad=q, base_pos_world=base, zmp_base=zmp_base, gait=gait)

    def status(self) -> dict:
        g = self.last_gait
        return {"enabled": self.enabled, "active": self.active, "weight": round(self._weight, 4),
                "walking": bool(g.walking) if g else False, "support": g.support if g else "both",
                "has_ik_failed": self.has_ik_failed}
