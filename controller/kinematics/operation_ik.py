"""Whole-body IK of the operation layer ([OP] III): hands, gaze, waist and balance on placo, one QP step per tick.

The solver adds up the tasks of controller.kinematics.operation_tasks (one per operated point, and the joint step
bounds), the feet, BODY and COM tasks of the whole-body mode or the COM guard of the upper-body mode, and a torso
posture. Targets and results: operation_targets; parameters: operation_params; plane geometry: operation_geometry.
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np
import pinocchio as pin
import placo

from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE
from controller.core.errors import InvalidCommand
from controller.core.types import read_only
from controller.kinematics.operation_geometry import GuardBox, SupportPolygon, sub3
from controller.kinematics.operation_params import OperationIKParams
from controller.kinematics.operation_targets import (
    JOINT_LIMIT,
    NO_POINTS,
    POINTS,
    REACH,
    SOLVER,
    VELOCITY,
    FeetPoses,
    GazeTarget,
    HandTarget,
    OperationIKResult,
    OperationTargets,
    PointResult,
    WaistTarget,
)
from controller.kinematics.operation_tasks import (
    ARM_JOINTS,
    BODY_FRAME,
    CHEST_FRAME,
    FOOT_FRAMES,
    HAND_FRAMES,
    HEAD_FRAME,
    HEAD_JOINTS,
    LEG_JOINTS,
    NECK_FRAME,
    TORSO_JOINTS,
    GazeTask,
    HandFrameTask,
    PointTask,
    StepBounds,
    WaistTask,
)
from controller.kinematics.rotations import quat_xyzw_to_rows, quat_xyzw_to_rpy, rows_tmulv, rpy_to_rows
from robot.names import JOINT_NAMES, URDF

#: Importable from here as before the split (the layer and the tests import some of them from this module).
__all__ = ["BODY_FRAME", "CHEST_FRAME", "FOOT_FRAMES", "HAND_FRAMES", "HEAD_FRAME", "JOINT_LIMIT", "NECK_FRAME",
           "POINTS", "REACH", "SOLVER", "VELOCITY", "FeetPoses", "GazeTarget", "HandTarget", "OperationIK",
           "OperationIKParams", "OperationIKResult", "OperationTargets", "PointResult", "WaistTarget"]

_COM_TARGET_INSET_M = 0.005  # the COM target stays this much deeper inside than the margin [m]
_TORSO_NAMES = tuple(JOINT_NAMES[i] for i in TORSO_JOINTS)
_TORSO_SLICE = slice(TORSO_JOINTS[0], TORSO_JOINTS[-1] + 1)
assert tuple(range(len(JOINT_NAMES))[_TORSO_SLICE]) == TORSO_JOINTS


class OperationIK:
    """placo KinematicsSolver on the HRP-2 URDF, warm-started between ticks (one QP step per tick).

    Every tick: the chains nobody operates follow the reference joint angles (rate-limited, masked out of
    the QP); the legs, the floating base and the operated chains solve one step: soles on their poses
    (soft, very high weight), each active point toward a servo target one bounded step from its pose
    toward its target, BODY height and orientation on the waist target (or held at the reference's), COM
    x-y held where it was at activation and, near the edge, inside the support polygon with a margin, the
    torso toward the reference posture. Hard: per-joint step bounds (velocity limit, braking near the
    position limits). A tick without active points returns its inputs untouched, without solving.
    """

    def __init__(self, urdf_path=URDF, params: OperationIKParams | None = None, upper_body: bool = False) -> None:
        """upper_body=True: the floating base and the legs stay where the caller puts them (the
        AutoBalancer owns them and balance); only the arms, torso and head solve, with no foot, BODY or COM
        task, the COM kept within com_guard_m of where it was at activation by a guard constraint; no
        waist point (the caller moves BODY itself)."""
        self.params = params or OperationIKParams()
        self.upper_body = upper_body
        self.robot = placo.RobotWrapper(str(urdf_path), placo.Flags.ignore_collisions)
        robot = self.robot
        missing = sorted(set(JOINT_NAMES) - set(robot.joint_names()))
        if missing:
            raise InvalidCommand(f"URDF {urdf_path} lacks joints {missing}; it must have all of JOINT_NAMES")
        self.nq = robot.model.nq
        #: where each JOINT_NAMES joint sits in placo's configuration (placo orders the joints by name)
        self.idx_q = np.array([robot.get_joint_offset(n) for n in JOINT_NAMES])
        self.q_lower = robot.model.lowerPositionLimit[self.idx_q].copy()
        self.q_upper = robot.model.upperPositionLimit[self.idx_q].copy()
        self._lower, self._upper = self.q_lower.tolist(), self.q_upper.tolist()
        self._head_q = tuple(int(self.idx_q[i]) for i in HEAD_JOINTS)
        self.solver = placo.KinematicsSolver(robot)
        solver = self.solver
        solver.enable_joint_limits(False)  # replaced by the step bounds (velocity limit and braking)
        solver.enable_velocity_limits(False)
        if upper_body:
            solver.mask_fbase(True)
            self._feet, self._foot_tasks = [], []
            self.body_z_task = self.body_R_task = self._com = None
        else:
            self._feet = [solver.add_frame_task(f, np.eye(4)) for f in FOOT_FRAMES]
            self._foot_tasks = [(t.position(), t.orientation()) for t in self._feet]
            self.body_z_task = solver.add_position_task(BODY_FRAME, np.zeros(3))
            self.body_z_task.mask.set_axises("z")
            self.body_R_task = solver.add_orientation_task(BODY_FRAME, np.eye(3))
            self._com = solver.add_com_task(np.zeros(3))
            self._com.mask.set_axises("xy")
        self._base_key: tuple | None = None  # upper-body mode: the base pose last written
        self._base_rows: tuple = (None, None)  # (base key, its rotation rows)
        self._base_arg: tuple = (None, None, None)  # (base position, rpy arrays, their key): last read
        self._base_arrays: tuple = (None, None, None)  # (base key, position, rpy): the result's arrays
        self._masked_settled: list | None = None  # the reference the masked chains have reached
        self._com_polygon = None  # the constraint (whole-body: while the COM is near the edge; upper body: the guard)
        self._guard_base: tuple | None = None  # upper-body mode: the base pose the guard's world box is for
        self._com_tracking = False  # the caller gives the COM target (com_track_weight)
        self._com_polygon_hard = True
        self._polygon: SupportPolygon | None = None
        self._polygon_key: tuple | None = None
        self._step_bounds = StepBounds(self.idx_q, self.q_lower, self.q_upper)  # rebuilt with the free joints
        self._posture = None
        self._posture_ref: list[float] | None = None
        self._hold: tuple | None = None  # the reference BODY height and rpy last written to the hold tasks
        self._points: dict[str, PointTask] = {"rhand": HandFrameTask("rhand"), "lhand": HandFrameTask("lhand"),
                                           "head": GazeTask(), "waist": WaistTask()}
        self._active: tuple[str, ...] = ()
        self._inactive = (True, True, True, True)  # per point of POINTS: not operated
        self._masked: list[tuple[int, int]] = []  # (JOINT_NAMES index, placo index) out of the QP
        self._free = np.arange(len(JOINT_NAMES))
        self._seeded = False
        self.q = np.zeros(self.nq)  # placo's configuration, as last written or solved
        self.fk_count = 0  # forward-kinematics passes so far: what cached poses refer to
        self._com_cache: tuple[int, list] = (-1, [0.0, 0.0, 0.0])
        self._feet_poses: FeetPoses | None = None
        self._com_ref = (0.0, 0.0)  # COM x-y target before the margin [m]: at activation, or the caller's
        self._configure_weights()

    def __repr__(self) -> str:
        return f"OperationIK(nq={self.nq}, active={list(self._active)}, params={self.params})"

    # ---- configuration ---------------------------------------------------------------------------
    def set_params(self, params: OperationIKParams) -> None:
        self.params = params
        self._configure_weights()
        if self._active:
            self._set_active(self._active, rebuild=True)  # the bounds' braking gain

    def _configure_weights(self) -> None:
        p = self.params
        self.solver.problem.regularization = p.damping_weight
        if self.upper_body:
            for name in self._active:
                self._points[name].configure(p)
            if self._posture is not None:
                self._posture.configure("posture", "soft", p.upper_body_posture_weight)
            if self._com_polygon is not None:
                self.solver.dt = p.dt_s
                self._com_polygon.omega = 1.0 / p.com_guard_braking_time_s
            if self._com_polygon is not None:
                self._com_polygon.margin = 0.0
                self._configure_com_polygon(True)
            self._polygon_key = None
            return
        for side, task in zip(("rfoot", "lfoot"), self._feet, strict=True):
            task.configure(side, "soft", p.foot_position_weight, p.foot_orientation_weight)
        self._com.configure("com", "soft", p.com_track_weight if self._com_tracking else p.com_weight)
        if "waist" in self._active:
            self.body_z_task.configure("waist_height", "soft", p.waist_height_weight)
            self.body_R_task.configure("waist_orientation", "soft", p.waist_orientation_weight)
        else:
            self.body_z_task.configure("hold_height", "soft", p.hold_height_weight)
            self.body_R_task.configure("hold_orientation", "soft", p.hold_orientation_weight)
        for name in self._active:
            self._points[name].configure(p)
        if self._posture is not None:
            self._posture.configure("posture", "soft", p.posture_weight)
        if self._com_polygon is not None:
            self._com_polygon.margin = p.com_margin_m
            self._configure_com_polygon(self._com_polygon_hard)
        self._polygon_key = None  # the margin polygon is rebuilt with the next feet

    def _set_active(self, active: tuple[str, ...], rebuild: bool = False) -> None:
        """Add and remove point tasks; mask the chains nobody operates; bounds and posture on the rest."""
        solver = self.solver
        for name in set(self._active) - set(active):
            self._points[name].remove(solver)
        for name in active:
            if name not in self._active:
                self._points[name].add(solver)
        self._active = active
        self._inactive = tuple(n not in active for n in POINTS)
        hands = [n for n in ("rhand", "lhand") if n in active]
        free = (set() if self.upper_body else set(LEG_JOINTS)) | (set(TORSO_JOINTS) if hands else set())
        free |= set(HEAD_JOINTS) if "head" in active else set()
        for name in hands:
            free |= set(ARM_JOINTS[name])
        for i, _ in self._masked:
            solver.unmask_dof(JOINT_NAMES[i])
        self._masked = [(i, int(self.idx_q[i])) for i in range(len(JOINT_NAMES)) if i not in free]
        for i, _ in self._masked:
            solver.mask_dof(JOINT_NAMES[i])
        self._free = np.array(sorted(free), dtype=int)
        self._step_bounds.rebuild(solver, self._free, self.nq, self.params)  # velocity limit, braking
        self._masked_settled = None
        # posture on the torso: the redundancy left once hands, feet, BODY and COM are set
        if not rebuild:
            if self._posture is not None:
                solver.remove_task(self._posture)
                self._posture = None
            if hands:
                self._posture = solver.add_joints_task()
            self._posture_ref = None
        self._configure_weights()

    def _configure_com_polygon(self, hard: bool) -> None:
        if hard:
            self._com_polygon.configure("com_polygon", "hard", 1.0)
        else:
            self._com_polygon.configure("com_polygon", "soft", self.params.com_polygon_weight)
        self._com_polygon_hard = hard

    # ---- joint order and state -------------------------------------------------------------------------
    def to_placo(self, q_rad, base_pos_world, R_world_base) -> np.ndarray:
        """(nq,) placo configuration from JOINT_NAMES-ordered joints [rad] and the BODY pose."""
        q = np.zeros(self.nq)
        q[:3] = base_pos_world
        q[3:7] = pin.Quaternion(np.asarray(R_world_base, dtype=float)).coeffs()  # x, y, z, w
        q[self.idx_q] = q_rad
        return q

    def from_placo(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(joints (30,) in JOINT_NAMES order [rad], BODY position (3,) [m], BODY rotation (3, 3))."""
        return q[self.idx_q].copy(), q[:3].copy(), np.array(quat_xyzw_to_rows(*q[3:7].tolist()))

    def head_angles(self) -> tuple[float, float]:
        """(HEAD_JOINT0, HEAD_JOINT1) [rad] in the current configuration."""
        return float(self.q[self._head_q[0]]), float(self.q[self._head_q[1]])

    def base_pose(self) -> tuple[float, tuple]:
        """(BODY height [m], BODY rotation rows) in the current configuration."""
        return float(self.q[2]), quat_xyzw_to_rows(*self.q[3:7].tolist())

    def _forward_kinematics(self) -> None:
        self.robot.update_kinematics()
        self.fk_count += 1

    def _com_now(self) -> list:
        if self._com_cache[0] != self.fk_count:
            self._com_cache = (self.fk_count, self.robot.com_world().tolist())
        return self._com_cache[1]

    # ---- per tick ----------------------------------------------------------------------------------
    def reset(self) -> None:
        """Forget the warm start: the next active solve starts from its inputs."""
        self._seeded = False

    def warm_start(self, q: np.ndarray) -> None:
        """Continue from the placo configuration `q` (nq,) (a copy of an earlier `self.q`), e.g. the
        posture an emergency stop reverted to; the next solve steps from there instead of its inputs."""
        self.q = np.array(q, dtype=float)
        self.robot.state.q = self.q
        self._forward_kinematics()
        self._seeded = True
        self._masked_settled = None

    def solve(self, q_rad: np.ndarray, base_pos_world: np.ndarray, base_rpy_rad: np.ndarray,
              targets: OperationTargets, feet: FeetPoses | None = None,
              com_xy_world: np.ndarray | None = None, lean: bool = False) -> OperationIKResult:
        """One tick: the posture realising `targets` one step further, from the last solution.

        q_rad (30,), base pose: the upstream reference. It seeds the warm start after an idle tick; the
        chains nobody operates and the torso posture follow it; BODY height and orientation are held at it
        without a waist target. feet: sole poses and contacts; None keeps the soles where the reference
        had them when the points became active. com_xy_world (2,) [m]: where to hold the COM (e.g. the
        AutoBalancer's planned COG, so that its BODY correction downstream stays small); None: where it
        was when the points became active. Either is moved into the support polygon's margin if outside.
        lean: the points' poses, scales and reasons only (their error_m, error_rad and the result's COM are
        None), for a caller that reads nothing else (the operation layer, every tick); the same posture.
        """
        if not targets.active:  # idle: a pass-through; the next active tick seeds afresh
            self._seeded = False
            return OperationIKResult(q_rad=q_rad, base_pos_world=base_pos_world, base_rpy_rad=base_rpy_rad,
                                     points=NO_POINTS, active=False)
        p = self.params
        robot = self.robot
        q_ref = np.asarray(q_rad, dtype=float).tolist()
        lower, upper = self._lower, self._upper
        seeding = not self._seeded
        seeding_base = False
        if seeding:
            q_clip = np.minimum(np.maximum(np.asarray(q_rad, dtype=float), self.q_lower), self.q_upper)
            self.q = self.to_placo(q_clip, base_pos_world, rpy_to_rows(*np.asarray(base_rpy_rad).tolist()))
            self._hold = None
        elif self.upper_body:  # the base where the caller has it now (the AutoBalancer moves it)
            key = self._base_key_of(base_pos_world, base_rpy_rad)
            if key != self._base_key:
                self.q[:3] = key[:3]
                self.q[3:7] = pin.Quaternion(np.array(rpy_to_rows(*key[3:]))).coeffs()
                self._base_key = None  # written below with the masked chains' forward kinematics
                seeding_base = True
        if self.upper_body and targets.waist is not None:
            raise InvalidCommand("OperationIK(upper_body=True) has no waist point: the caller moves BODY itself")
        active = self._active
        inactive = (targets.rhand is None, targets.lhand is None, targets.head is None, targets.waist is None)
        if inactive != self._inactive:
            active = tuple(n for n in POINTS if getattr(targets, n) is not None)
            self._set_active(active)
        q = self.q
        step = p.joint_velocity_limit_rad_s * p.dt_s
        # the chains nobody operates, and the grippers: toward the reference, no faster than the limit
        moved = seeding or seeding_base
        if seeding or q_ref != self._masked_settled:  # (settled on this reference: nothing left to move)
            settled = True
            for i, j in self._masked:
                d = min(upper[i], max(lower[i], q_ref[i])) - q[j]
                if d:
                    q[j] += d if -step <= d <= step else (step if d > 0.0 else -step)
                    moved = True
                    settled = False
            self._masked_settled = q_ref if settled else None
        if moved:
            robot.state.q = q
            self._forward_kinematics()
        if self.upper_body:
            return self._solve_upper_body(targets, q, q_ref, seeding, base_pos_world, base_rpy_rad, lean)
        if seeding:
            self._com_ref = tuple(self._com_now()[:2])
            if feet is None:  # the soles stay where the reference has them
                Tr, Tl = (robot.get_T_world_frame(f) for f in FOOT_FRAMES)
                feet = FeetPoses(Tr[:3, 3], Tr[:3, :3], Tl[:3, 3], Tl[:3, :3])
            self._polygon_key = None
        if feet is not None and feet is not self._feet_poses or self._polygon_key is None:
            self._set_feet(feet if feet is not None else self._feet_poses)
        if (com_xy_world is not None) != self._com_tracking:
            self._com_tracking = com_xy_world is not None
            self._com.configure("com", "soft", p.com_track_weight if self._com_tracking else p.com_weight)
        if com_xy_world is not None:
            com_ref = (float(com_xy_world[0]), float(com_xy_world[1]))
            if com_ref != self._com_ref:
                self._com_ref = com_ref
                self._set_com_target()
        self._seeded = True
        if self._posture is not None:  # torso posture toward the reference
            torso = q_ref[_TORSO_SLICE]
            if torso != self._posture_ref:
                self._posture.set_joints({n: min(upper[i], max(lower[i], q_ref[i]))
                                          for n, i in zip(_TORSO_NAMES, TORSO_JOINTS, strict=True)})
                self._posture_ref = torso
        for name in active:
            self._points[name].servo(self, getattr(targets, name))
        if targets.waist is None:  # BODY held at the reference
            hold = (float(base_pos_world[2]), *np.asarray(base_rpy_rad, dtype=float).tolist())
            if hold != self._hold:
                self.body_z_task.target_world = np.array((0.0, 0.0, hold[0]))
                self.body_R_task.R_world_frame = np.array(rpy_to_rows(*hold[1:]))
                self._hold = hold
        else:
            self._hold = None
        self._update_com_polygon()
        # step bounds on the free joints: velocity limit, and braking toward the position limits
        self._step_bounds.update(q, step)
        ok = True
        try:
            for it in range(p.iterations):
                if it:
                    self._forward_kinematics()
                self.solver.solve(True)
        except RuntimeError:  # placo's QPError: keep the previous tick's posture
            ok = False
            robot.state.q = q
        self._forward_kinematics()
        q_prev, self.q = q, robot.state.q.copy()  # the getter is a view on placo's state
        points = self._results(targets, q_prev, step, ok, lean)
        com = self._com_now()
        x, y, z = self.q[:3].tolist()
        return OperationIKResult(
            q_rad=read_only(self.q[self.idx_q]), base_pos_world=read_only(np.array((x, y, z))),
            base_rpy_rad=read_only(np.array(quat_xyzw_to_rpy(*self.q[3:7].tolist()))), points=MappingProxyType(points),
            active=True, ok=ok, com_world=read_only(np.array(com)), com_margin_m=self._polygon.margin(com[0], com[1]))

    def _solve_upper_body(self, targets, q, q_ref, seeding, base_pos_world, base_rpy_rad,
                          lean: bool = False) -> OperationIKResult:
        """The rest of solve() with the base and legs fixed: the points, the torso posture, the COM guard."""
        p, robot = self.params, self.robot
        lower, upper = self._lower, self._upper
        step = p.joint_velocity_limit_rad_s * p.dt_s
        self._base_key = self._base_key_of(base_pos_world, base_rpy_rad)
        if seeding:  # the guard around the COM as it is at activation, in the BODY frame
            x, y, _ = self._com_in_base()
            self._polygon = GuardBox(x, y, p.com_guard_m)
            if self._com_polygon is not None:
                self.solver.remove_constraint(self._com_polygon)
                self._com_polygon = None
        self._seeded = True
        if self._posture is not None:  # torso posture toward the reference
            torso = q_ref[_TORSO_SLICE]
            if torso != self._posture_ref:
                self._posture.set_joints({n: min(upper[i], max(lower[i], q_ref[i]))
                                          for n, i in zip(_TORSO_NAMES, TORSO_JOINTS, strict=True)})
                self._posture_ref = torso
        for name in self._active:
            self._points[name].servo(self, getattr(targets, name))
        # the guard: a hard constraint on c + dc/dt * T (com_guard_braking_time_s), the box in the world (the
        # guard is in the BODY frame), rebuilt when the base moves
        base = self._base_key
        if self._com_polygon is None or self._guard_base != base:
            R = rpy_to_rows(*base[3:])
            world = [np.array((base[0] + R[0][0] * v[0] + R[0][1] * v[1], base[1] + R[1][0] * v[0] + R[1][1] * v[1]))
                     for v in self._polygon.clockwise]
            if self._com_polygon is None:
                self.solver.dt = p.dt_s
                self._com_polygon = self.solver.add_com_polygon_constraint(world, 0.0)
                self._com_polygon.dcm = True
                self._com_polygon.omega = 1.0 / p.com_guard_braking_time_s
                self._configure_com_polygon(True)
            else:
                self._com_polygon.polygon = world
            self._guard_base = base
        self._step_bounds.update(q, step)
        ok = True
        try:
            for it in range(p.iterations):
                if it:
                    self._forward_kinematics()
                self.solver.solve(True)
        except RuntimeError:  # placo's QPError: keep the previous tick's posture
            ok = False
            robot.state.q = q
        self._forward_kinematics()
        q_prev, self.q = q, robot.state.q.copy()
        points = self._results(targets, q_prev, step, ok, lean)
        base = self._base_arrays
        if base[0] != self._base_key:  # the base arrays of the result, rebuilt when the base moves
            base = self._base_arrays = (self._base_key, read_only(np.array(self._base_key[:3])),
                                        read_only(np.array(self._base_key[3:])))
        if lean:  # (the COM: a placo call and the guard's margin, read by no lean caller)
            return OperationIKResult(q_rad=read_only(self.q[self.idx_q]), base_pos_world=base[1], base_rpy_rad=base[2],
                                     points=MappingProxyType(points), active=True, ok=ok)
        com = self._com_now()
        cx, cy, _ = self._com_in_base()
        return OperationIKResult(
            q_rad=read_only(self.q[self.idx_q]), base_pos_world=base[1], base_rpy_rad=base[2],
            points=MappingProxyType(points), active=True, ok=ok, com_world=read_only(np.array(com)),
            com_margin_m=self._polygon.margin(cx, cy))

    def _base_key_of(self, base_pos_world, base_rpy_rad) -> tuple[float, ...]:
        """The base pose as 6 floats; the last one again for the same two read-only arrays (the caller's
        constants, e.g. the upper-body caller's BODY frame origin)."""
        last = self._base_arg
        if base_pos_world is last[0] and base_rpy_rad is last[1]:
            return last[2]
        key = (*np.asarray(base_pos_world, dtype=float).tolist(), *np.asarray(base_rpy_rad, dtype=float).tolist())
        frozen = all(isinstance(a, np.ndarray) and not a.flags.writeable and a.base is None  # (no writeable base)
                     for a in (base_pos_world, base_rpy_rad))
        self._base_arg = (base_pos_world, base_rpy_rad, key) if frozen else (None, None, None)
        return key

    def _com_in_base(self) -> tuple[float, float, float]:
        """The COM in the BODY frame [m] (upper-body mode: the frame of the COM guard)."""
        base = self._base_key
        if self._base_rows[0] != base:
            self._base_rows = (base, rpy_to_rows(*base[3:]))
        return rows_tmulv(self._base_rows[1], sub3(self._com_now(), base[:3]))

    def _set_feet(self, feet: FeetPoses) -> None:
        last = self._feet_poses.sole_keys if self._feet_poses is not None else (None, None)
        for (pos_task, ori_task), pos, R, key, key_last in zip(
                self._foot_tasks, (feet.p_rsole_world, feet.p_lsole_world), (feet.R_rsole_world, feet.R_lsole_world),
                feet.sole_keys, last, strict=True):
            if key != key_last:  # only a sole that moved
                pos_task.target_world = pos
                ori_task.R_world_frame = R
        soles = tuple((pose, rect) for c, pose, rect in zip(feet.contact, feet.planar_soles,
                                                            (HRP2_RIGHT_SOLE, HRP2_LEFT_SOLE), strict=True) if c)
        key = tuple(pose for pose, _ in soles), feet.contact
        if key != self._polygon_key:
            # the COM target 5 mm deeper than the margin: the constraint guards, it is not active all along
            self._polygon = SupportPolygon(soles, self.params.com_margin_m + _COM_TARGET_INSET_M)
            self._polygon_key = key
            self._set_com_target()
            if self._com_polygon is not None:
                self._com_polygon.polygon = self._polygon.clockwise
        self._feet_poses = feet

    def _set_com_target(self) -> None:
        """The COM x-y target: the COM at activation, or the nearest point inside the margin if it is not."""
        x, y = self._polygon.nearest_safe(*self._com_ref)
        self._com.target_world = np.array((x, y, 0.0))

    def _update_com_polygon(self) -> None:
        """The support-polygon constraint only while the COM is within 1 cm of the margin (it cannot get
        across in one tick); hard while inside the margin, soft (always feasible) while outside it."""
        p = self.params
        com = self._com_now()
        margin = self._polygon.margin(com[0], com[1])
        if margin > p.com_margin_m + 0.01:
            if self._com_polygon is not None:
                self.solver.remove_constraint(self._com_polygon)
                self._com_polygon = None
            return
        hard = margin >= p.com_margin_m - 1e-4
        if self._com_polygon is None:
            self._com_polygon = self.solver.add_com_polygon_constraint(self._polygon.clockwise, p.com_margin_m)
            self._configure_com_polygon(hard)
        elif hard != self._com_polygon_hard:
            self._configure_com_polygon(hard)

    def _results(self, targets, q_prev, step, ok, lean: bool = False) -> dict[str, PointResult]:
        p = self.params
        out: dict[str, PointResult] = {}
        lists = None
        for name in self._active:
            point = self._points[name]
            T, error_m, error_rad, scale = point.result(self, getattr(targets, name), lean)
            limited = None
            if not ok:
                scale, limited = 0.0, SOLVER
            elif scale < p.limited_scale:
                lists = lists or (q_prev.tolist(), self.q.tolist())
                limited = self._step_bounds.limit_reason(point, *lists, step)
            out[name] = PointResult(T_world=read_only(T), error_m=error_m, error_rad=error_rad, scale=scale,
                                    limited=limited)
        return out
