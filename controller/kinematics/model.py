"""The controller's kinematic model of HRP-2 (pinocchio on the URDF): frames, COM, subtree masses, IK."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pinocchio as pin

from controller.core.errors import InvalidCommand, UnknownName, Unreachable
from controller.kinematics.limb_ik import LimbIkParams, PoseTarget, solve_limb_ik
from controller.kinematics.rotations import rpy_to_matrix
from robot.names import (
    END_EFFECTORS,
    FORCE_SENSOR_NAMES,
    FORCE_SENSORS,
    JOINT_GROUPS,
    JOINT_NAMES,
    URDF,
)

#: Which limb group each end effector moves.
LIMB_OF_GROUP = {"rarm": "rarm", "larm": "larm", "rleg": "rleg", "lleg": "lleg"}


@lru_cache(maxsize=16)
def _limb_ik_params(max_iterations: int, pos_tol_m: float, rot_tol_rad: float) -> LimbIkParams:
    """limb_ik's solver parameters (validated once per combination: the ImpedanceController asks every tick)."""
    return LimbIkParams(max_iterations=max_iterations, pos_tol_m=pos_tol_m, rot_tol_rad=rot_tol_rad)


class RobotKinematics:
    """Pinocchio model with a free-flyer base; joint vectors are in JOINT_NAMES order.

    The URDF carries the sensor and end-effector frames (same names and places as the MJCF sites)."""

    def __init__(self, urdf_path=URDF) -> None:
        self.model = pin.buildModelFromUrdf(str(urdf_path), pin.JointModelFreeFlyer())
        self.data = self.model.createData()
        self.total_mass = float(sum(i.mass for i in self.model.inertias))
        self.idx_q = np.array([self.model.joints[self.model.getJointId(n)].idx_q for n in JOINT_NAMES])
        self.idx_v = np.array([self.model.joints[self.model.getJointId(n)].idx_v for n in JOINT_NAMES])
        self.q_lower = self.model.lowerPositionLimit[self.idx_q].copy()
        self.q_upper = self.model.upperPositionLimit[self.idx_q].copy()
        self.frame_ids = {name: self.model.getFrameId(name)
                          for name in (*END_EFFECTORS.values(), *FORCE_SENSOR_NAMES, "BODY")}
        self.sensor_frame_ids = np.array([self.frame_ids[s] for s in FORCE_SENSOR_NAMES])
        # the joint whose subtree hangs below each sensor (pinocchio keeps subtree masses and COMs)
        self._below_joint = {sensor: self.model.frames[self.model.getFrameId(link)].parentJoint
                             for sensor, link in FORCE_SENSORS.items()}
        self.q = pin.neutral(self.model)
        self._neutral = pin.neutral(self.model)
        self._quat_key: bytes | None = None  # the rotation matrix (bytes) _quaternion last converted, and its result
        self._quat = np.zeros(4)

    # ---- configuration ------------------------------------------------------------------------
    def configuration(self, base_pos_world, base_R_world, q_rad) -> np.ndarray:
        q = self._neutral.copy()
        q[:3] = base_pos_world
        q[3:7] = self._quaternion(np.asarray(base_R_world))  # x, y, z, w
        q[self.idx_q] = q_rad
        return q

    def _quaternion(self, R: np.ndarray) -> np.ndarray:
        """pin.Quaternion(R).coeffs() (x, y, z, w), kept for the last float64 R: the AutoBalancer's IK asks for the
        same BODY rotation tick after tick (2 us a conversion, 0.1 us the comparison)."""
        if R.dtype != np.float64:
            return pin.Quaternion(R).coeffs()
        key = R.tobytes()
        if key != self._quat_key:
            self._quat = pin.Quaternion(R).coeffs().copy()
            self._quat_key = key
        return self._quat

    def update(self, base_pos_world, base_R_world, q_rad) -> None:
        """Forward kinematics, frame placements and COM for this configuration."""
        self.q = self.configuration(base_pos_world, base_R_world, q_rad)
        pin.forwardKinematics(self.model, self.data, self.q)
        pin.updateFramePlacements(self.model, self.data)
        # from the placements just computed (same result as passing q, without a second forward pass)
        pin.centerOfMass(self.model, self.data, pin.KinematicLevel.POSITION, True)  # True: subtree COMs too

    def update_joints(self, base_pos_world, base_R_world, q_rad) -> None:
        """update without the frame placements and the COM: joint placements only; read frames with
        `frame_homogeneous` (for a few frames, a fraction of the full update)."""
        self.q = self.configuration(base_pos_world, base_R_world, q_rad)
        pin.forwardKinematics(self.model, self.data, self.q)

    def update_rpy(self, base_pos_world, base_rpy_rad, q_rad) -> None:
        self.update(base_pos_world, rpy_to_matrix(base_rpy_rad), q_rad)

    def update_joints_rpy(self, base_pos_world, base_rpy_rad, q_rad) -> None:
        """update_rpy without the frame placements: joint placements and COMs only; read frames with
        `frame_homogeneous` (the same placement updateFramePlacements computes, for the frames needed)."""
        self.q = self.configuration(base_pos_world, rpy_to_matrix(base_rpy_rad), q_rad)
        pin.forwardKinematics(self.model, self.data, self.q)
        pin.centerOfMass(self.model, self.data, pin.KinematicLevel.POSITION, True)  # True: subtree COMs too

    def frame_homogeneous(self, frame_id: int) -> np.ndarray:
        """(4, 4) world <- frame after update_joints_rpy (the frame's placement is updated in data.oMf)."""
        return pin.updateFramePlacement(self.model, self.data, frame_id).homogeneous

    # ---- queries on the last update -------------------------------------------------------------
    def com_world(self) -> np.ndarray:
        return self.data.com[0].copy()

    def frame_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """(position (3,), rotation (3,3)) of a frame in the world."""
        fid = self.frame_ids.get(name)
        if fid is None:
            if not self.model.existFrame(name):
                raise InvalidCommand(f"unknown frame {name!r}; known: {sorted(self.frame_ids)}")
            fid = self.frame_ids[name] = self.model.getFrameId(name)
        M = self.data.oMf[fid]
        return M.translation.copy(), M.rotation.copy()

    def joint_below(self, sensor: str) -> int:
        """The pinocchio joint id whose subtree is the part below a force sensor (its `data.mass[j]` is that
        part's mass, and `data.com[j]` its COM in the joint's own frame, after an update: pinocchio keeps the
        subtree COMs of j > 0 in the joint frame, only com[0] in the world; `mass_below` gives it in the world)."""
        return self._below_joint[sensor]

    def mass_below(self, sensor: str) -> tuple[float, np.ndarray]:
        """Mass [kg] and world COM [m] of the links below a force sensor."""
        j = self._below_joint[sensor]
        M = self.data.oMi[j]
        return float(self.data.mass[j]), M.rotation @ self.data.com[j] + M.translation

    def frame_jacobian(self, frame_id: int, base_pos_world, base_R_world, q_rad,
                       reference=pin.LOCAL) -> tuple[pin.SE3, np.ndarray]:
        """One kinematic pass for this configuration: the frame's placement (world <- frame) and its Jacobian
        (6, nv) in `reference` (pin.LOCAL: the frame's axes; pin.LOCAL_WORLD_ALIGNED: world axes at the frame's
        origin). Only the joint placements and this frame are updated (not the other frames, not the COM)."""
        self.q = self.configuration(base_pos_world, base_R_world, q_rad)
        pin.computeJointJacobians(self.model, self.data, self.q)
        M_world_frame = pin.updateFramePlacement(self.model, self.data, frame_id)
        return M_world_frame, pin.getFrameJacobian(self.model, self.data, frame_id, reference)

    # ---- inverse kinematics ---------------------------------------------------------------------
    def limb_ik(self, group: str, q_init_rad, base_pos_world, base_rpy_rad, target_pos, target_R,
                frame: str | None = None, max_iter: int = 50, pos_tol_m: float = 1e-4,
                rot_tol_rad: float = 1e-3, best_effort: bool = False) -> np.ndarray:
        """Move only `group`'s joints so its end effector reaches the target (hrpsys setTargetPose).

        `frame` None: target in the world; otherwise in that link's frame (e.g. "BODY").
        `solve_limb_ik` with LimbIkParams' defaults; raises Unreachable if it does not converge, unless
        `best_effort`, which returns the closest posture it found. Afterwards only the joint placements and
        the end-effector frame of the last posture evaluated are up to date (not all frames).
        """
        if group not in LIMB_OF_GROUP:
            raise InvalidCommand(
                f"setTargetPose group {group!r} has no end effector; valid: {sorted(LIMB_OF_GROUP)}")
        base_R = rpy_to_matrix(base_rpy_rad)
        target = pin.SE3(np.asarray(target_R, dtype=float), np.asarray(target_pos, dtype=float))
        if frame is not None:
            if not self.model.existFrame(frame):
                raise UnknownName(f"unknown frame {frame!r}; e.g. BODY, CHEST_LINK1")
            self.update(base_pos_world, base_R, q_init_rad)
            target = self.data.oMf[self.model.getFrameId(frame)] * target
        params = _limb_ik_params(max_iter, pos_tol_m, rot_tol_rad)
        fid = self.frame_ids[END_EFFECTORS[LIMB_OF_GROUP[group]]]
        sol = solve_limb_ik(self, JOINT_GROUPS[group], fid, PoseTarget(target.translation, target.rotation),
                            q_init_rad, base_pos_world, base_R, params)
        if sol.reached or best_effort:
            return sol.q_rad
        raise Unreachable(
            f"setTargetPose: {group} cannot reach the target (closest: "
            f"{sol.pos_error_m * 1e3:.1f} mm, {np.rad2deg(sol.rot_error_rad):.2f} deg off) within joint limits"
        )


def frame_from_soles_midpoint(kin: RobotKinematics, base_rpy_rad, q_rad, frame: str):
    """(position [m], rotation) of `frame` relative to the midpoint of the two soles, BODY at the origin with the
    attitude `base_rpy_rad` (e.g. the KalmanFilter's) and the joints `q_rad` (e.g. the encoders): where the
    robot itself sees one of its points, in axes of the world's attitude (yaw as BODY's)."""
    kin.update_rpy(np.zeros(3), base_rpy_rad, q_rad)
    mid = 0.5 * (kin.frame_pose("rleg_end")[0] + kin.frame_pose("lleg_end")[0])
    p, R = kin.frame_pose(frame)
    return p - mid, R
