"""The one limb IK: damped least squares on the model's Jacobian, joint limits enforced (hrpsys setTargetPose,
the ImpedanceController's hand, the experiments' grasp planners).

A target is either a full pose of the end frame (`PoseTarget`) or a point of the end frame at a position
with one of the frame's axes kept perpendicular to a world direction (`PointAxisTarget`: a knob held across
its axis, the turn about the closing direction left free). The maths of one step is
`damped_least_squares_step_rad`; `solve_limb_ik` iterates it on a `LimbKinematics` (the model's RobotKinematics,
whose `limb_ik` is setTargetPose on it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Protocol

import numpy as np
import pinocchio as pin

from controller.core.layer import Params


class LimbKinematics(Protocol):
    """What the solver needs of a kinematic model (controller.kinematics.model.RobotKinematics)."""

    idx_v: np.ndarray  # (30,) the joints' columns in a Jacobian
    q_lower: np.ndarray  # (30,) joint limits [rad]
    q_upper: np.ndarray  # (30,) [rad]

    def frame_jacobian(self, frame_id: int, base_pos_world, base_R_world, q_rad,
                       reference=pin.LOCAL) -> tuple[pin.SE3, np.ndarray]: ...


@dataclass(frozen=True)
class LimbIkParams(Params):
    """Iteration and damping of the solver; the defaults are hrpsys setTargetPose's."""

    #: postures evaluated at most (the seed is the first)
    max_iterations: int = field(default=50, metadata={"unit": "-", "min": 1, "max": 10000})
    #: lambda added to J J^T (units of the task error squared: m^2, rad^2)
    damping: float = field(default=1e-4, metadata={"unit": "-", "min": 0.0, "max": 1.0})
    #: the largest joint change of one iteration; a longer step is scaled down whole (its direction kept)
    max_step_rad: float = field(default=math.inf, metadata={"unit": "rad", "min": 1e-6})
    pos_tol_m: float = field(default=1e-4, metadata={"unit": "m", "min": 0.0})
    rot_tol_rad: float = field(default=1e-3, metadata={"unit": "rad", "min": 0.0})
    #: with a posture to draw toward: the fraction of the posture error taken per iteration (in the task's
    #: null space), and the step below which the posture counts as settled (the solve ends there)
    posture_gain: float = field(default=0.0, metadata={"unit": "-", "min": 0.0, "max": 1.0})
    settle_step_rad: float = field(default=0.0, metadata={"unit": "rad", "min": 0.0})


@dataclass(frozen=True)
class LimbIkSolution:
    """The posture (30,) [rad]: the one that reached the target, or the closest one found."""

    q_rad: np.ndarray
    reached: bool
    pos_error_m: float
    rot_error_rad: float
    iterations: int


@dataclass(frozen=True)
class PoseTarget:
    """The end frame at position `p_world_m` [m] with rotation `R_world_frame` (world <- frame).

    Task error: the twist log6(M_world_frame^-1 M_world_target), in the end frame [m, rad]."""

    p_world_m: np.ndarray
    R_world_frame: np.ndarray
    reference_frame = pin.LOCAL  # the Jacobian the task is written with

    @cached_property
    def M_world_target(self) -> pin.SE3:
        return pin.SE3(np.asarray(self.R_world_frame, dtype=float), np.asarray(self.p_world_m, dtype=float))

    def task(self, M_world_frame: pin.SE3, J_local: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(error (6,) [m, rad] in the end frame, its Jacobian (6, n))."""
        return pose_error_local(M_world_frame, self.M_world_target), J_local

    @staticmethod
    def residual(error: np.ndarray) -> tuple[float, float]:
        return float(np.linalg.norm(error[:3])), float(np.linalg.norm(error[3:]))


@dataclass(frozen=True)
class PointAxisTarget:
    """The point `point_in_frame_m` [m] of the end frame at `p_world_m` [m], the end frame's `axis_in_frame`
    (unit) perpendicular to the world direction `normal_world` (unit); the rest of the orientation is free.

    Task error: the point's miss [m] in world axes and -(axis . normal) (the sine of the axis's angle from
    perpendicular, ~rad)."""

    p_world_m: np.ndarray
    point_in_frame_m: np.ndarray
    axis_in_frame: np.ndarray
    normal_world: np.ndarray
    reference_frame = pin.LOCAL_WORLD_ALIGNED

    def task(self, M_world_frame: pin.SE3, J_world_aligned: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(error (4,) [m, ~rad], its Jacobian (4, n)), from the frame's Jacobian in world axes at its origin."""
        return point_axis_task_world(M_world_frame.translation, M_world_frame.rotation, J_world_aligned,
                                     self.p_world_m, self.point_in_frame_m, self.axis_in_frame, self.normal_world)

    @staticmethod
    def residual(error: np.ndarray) -> tuple[float, float]:
        return float(np.linalg.norm(error[:3])), float(abs(error[3]))


def pose_error_local(M_world_frame: pin.SE3, M_world_target: pin.SE3) -> np.ndarray:
    """The twist (6,) [m, rad] in the frame that moves the frame onto the target in unit time."""
    return pin.log6(M_world_frame.actInv(M_world_target)).vector


def point_axis_task_world(p_world_frame_m: np.ndarray, R_world_frame: np.ndarray, J_world_aligned: np.ndarray,
                          p_world_target_m: np.ndarray, point_in_frame_m: np.ndarray, axis_in_frame: np.ndarray,
                          normal_world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Error (4,) and Jacobian (4, n) of "this point of the frame at the target, this axis perpendicular to
    the normal". `J_world_aligned` (6, n): the frame origin's linear velocity and the angular velocity, in
    world axes. Rows 0-2: target minus point [m]; row 3: -(axis_world . normal_world)."""
    offset_world_m = R_world_frame @ point_in_frame_m
    axis_world = R_world_frame @ axis_in_frame
    J_lin, J_ang = J_world_aligned[:3], J_world_aligned[3:]
    # the point moves with v + w x offset; the axis with w x axis, so d(axis . normal) = (axis x normal) . w
    jacobian = np.vstack([J_lin - pin.skew(offset_world_m) @ J_ang, (np.cross(axis_world, normal_world) @ J_ang)[None]])
    error = np.concatenate([p_world_target_m - p_world_frame_m - offset_world_m, [-(axis_world @ normal_world)]])
    return error, jacobian


def damped_least_squares_step_rad(jacobian: np.ndarray, error: np.ndarray, damping: float,
                                  posture_step_rad: np.ndarray | None = None,
                                  max_step_rad: float = math.inf) -> np.ndarray:
    """Joint step dq [rad] = J^+ e + (I - J^+ J) d_posture with J^+ = J^T (J J^T + damping I)^-1: the damped
    least-squares step toward the task, plus the posture step projected into the task's null space; scaled
    down whole so that no joint moves more than `max_step_rad`."""
    JJt = jacobian @ jacobian.T + damping * np.eye(len(error))
    dq = jacobian.T @ np.linalg.solve(JJt, error)
    if posture_step_rad is not None:
        dq = dq + posture_step_rad - jacobian.T @ np.linalg.solve(JJt, jacobian @ posture_step_rad)
    if math.isfinite(max_step_rad):
        dq *= min(1.0, max_step_rad / max(np.abs(dq).max(), 1e-12))
    return dq


def solve_limb_ik(kin: LimbKinematics, joints, frame_id: int, target: PoseTarget | PointAxisTarget,
                  q_seed_rad, base_pos_world, base_R_world, params: LimbIkParams = LimbIkParams(),
                  posture_rad: np.ndarray | None = None) -> LimbIkSolution:
    """Move the `joints` (indices into JOINT_NAMES) from the seed (30,) [rad] until the end frame `frame_id`
    meets `target` within tolerance, the base fixed at `base_pos_world`, `base_R_world`.

    Without a posture the solve ends at the first posture within tolerance; with `posture_rad` (for the
    joints) it goes on drawing the joints toward it until the step settles below `params.settle_step_rad`.
    Not reached within `params.max_iterations` postures (or settled outside tolerance): the closest posture
    evaluated, `reached` False. Afterwards `kin` holds the joint placements and the end frame of the last
    posture evaluated (not all frames, not the COM)."""
    joints = np.asarray(joints)
    cols = kin.idx_v[joints]
    lower, upper = kin.q_lower[joints], kin.q_upper[joints]
    q_rad = np.array(q_seed_rad, dtype=float)
    best_q, best_norm, best_residual = q_rad.copy(), math.inf, (math.inf, math.inf)
    within, residual, it = False, (math.inf, math.inf), 0
    for it in range(1, params.max_iterations + 1):
        M_world_frame, J = kin.frame_jacobian(frame_id, base_pos_world, base_R_world, q_rad, target.reference_frame)
        error, jacobian = target.task(M_world_frame, J[:, cols])
        residual = target.residual(error)
        within = residual[0] < params.pos_tol_m and residual[1] < params.rot_tol_rad
        if within and posture_rad is None:
            break
        error_norm = float(np.linalg.norm(error))
        if error_norm < best_norm:
            best_q[:], best_norm, best_residual = q_rad, error_norm, residual
        if it == params.max_iterations:
            break
        posture_step = None if posture_rad is None else params.posture_gain * (posture_rad - q_rad[joints])
        dq = damped_least_squares_step_rad(jacobian, error, params.damping, posture_step, params.max_step_rad)
        if np.abs(dq).max() < params.settle_step_rad:
            break
        q_rad[joints] = np.clip(q_rad[joints] + dq, lower, upper)
    if within:
        return LimbIkSolution(q_rad, True, *residual, it)
    return LimbIkSolution(best_q, False, *best_residual, it)
