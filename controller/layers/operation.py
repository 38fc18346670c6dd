"""OperationLayer ([OP] II-V, Eq. 5): the operator's and the behaviours' twists summed per operational point,
limited, integrated into targets in the feet frame F and realised by the whole-body IK on placo; the walking
point published for the AutoBalancer. Sits after the SequencePlayer and before the EmergencyStopper."""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from controller.core.errors import InvalidCommand
from controller.core.layer import Layer, Params, SharedStatus, Status, described, plain
from controller.core.types import Reference, TickContext
from controller.interpolation.blend import Transition
from controller.kinematics.fullbody_ik import FullbodyIK
from controller.kinematics.model import RobotKinematics
from controller.kinematics.operation_ik import (
    FeetPoses,
    GazeTarget,
    HandTarget,
    OperationIK,
    OperationTargets,
    WaistTarget,
)
from controller.kinematics.rotations import matrix_to_rpy, rpy_to_matrix
from controller.operation.deadman import deadman_factor
from controller.operation.limits import MOTION_STOP, VELOCITY, clamp_to_achieved, limit_twist
from controller.operation.points import (
    POINTS,
    ZERO_TWIST,
    OperationView,
    PointPose,
    Twist,
    WalkCommand,
    check_twist,
    sum_per_point,
)
from controller.operation.targets import GazeAngles, HandPose, WaistPose, feet_frame, yaw_rotation

IK_POINTS = ("rhand", "lhand", "head", "waist")  # the points the IK realises ("walk" goes to the AutoBalancer)
_FRAMES = {"rhand": "rarm_end", "lhand": "larm_end", "head": "HEAD_LINK1", "waist": "BODY"}
_NECK = "HEAD_LINK0"  # the gaze ray's origin
_LOOK_AT_DISTANCE_M = 100.0  # a gaze direction becomes a point this far along it (neck drift: < 0.03 deg)


@dataclass(frozen=True)
class OperationParams(Params):
    """Per-point speed limits (one scale factor per point keeps the direction), the dead-man, the blends."""

    hand_speed_m_s: float = field(default=0.3, metadata={"unit": "m/s", "min": 0.001, "max": 1.0})
    hand_angular_speed_rad_s: float = field(default=1.0, metadata={"unit": "rad/s", "min": 0.001, "max": 5.0})
    head_angular_speed_rad_s: float = field(default=1.5, metadata={"unit": "rad/s", "min": 0.001, "max": 5.0})
    waist_speed_m_s: float = field(default=0.1, metadata={"unit": "m/s", "min": 0.001, "max": 0.5})
    waist_angular_speed_rad_s: float = field(default=0.5, metadata={"unit": "rad/s", "min": 0.001, "max": 5.0})
    walk_speed_m_s: float = field(default=0.3, metadata={"unit": "m/s", "min": 0.001, "max": 1.0})
    walk_turn_rad_s: float = field(default=0.5, metadata={"unit": "rad/s", "min": 0.001, "max": 3.0})
    deadman_timeout_s: float = field(default=0.2, metadata={"unit": "s", "min": 0.0, "max": 5.0})
    deadman_ramp_s: float = field(default=0.1, metadata={"unit": "s", "min": 0.0, "max": 5.0})
    # reset_targets(): the output blends back onto the upstream reference over this time
    reset_time_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.01, "max": 10.0})
    # targets kept this long for a release after an emergency stop (must cover the EmergencyStopper's T1)
    history_s: float = field(default=3.0, metadata={"unit": "s", "min": 0.0, "max": 20.0})


@dataclass(frozen=True, slots=True)
class PointStatus:
    """One operational point in the status (all in the feet frame F)."""

    target: tuple[float, ...] | None = field(metadata=described(
        "target in F: hands (x, y, z [m], roll, pitch, yaw [rad]); head (pitch, yaw [rad]); waist (height [m], "
        "roll, pitch, yaw [rad]); walk (vx, vy [m/s], vtheta [rad/s]); null: not operated"))
    achieved: tuple[float, ...] | None = field(metadata=described("the IK's pose, same layout as target"))
    limited: str | None = field(metadata=described(
        "why the point did less than asked: null, 'reach', 'joint_limit', 'velocity' or 'motion_stop'"))
    motion: tuple[float, ...] = field(metadata=described(
        "operator twist after the dead-man (vx, vy, vz [m/s], wx, wy, wz [rad/s]) in F"))
    behavior: tuple[float, ...] = field(metadata=described("the behaviours' summed twist, same layout"))


@dataclass(frozen=True, slots=True)
class OperationStatus(Status):
    active: bool = field(metadata=described("some point holds a target: the IK runs"))
    motion_stopped: bool = field(metadata=described("the EmergencyStopper holds the motion: nothing integrates"))
    points: dict[str, PointStatus] = field(metadata=described("per operational point (POINTS order)"))

    def to_dict(self) -> dict:
        return {"enabled": self.enabled, "active": self.active, "motion_stopped": self.motion_stopped,
                "points": {name: plain(ps) for name, ps in self.points.items()}}


def _six(t: Twist) -> tuple[float, ...]:
    return (*t.linear_m_s.tolist(), *t.angular_rad_s.tolist())


class _Frame:
    """A planar frame (origin, yaw) with the world <-> frame maps for points and rotations."""

    __slots__ = ("p", "yaw", "R")

    def __init__(self, p: np.ndarray, yaw: float) -> None:
        self.p, self.yaw, self.R = np.asarray(p, dtype=float), float(yaw), yaw_rotation(yaw)

    def to_local(self, p_world, R_world=None):
        p = self.R.T @ (np.asarray(p_world, dtype=float) - self.p)
        return p if R_world is None else (p, self.R.T @ R_world)

    def to_world(self, p_local, R_local=None):
        p = self.p + self.R @ np.asarray(p_local, dtype=float)
        return p if R_local is None else (p, self.R @ R_local)


class OperationLayer(Layer):
    """Each tick: motion twist (dead-man) + behaviour twist -> per-point sum (Eq. 5) -> speed limits ->
    integrate the targets in F -> whole-body IK -> the reference's upper body (arms, head, torso) and waist
    (BODY height and orientation, which the AutoBalancer keeps while it balances on the legs). A point
    becomes operated with its first non-zero twist and holds its target until `reset_targets()`; with
    nothing operated the layer is identity (no IK call). The walking point is published as
    `ports.walk_command`. While the EmergencyStopper holds the motion nothing integrates; on its release
    the targets restart from the ones the revert went back to."""

    name = "op"
    description = "OperationLayer: operator + behaviour twists per operational point (Eq. 5), placo IK"

    def __init__(self, dt_s: float, params: OperationParams | None = None, ik: OperationIK | None = None) -> None:
        super().__init__()
        self.params = params or OperationParams()
        self.dt_s = dt_s
        self.ik = ik or OperationIK()
        self.kin = RobotKinematics()  # the reference's own kinematics (seeding, view)
        # the AutoBalancer's closed-form legs, to see the reference as it balances it (seeding, view)
        self._balanced = FullbodyIK(RobotKinematics())
        self._gait = None
        self._motion: dict[str, tuple[Twist, float]] = {}  # point -> (twist, control time it arrived)
        self._motion_walk: WalkCommand | None = None
        self._behavior: dict[str, Twist] = {}
        self._behavior_walk: WalkCommand | None = None
        self._targets: dict[str, object] = {}  # operated point -> HandPose | GazeAngles | WaistPose (in F)
        self._achieved: dict[str, object] = {}
        self._limited: dict[str, str | None] = {}
        self._last_motion: dict[str, Twist] = {}
        self._last_behavior: dict[str, Twist] = {}
        self._walk_active = False  # a non-zero walk command went out: one zero follows when it ends
        self._last_walk: WalkCommand | None = None
        self._neck_feet: np.ndarray | None = None
        self._stopped = False
        self._revert_to_s: float | None = None
        self._history: deque[tuple[float, dict, np.ndarray]] = deque()
        self._active_since_s: float | None = None
        self._reset_blend: tuple[Transition, np.ndarray] | None = None
        self._last_out: Reference | None = None
        self._last_in: Reference | None = None
        self._feet_world: _Frame | None = None
        self._feet_key: tuple | None = None
        self._feet_poses: FeetPoses | None = None
        self._walking = False
        self._idle_gait = None  # the gait port of the last idle tick (None: the last tick operated)
        self._time_s = 0.0
        self._version = 0
        self._status = SharedStatus()

    # ---- commands (at a tick boundary) ---------------------------------------------------------------
    def set_params(self, params: OperationParams) -> None:
        self.params = params

    def set_motion(self, point: str, twist: Twist, time_s: float, walk: WalkCommand | None = None) -> None:
        """The operator's latest setpoint for `point` (F frame, see controller.operation.points), arrived at
        control time `time_s` [s]; for "walk", `walk` may carry the step parameters."""
        check_twist(point, twist)
        if not math.isfinite(time_s):
            raise InvalidCommand(f"time_s must be a finite control time [s], got {time_s!r}")
        if walk is not None and point != "walk":
            raise InvalidCommand(f"walk step parameters given for point {point!r}; only the 'walk' point takes them")
        self._motion[point] = (twist, float(time_s))
        if point == "walk":
            self._motion_walk = walk

    def set_behavior(self, twists: Mapping[str, Twist], walk: WalkCommand | None = None) -> None:
        """The behaviours' sum per point for the next tick only (not refreshed: zero)."""
        for point, twist in twists.items():
            check_twist(point, twist)
        self._behavior = dict(twists)
        self._behavior_walk = walk

    def reset_targets(self) -> None:
        """Nothing offset any more: the targets go back onto the upstream reference (the output blends there
        over reset_time_s); the operator's setpoints are dropped."""
        self._motion.clear()
        self._behavior = {}
        if self._targets and self._last_out is not None:
            self._reset_blend = (Transition(0.0, 1.0, self.params.reset_time_s, "min_jerk"), self._pack(self._last_out))
        self._deactivate()

    def _deactivate(self) -> None:
        self._targets.clear()
        self._achieved.clear()
        self._limited.clear()
        self._history.clear()
        self._active_since_s = None
        self.ik.reset()
        self._version += 1

    # ---- tick ------------------------------------------------------------------------------------
    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        if not self.enabled:
            return ref
        t = ctx.time_s
        self._time_s = t
        self._last_in = ref
        stopped = ctx.last_ports.motion_stopped
        if stopped:
            if ctx.last_ports.motion_reverted_to_s is not None:
                self._revert_to_s = ctx.last_ports.motion_reverted_to_s
        elif self._stopped:
            self._on_release()
        if stopped != self._stopped:
            self._stopped = stopped
            self._version += 1
        motion = self._motion_twists(t) if self._motion else {}
        behavior, self._behavior = self._behavior, {}
        if motion or behavior or self._last_motion or self._last_behavior:
            self._version += 1
        self._last_motion, self._last_behavior = motion, behavior
        total = sum_per_point(motion, behavior) if behavior else motion
        self._publish_walk(ctx, total.get("walk"))
        if not self._targets and not stopped:
            for point in IK_POINTS:
                twist = total.get(point)
                if twist is not None and not twist.is_zero:
                    break
            else:  # idle
                self._idle_gait = ctx.last_ports.gait  # the view stays current (walking, the feet frame)
                out = ref if self._reset_blend is None else self._blend_back(ref, ctx.dt_s)
                self._last_out = out
                return out
        self._idle_gait = None
        return self._operate(ctx, ref, total, stopped)

    def _motion_twists(self, t: float) -> dict[str, Twist]:
        p = self.params
        out = {}
        for point, (twist, t0) in list(self._motion.items()):
            k = deadman_factor(t - t0, p.deadman_timeout_s, p.deadman_ramp_s)
            if k <= 0.0:
                del self._motion[point]
                continue
            out[point] = twist if k == 1.0 else twist.scaled(k)
        return out

    def _publish_walk(self, ctx: TickContext, twist: Twist | None) -> None:
        if twist is None or twist.is_zero:
            if self._walk_active:  # one zero command: the walk the operator drove stops
                self._walk_active = False
                ctx.ports.walk_command = self._last_walk = WalkCommand(0.0, 0.0, 0.0)
            return
        p = self.params
        lin = limit_twist(Twist.of(twist.linear_m_s), p.walk_speed_m_s, 1.0).scale
        ang = limit_twist(Twist.of(angular_rad_s=twist.angular_rad_s), 1.0, p.walk_turn_rad_s).scale
        k = min(lin, ang)
        steps = self._motion_walk or self._behavior_walk
        vx, vy, _ = twist.linear_m_s.tolist()
        cmd = WalkCommand(vx * k, vy * k, float(twist.angular_rad_s[2]) * k,
                          max_stride_m=steps.max_stride_m if steps else None,
                          foot_distance_m=steps.foot_distance_m if steps else None)
        self._walk_active = True
        ctx.ports.walk_command = self._last_walk = cmd

    # ---- the operated tick -------------------------------------------------------------------------
    def _operate(self, ctx: TickContext, ref: Reference, total: dict[str, Twist], stopped: bool) -> Reference:
        p, dt = self.params, ctx.dt_s
        F_ref = self._reference_frame(ref)
        self._update_feet(ctx, F_ref)
        base_feet, R_feet_base = F_ref.to_local(ref.base_pos_world, rpy_to_matrix(ref.base_rpy_rad))
        if self._active_since_s is None:
            self._active_since_s = ctx.time_s
        seeded = False
        if not stopped:
            for point in IK_POINTS:
                twist = total.get(point)
                if twist is None or twist.is_zero:
                    continue
                if point not in self._targets:
                    if not seeded:
                        F_seed = self._balanced_kinematics(ref)
                        seeded = True
                    self._targets[point] = self._seed(point, F_seed)
                limits = {"rhand": (p.hand_speed_m_s, p.hand_angular_speed_rad_s),
                          "lhand": (p.hand_speed_m_s, p.hand_angular_speed_rad_s),
                          "head": (1.0, p.head_angular_speed_rad_s),
                          "waist": (p.waist_speed_m_s, p.waist_angular_speed_rad_s)}[point]
                limited = limit_twist(twist, *limits)
                self._targets[point] = self._targets[point].integrated(limited.twist, dt)
                self._limited[point] = VELOCITY if limited.scale < 1.0 else None
            if self._reset_blend is not None:  # a new motion during a reset: from where the blend is
                self._reset_blend = None
        res = self.ik.solve(ref.q_rad, base_feet, matrix_to_rpy(R_feet_base), self._ik_targets(), self._feet_poses,
                            self._com_xy)
        for point, r in res.points.items():
            achieved = self._achieved_of(point, r.T_world)
            self._achieved[point] = achieved
            if stopped:
                self._limited[point] = MOTION_STOP
            elif r.limited is not None:
                self._limited[point] = r.limited
                self._targets[point] = clamp_to_achieved(self._targets[point], achieved, r.limited)
            elif self._limited.get(point) != VELOCITY:
                self._limited[point] = None
        self._version += 1
        if p.history_s > 0.0 and not stopped:
            h = self._history
            h.append((ctx.time_s, dict(self._targets), self.ik.q.copy()))
            while len(h) > 1 and h[0][0] < ctx.time_s - p.history_s:
                h.popleft()
        base_w, R_w = F_ref.to_world(res.base_pos_world, rpy_to_matrix(res.base_rpy_rad))
        out = ref.with_owned(q_rad=np.array(res.q_rad, dtype=float), base_pos_world=base_w,
                             base_rpy_rad=matrix_to_rpy(R_w))
        self._last_out = out
        return out

    def _reference_frame(self, ref: Reference) -> _Frame:
        """F of the upstream reference (its own soles), where its base pose is expressed for the IK."""
        kin = self.kin
        kin.update_rpy(ref.base_pos_world, ref.base_rpy_rad, ref.q_rad)
        (pr, Rr), (pl, Rl) = kin.frame_pose("rleg_end"), kin.frame_pose("lleg_end")
        return _Frame(*feet_frame(pr, Rr, pl, Rl))

    def _update_feet(self, ctx: TickContext, F_ref: _Frame) -> None:
        """The soles in F (from the AutoBalancer's gait of the last tick, else the reference's), the COM
        target in F (the gait's COG, so the IK and the AutoBalancer agree on BODY's place)."""
        gait = self._gait = ctx.last_ports.gait
        if gait is None:
            self._walking = False
            self._feet_world = F_ref
            self._com_xy = None
            kin = self.kin  # updated on the reference by _reference_frame
            soles = [F_ref.to_local(*kin.frame_pose(f)) for f in ("rleg_end", "lleg_end")]
            contact = (True, True)
        else:
            self._walking = gait.walking
            F = _Frame(*feet_frame(gait.p_rsole_world, gait.R_rsole_world, gait.p_lsole_world, gait.R_lsole_world))
            self._feet_world = F
            soles = [F.to_local(gait.p_rsole_world, gait.R_rsole_world), F.to_local(gait.p_lsole_world,
                                                                                  gait.R_lsole_world)]
            contact = gait.contact
            self._com_xy = F.to_local(gait.cog_world)[:2]
        key = (tuple(np.round(np.concatenate([soles[0][0], soles[0][1].ravel(), soles[1][0], soles[1][1].ravel()]),
                              9).tolist()), tuple(contact))
        if key != self._feet_key:
            self._feet_key = key
            self._feet_poses = FeetPoses(soles[0][0], soles[0][1], soles[1][0], soles[1][1], contact)

    def _balanced_kinematics(self, ref: Reference) -> _Frame:
        """self.kin on `ref` as the AutoBalancer balances it (the legs and BODY x-y that put the gait's COG
        over its soles, BODY yaw along the feet), and F of that posture: so a point starts from where the
        robot has it, not from the unbalanced plan. Without a gait: the reference as it is."""
        gait = self._gait
        if gait is None:
            return self._reference_frame(ref)
        F = _Frame(*feet_frame(gait.p_rsole_world, gait.R_rsole_world, gait.p_lsole_world, gait.R_lsole_world))
        roll, pitch, yaw = ref.base_rpy_rad.tolist()
        R_body = rpy_to_matrix((roll, pitch, yaw + F.yaw))
        res = self._balanced.solve(ref.q_rad, float(ref.base_pos_world[2]), R_body, gait.cog_world[:2],
                                   (gait.p_rsole_world, gait.R_rsole_world), (gait.p_lsole_world, gait.R_lsole_world))
        self.kin.update(res.base_pos_world, R_body, res.q_rad)
        return F

    def _seed(self, point: str, F_ref: _Frame):
        """A point's first target: where the reference has it now, in F (self.kin is on the reference)."""
        p, R = F_ref.to_local(*self.kin.frame_pose(_FRAMES[point]))
        if point in ("rhand", "lhand"):
            return HandPose.of(p, R)
        if point == "head":
            self._neck_feet = F_ref.to_local(self.kin.frame_pose(_NECK)[0])
            return GazeAngles.of_direction(R[:, 0])
        return WaistPose(float(p[2]), tuple(matrix_to_rpy(R).tolist()))

    def _ik_targets(self) -> OperationTargets:
        t = self._targets
        kw = {}
        for point in ("rhand", "lhand"):
            if point in t:
                kw[point] = HandTarget(t[point].p_feet_m, t[point].R_feet_hand)
        if "head" in t:
            neck = self._neck_feet if self._neck_feet is not None else np.zeros(3)
            kw["head"] = GazeTarget(look_at_world=neck + _LOOK_AT_DISTANCE_M * t["head"].direction_feet())
        if "waist" in t:
            kw["waist"] = WaistTarget(t["waist"].height_m, np.array(t["waist"].rpy_rad))
        return OperationTargets(**kw)

    @staticmethod
    def _achieved_of(point: str, T: np.ndarray):
        if point in ("rhand", "lhand"):
            return HandPose.of(T[:3, 3], T[:3, :3])
        if point == "head":
            return GazeAngles.of_direction(T[:3, 0])
        return WaistPose(float(T[2, 3]), tuple(matrix_to_rpy(T[:3, :3]).tolist()))

    def _on_release(self) -> None:
        """The EmergencyStopper released the motion: restart from the targets its revert went back to."""
        t_rev, self._revert_to_s = self._revert_to_s, None
        self._motion.clear()  # a setpoint streamed into the stop is not replayed
        if t_rev is None or self._active_since_s is None or t_rev < self._active_since_s or not self._history:
            self._deactivate()  # reverted to before anything was operated: the plain reference
            return
        entry = self._history[0]
        for e in self._history:
            if e[0] <= t_rev + 1e-9:
                entry = e
            else:
                break
        self._targets = dict(entry[1])
        self.ik.warm_start(entry[2])
        self._version += 1

    # ---- reset blend --------------------------------------------------------------------------------
    @staticmethod
    def _pack(ref: Reference) -> np.ndarray:
        return np.concatenate((ref.q_rad, ref.base_pos_world, ref.base_rpy_rad))

    def _blend_back(self, ref: Reference, dt_s: float) -> Reference:
        weight, x0 = self._reset_blend
        w = weight.step(dt_s)
        if weight.done:
            self._reset_blend = None
            return ref
        x = x0 + w * (self._pack(ref) - x0)
        n = len(ref.q_rad)
        return ref.with_owned(q_rad=x[:n], base_pos_world=x[n:n + 3], base_rpy_rad=x[n + 3:n + 6])

    # ---- reading ------------------------------------------------------------------------------------
    def view(self) -> OperationView:
        """The points as the layer's last output reference puts them (FK of the controller's reference,
        placed in the world by the gait's feet frame), the gaze and waist height in F."""
        ref = self._last_out or self._last_in
        if ref is None:
            raise InvalidCommand("the operation layer has not ticked yet; no view before the first tick")
        idle_gait, walking = self._idle_gait, self._walking
        if idle_gait is not None:  # idle: the feet frame and the walking flag of the gait, not the last IK's
            walking = idle_gait.walking
            F_world = _Frame(*feet_frame(idle_gait.p_rsole_world, idle_gait.R_rsole_world, idle_gait.p_lsole_world,
                                         idle_gait.R_lsole_world))
        else:
            F_world = self._feet_world or self._reference_frame(ref)
        F_ref = self._balanced_kinematics(ref)
        points = {}
        for point, frame in _FRAMES.items():
            p_f, R_f = F_ref.to_local(*self.kin.frame_pose(frame))
            p_w, R_w = F_world.to_world(p_f, R_f)
            points[point] = PointPose(p_world_m=_ro(p_w), R_world_point=_ro(R_w), p_feet_m=_ro(p_f),
                                      R_feet_point=_ro(R_f))
        gaze = GazeAngles.of_direction(points["head"].R_feet_point[:, 0])
        return OperationView(time_s=self._time_s, feet_p_world_m=_ro(F_world.p.copy()), feet_yaw_rad=F_world.yaw,
                             points=points, gaze_rad=(gaze.pitch_rad, gaze.yaw_rad),
                             waist_height_m=float(points["waist"].p_feet_m[2]), walking=walking,
                             motion_stopped=self._stopped)

    def status(self) -> OperationStatus:
        return self._status.get((self._version, self.enabled), self._build_status)

    def _build_status(self) -> OperationStatus:
        pts = {}
        for point in POINTS:
            motion = self._last_motion.get(point, ZERO_TWIST)
            behavior = self._last_behavior.get(point, ZERO_TWIST)
            if point == "walk":
                w = self._last_walk if self._walk_active else None
                target = None if w is None else (w.vx_m_s, w.vy_m_s, w.vtheta_rad_s)
                achieved, limited = None, None
            else:
                target = _layout(self._targets.get(point))
                achieved = _layout(self._achieved.get(point))
                limited = self._limited.get(point) if point in self._targets else None
            pts[point] = PointStatus(target=target, achieved=achieved, limited=limited,
                                     motion=_six(motion), behavior=_six(behavior))
        return OperationStatus(enabled=self.enabled, active=bool(self._targets), motion_stopped=self._stopped,
                               points=pts)


def _layout(pose) -> tuple[float, ...] | None:
    if pose is None:
        return None
    if isinstance(pose, HandPose):
        return (*pose.p_feet_m.tolist(), *matrix_to_rpy(pose.R_feet_hand).tolist())
    if isinstance(pose, GazeAngles):
        return (pose.pitch_rad, pose.yaw_rad)
    return (pose.height_m, *pose.rpy_rad)


def _ro(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a
