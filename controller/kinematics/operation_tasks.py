"""The operation IK's tasks: one class per operational point (hand frame, gaze, waist) that servoes its placo
tasks one bounded step toward its target and reports what it achieved, and the joint step bounds."""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np

from controller.kinematics.operation_geometry import clip3, clip3_flagged, dot3, split_pose, sub3
from controller.kinematics.operation_params import OperationIKParams
from controller.kinematics.operation_targets import JOINT_LIMIT, REACH, VELOCITY, GazeTarget, HandTarget, WaistTarget
from controller.kinematics.rotations import (
    rows_angle_between,
    rows_exp3,
    rows_log3,
    rows_mul,
    rows_small_log3,
    rows_tmul,
    rows_tmulv,
)
from robot.names import END_EFFECTORS, JOINT_GROUPS, JOINT_NAMES

#: Frames in the URDF (robot/hrp2/hrp2.urdf).
HAND_FRAMES = {"rhand": END_EFFECTORS["rarm"], "lhand": END_EFFECTORS["larm"]}
FOOT_FRAMES = (END_EFFECTORS["rleg"], END_EFFECTORS["lleg"])
BODY_FRAME = "BODY"
CHEST_FRAME = "CHEST_LINK1"  # the gaze angles are relative to this link
HEAD_FRAME = "HEAD_LINK1"  # gaze axis: its x axis (the URDF has no camera frames)
NECK_FRAME = "HEAD_LINK0"  # its origin is on both head axes: where the gaze ray starts

_GRIPPERS = (JOINT_NAMES.index("RARM_JOINT6"), JOINT_NAMES.index("LARM_JOINT6"))  # never move a hand frame
ARM_JOINTS = {"rhand": tuple(i for i in JOINT_GROUPS["rarm"] if i not in _GRIPPERS),
              "lhand": tuple(i for i in JOINT_GROUPS["larm"] if i not in _GRIPPERS)}
TORSO_JOINTS = JOINT_GROUPS["torso"]
HEAD_JOINTS = JOINT_GROUPS["head"]
LEG_JOINTS = JOINT_GROUPS["rleg"] + JOINT_GROUPS["lleg"]
#: The control joints of each point ([OP] Eq. 1, theta_cl): any at the velocity limit explains a slowdown.
CHAINS: dict[str, tuple[int, ...]] = {"rhand": TORSO_JOINTS + ARM_JOINTS["rhand"],
                                      "lhand": TORSO_JOINTS + ARM_JOINTS["lhand"], "head": HEAD_JOINTS,
                                      "waist": LEG_JOINTS}
#: The point's own limb: one of these braking at its position limit explains a slowdown as "joint_limit";
#: the torso's limits (which extend the hands' workspace) count as the edge of the reach.
LIMBS: dict[str, tuple[int, ...]] = {"rhand": ARM_JOINTS["rhand"], "lhand": ARM_JOINTS["lhand"], "head": HEAD_JOINTS,
                                     "waist": LEG_JOINTS}


class SolverView(Protocol):
    """What a task reads of the solver (OperationIK): its parameters, placo's robot after the last forward
    kinematics pass (`fk_count`), the configuration `q` (nq,), and BODY's height and orientation tasks."""

    params: OperationIKParams
    robot: Any  # placo.RobotWrapper
    fk_count: int
    q: np.ndarray
    body_z_task: Any
    body_R_task: Any

    def head_angles(self) -> tuple[float, float]: ...

    def base_pose(self) -> tuple[float, tuple]: ...


class PointTask:
    """One operational point: its placo tasks, its servo step toward its target (`servo`, before the solve),
    what it achieved (`result`: the pose, the errors, the scale of the requested step it did)."""

    name = ""

    def __init__(self) -> None:
        self.tasks: tuple = ()
        self.requested: tuple = ()
        self.chain_list = CHAINS[self.name]
        self.limb_set = frozenset(LIMBS[self.name])
        self.bound_rows: tuple | None = None  # the chain's joint limits, as StepBounds.limit_reason reads them

    def add(self, solver) -> None:  # noqa: B027 - the waist has no task of its own
        """Create the placo tasks (the point became active)."""

    def remove(self, solver) -> None:
        for task in self.tasks:
            solver.remove_task(task)
        self.tasks = ()

    def configure(self, p: OperationIKParams) -> None:  # noqa: B027
        """Task weights from the parameters."""

    @staticmethod
    def scale(dz_ach: float, dz_req: float, dp_ach, dp_req, w_ach, w_req, p: OperationIKParams) -> float:
        """The achieved step projected on the requested one, as a fraction of it, in [0, 1]: translation
        (a height dz and/or a 3-vector dp [m]) and rotation (w [rad], counted as angle x scale_length_m);
        a request under the deadband is nothing asked (1)."""
        L2 = p.scale_length_m * p.scale_length_m
        rr = dz_req * dz_req + L2 * dot3(w_req, w_req)
        ar = dz_ach * dz_req + L2 * dot3(w_ach, w_req)
        if dp_req is not None:
            rr += dot3(dp_req, dp_req)
            ar += dot3(dp_ach, dp_req)
        if rr <= p.scale_deadband_m * p.scale_deadband_m:
            return 1.0
        return min(1.0, max(0.0, ar / rr))


class HandFrameTask(PointTask):
    """A hand frame (rarm_end / larm_end) toward its pose: placo position and orientation tasks."""

    def __init__(self, name: str) -> None:
        self.name = name
        super().__init__()
        self.frame = HAND_FRAMES[name]
        self.T: np.ndarray | None = None  # pose after the last solve, and as nested lists
        self.T_rows: list | None = None
        self.T_fk = -1  # the forward-kinematics pass it was read in
        self.servo_key: tuple = (None, None)  # the target the position / orientation tasks hold, if unclipped

    def add(self, solver) -> None:
        frame = solver.add_frame_task(self.frame, np.eye(4))
        self.tasks = (frame.position(), frame.orientation())
        self.servo_key = (None, None)

    def configure(self, p: OperationIKParams) -> None:
        self.tasks[0].configure(f"{self.name}_position", "soft", p.hand_position_weight)
        self.tasks[1].configure(f"{self.name}_orientation", "soft", p.hand_orientation_weight)

    def servo(self, ik: SolverView, target: HandTarget) -> None:
        p, dt = ik.params, ik.params.dt_s
        rows = self.T_rows if self.T_fk == ik.fk_count else ik.robot.get_T_world_frame(self.frame).tolist()
        p0, R0 = split_pose(rows)
        pt, Rt = target.rows
        dp, clipped_p = clip3_flagged(sub3(pt, p0), p.hand_speed_m_s * dt)
        w, clipped_w = clip3_flagged(rows_log3(rows_tmul(R0, Rt)), p.hand_angular_speed_rad_s * dt)
        # the target itself when it is within one step (no conversion), else one step toward it
        if clipped_p:
            self.tasks[0].target_world = np.array((p0[0] + dp[0], p0[1] + dp[1], p0[2] + dp[2]))
        elif self.servo_key[0] is not target:
            self.tasks[0].target_world = target.p_world
        if clipped_w:
            self.tasks[1].R_world_frame = np.array(rows_mul(R0, rows_exp3(w)))
        elif self.servo_key[1] is not target:
            self.tasks[1].R_world_frame = target.R_world
        self.servo_key = (None if clipped_p else target, None if clipped_w else target)
        self.requested = (p0, R0, dp, w)

    def result(self, ik: SolverView, target: HandTarget, lean: bool = False) -> tuple:
        T = self.T = ik.robot.get_T_world_frame(self.frame)
        rows = self.T_rows = T.tolist()
        self.T_fk = ik.fk_count
        p1, R1 = split_pose(rows)
        p0, R0, dp, w = self.requested
        scale = self.scale(0.0, 0.0, sub3(p1, p0), dp, rows_small_log3(rows_tmul(R0, R1)), w, ik.params)
        if lean:
            return T, None, None, scale
        pt, Rt = target.rows
        return T, math.dist(pt, p1), rows_angle_between(R1, Rt), scale


class GazeTask(PointTask):
    """Gaze. HEAD_LINK1 is exactly Rz(HEAD_JOINT0) Ry(HEAD_JOINT1) in CHEST_LINK1 (no origin rotations in the
    URDF), so the chest-relative gaze angles are the two head joint targets: a two-joint task is the exact
    gaze task, and cheaper than an orientation task."""

    name = "head"
    _JOINTS = tuple(JOINT_NAMES[i] for i in HEAD_JOINTS)

    def add(self, solver) -> None:
        self.tasks = (solver.add_joints_task(),)
        self.goal: tuple[float, float] | None = None

    def configure(self, p: OperationIKParams) -> None:
        self.tasks[0].configure("head", "soft", p.head_weight)

    def servo(self, ik: SolverView, target: GazeTarget) -> None:
        q_yaw, q_pitch = ik.head_angles()
        if target.look_at_world is not None:
            # the point in the chest frame: R_world_neck = R_world_chest Rz(q_yaw), from the neck's origin
            p_neck, R_neck = split_pose(ik.robot.get_T_world_frame(NECK_FRAME).tolist())
            d = rows_tmulv(R_neck, sub3(target.look_at_world.tolist(), p_neck))
            c, s = math.cos(q_yaw), math.sin(q_yaw)
            dx, dy, dz = c * d[0] - s * d[1], s * d[0] + c * d[1], d[2]
            yaw, pitch = math.atan2(dy, dx), math.atan2(-dz, math.hypot(dx, dy))
        else:
            yaw, pitch = target.yaw_rad, target.pitch_rad
        (d_yaw, d_pitch, _), _ = clip3_flagged((yaw - q_yaw, pitch - q_pitch, 0.0),
                                               ik.params.head_angular_speed_rad_s * ik.params.dt_s)
        goal = (q_yaw + d_yaw, q_pitch + d_pitch)
        if goal != self.goal:
            task = self.tasks[0]
            for joint, value, last in zip(self._JOINTS, goal, self.goal or (None, None), strict=True):
                if value != last:  # one joint at a time: no dict to convert
                    task.set_joint(joint, value)
            self.goal = goal
        self.requested = (q_yaw, q_pitch, d_yaw, d_pitch, yaw, pitch)

    def result(self, ik: SolverView, target: GazeTarget, lean: bool = False) -> tuple:
        yaw1, pitch1 = ik.head_angles()
        q_yaw, q_pitch, d_yaw, d_pitch, yaw, pitch = self.requested
        scale = self.scale(0.0, 0.0, None, None, (yaw1 - q_yaw, pitch1 - q_pitch, 0.0), (d_yaw, d_pitch, 0.0),
                           ik.params)
        if lean:
            return ik.robot.get_T_world_frame(HEAD_FRAME), None, None, scale
        # the angle between the achieved and the wanted gaze axes
        c = (math.cos(yaw1 - yaw) * math.cos(pitch1) * math.cos(pitch) + math.sin(pitch1) * math.sin(pitch))
        return ik.robot.get_T_world_frame(HEAD_FRAME), 0.0, math.acos(max(-1.0, min(1.0, c))), scale


class WaistTask(PointTask):
    """BODY height and orientation. Its tasks always exist: they hold the reference when it is not operated."""

    name = "waist"

    def servo(self, ik: SolverView, target: WaistTarget) -> None:
        p, dt = ik.params, ik.params.dt_s
        z0, R0 = ik.base_pose()
        step = p.waist_speed_m_s * dt
        dz = max(-step, min(step, target.height_m - z0))
        w = clip3(rows_log3(rows_tmul(R0, target.R_rows)), p.waist_angular_speed_rad_s * dt)
        ik.body_z_task.target_world = np.array((0.0, 0.0, z0 + dz))
        ik.body_R_task.R_world_frame = np.array(rows_mul(R0, rows_exp3(w)))
        self.requested = (z0, R0, dz, w)

    def result(self, ik: SolverView, target: WaistTarget, lean: bool = False) -> tuple:
        z1, R1 = ik.base_pose()
        z0, R0, dz, w = self.requested
        scale = self.scale(z1 - z0, dz, None, None, rows_small_log3(rows_tmul(R0, R1)), w, ik.params)
        x, y, _ = ik.q[:3].tolist()
        T = np.array((R1[0] + (x,), R1[1] + (y,), R1[2] + (z1,), (0.0, 0.0, 0.0, 1.0)))
        return T, abs(target.height_m - z1), rows_angle_between(R1, target.R_rows), scale


class StepBounds:
    """The joint limits as one hard constraint A q <= b on the free joints, rows [upper; lower]: each step at
    most the velocity limit, and braking toward the position limits (a step covers at most k = dt / braking
    time of the distance left). Also says which limit held a point back."""

    def __init__(self, idx_q: np.ndarray, q_lower: np.ndarray, q_upper: np.ndarray) -> None:
        """idx_q (30,): where each JOINT_NAMES joint sits in placo's configuration; q_lower, q_upper (30,) [rad]."""
        self.idx_q, self.q_lower, self.q_upper = idx_q, q_lower, q_upper
        self._idx_q_list, self._lower, self._upper = idx_q.tolist(), q_lower.tolist(), q_upper.tolist()
        self.constraint = None  # placo's half-spaces constraint, rebuilt with the free joints

    def rebuild(self, solver, free: np.ndarray, nq: int, params: OperationIKParams) -> None:
        """The constraint on the joints `free` (JOINT_NAMES indices), in the form b = min((1 - k) Q + K,
        Q + step) with Q = [q; -q], K = k [upper; -lower], k = dt / braking time."""
        free_q = self.idx_q[free]
        n = len(free_q)
        self._bound_q = np.concatenate((free_q, free_q))
        self._bound_sign = np.concatenate((np.ones(n), -np.ones(n)))
        k = min(1.0, params.dt_s / params.joint_limit_braking_time_s)  # k <= 1: never past a limit
        self.k = k
        self._bound_K = k * np.concatenate((self.q_upper[free], -self.q_lower[free]))
        if self.constraint is not None:
            solver.remove_constraint(self.constraint)
        self._bound_sign_k = (1.0 - k) * self._bound_sign
        self._bound_step = (None, None)
        A = np.zeros((2 * n, nq))
        A[np.arange(2 * n), self._bound_q] = self._bound_sign
        self.constraint = solver.add_joint_space_half_spaces_constraint(A, np.zeros(2 * n))
        self.constraint.configure("step_bounds", "hard", 1.0)

    def update(self, q: np.ndarray, step: float) -> None:
        """The step bounds' b for this tick: b = min((1 - k) Q + K, Q + step), Q = [q; -q] on the free joints
        ((1 - k) and step as arrays: a float scalar costs a numpy operation as much as the operation)."""
        if self._bound_step[0] != step:
            self._bound_step = (step, np.full(len(self._bound_q), step))
        qi = q[self._bound_q]
        b = qi * self._bound_sign_k  # (1 - k) Q
        b += self._bound_K
        Q = qi * self._bound_sign
        Q += self._bound_step[1]
        np.minimum(b, Q, out=b)
        self.constraint.b = b

    def limit_reason(self, point: PointTask, q_prev: list, q_new: list, step: float) -> str:
        """JOINT_LIMIT if a joint of the point's own limb is braking at (or sits at) its position limit,
        VELOCITY if a joint of its chain runs at the velocity limit, else REACH. A joint is at a bound when
        its step came within 2 % (1e-7 rad at least) of it; which term of the bound was the smaller says
        which limit it is."""
        k = self.k
        rows = point.bound_rows
        if rows is None:  # (placo index, upper, lower, in the limb) per chain joint, once
            rows = point.bound_rows = tuple((self._idx_q_list[i], self._upper[i], self._lower[i], i in point.limb_set)
                                            for i in point.chain_list)
        velocity = False
        for j, hi, lo, in_limb in rows:  # (conditionals, not min/max calls: this runs per joint)
            q0 = q_prev[j]
            dq = q_new[j] - q0
            up, down = k * (hi - q0), k * (q0 - lo)  # allowed steps
            if up > step:
                up = step
            if down > step:
                down = step
            tol = 0.02 * (up if up >= 0.0 else -up)
            if dq >= up - (tol if tol > 1e-7 else 1e-7):
                braking = up < step
            else:
                tol = 0.02 * (down if down >= 0.0 else -down)
                if -dq >= down - (tol if tol > 1e-7 else 1e-7):
                    braking = down < step
                else:
                    continue
            if braking and in_limb:
                return JOINT_LIMIT
            velocity = velocity or not braking
        return VELOCITY if velocity else REACH
