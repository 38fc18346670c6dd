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
from controller.core.types import Reference, TickContext, WalkCommand, frozen_array, read_only
from controller.interpolation.blend import Transition
from controller.kinematics.fullbody_ik import WALK_LEG_LIMIT_MARGIN_RAD, FullbodyIK, legs_within_limits
from controller.kinematics.model import RobotKinematics
from controller.kinematics.operation_ik import OperationIK
from controller.kinematics.operation_targets import GazeTarget, HandTarget, OperationTargets
from controller.kinematics.rotations import (
    matrix_to_rpy,
    rows_mul,
    rows_mulv,
    rows_tmul,
    rows_tmulv,
    rpy_to_matrix,
)
from controller.operation.deadman import live_twists
from controller.operation.frame import PlanarFrame, sole_from_sole, sub3
from controller.operation.integration import PointLimits, integrate_point
from controller.operation.limits import (
    HAND_STEP_LENGTH_M,
    JOINT_LIMIT,
    MOTION_STOP,
    REACH,
    VELOCITY,
    clamp_to_achieved,
    speed_scale,
)
from controller.operation.points import POINTS, ZERO_TWIST, OperationView, PointPose, Twist, check_twist, sum_per_point
from controller.operation.targets import GazeAngles, HandPose, WaistPose, feet_frame, status_layout
from robot.names import JOINT_GROUPS, JOINT_NAMES

_HANDS = ("rhand", "lhand")
#: [rad] a waist target keeps the legs' joints this far inside their limits (campaign seeds 1017, 1018: a 19 deg
#: roll put a hip roll at its limit, the sole tipped onto its edge and the robot fell walking)
WAIST_LEG_LIMIT_MARGIN_RAD = math.radians(3.0)
IK_POINTS = ("rhand", "lhand", "head", "waist")  # the points the IK realises ("walk" goes to the AutoBalancer)
_FRAMES = {"rhand": "rarm_end", "lhand": "larm_end", "head": "HEAD_LINK1", "waist": "BODY"}
_NECK = "HEAD_LINK0"  # the gaze ray's origin
_LOOK_AT_DISTANCE_M = 100.0  # a gaze direction becomes a point this far along it (neck drift: < 0.03 deg)
_LEGS = np.array(JOINT_GROUPS["rleg"] + JOINT_GROUPS["lleg"])
_UPPER = np.array([i for i in range(len(JOINT_NAMES)) if i not in set(_LEGS.tolist())])  # torso, head, arms
_IS_UPPER = np.isin(np.arange(len(JOINT_NAMES)), _UPPER)
_ZERO3 = read_only(np.zeros(3))


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
    # acceleration limits of the summed twist (Eq. 5) per point: a stick flicked from one direction to another
    # turns the point in ~0.2 s instead of one tick. A step of the hand's velocity (0.1 m/s forward to 0.05 m/s
    # up) reversed the chest at ~20 deg/s within a tick; the COM estimate moved 9 mm in 50 ms and the
    # capture-point flag stopped the motion
    hand_accel_m_s2: float = field(default=0.5, metadata={"unit": "m/s^2", "min": 0.01, "max": 100.0})
    hand_angular_accel_rad_s2: float = field(default=4.0, metadata={"unit": "rad/s^2", "min": 0.01, "max": 1000.0})
    head_angular_accel_rad_s2: float = field(default=8.0, metadata={"unit": "rad/s^2", "min": 0.01, "max": 1000.0})
    waist_accel_m_s2: float = field(default=0.5, metadata={"unit": "m/s^2", "min": 0.01, "max": 100.0})
    waist_angular_accel_rad_s2: float = field(default=2.0, metadata={"unit": "rad/s^2", "min": 0.01, "max": 1000.0})
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


_ZERO_SIX = _six(ZERO_TWIST)


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
        # the upper body only: the AutoBalancer owns balance, the legs and BODY's place
        self.ik = ik or OperationIK(upper_body=True)
        self.kin = RobotKinematics()  # the reference's own kinematics in F (seeding, view)
        # the AutoBalancer's closed-form legs: can they carry the waist target?
        self._balanced = FullbodyIK(RobotKinematics())
        self._leg_lower_rad = self._balanced.kin.q_lower.tolist()
        self._leg_upper_rad = self._balanced.kin.q_upper.tolist()
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
        self._walk_key: tuple | None = None  # (vx, vy, vtheta, step parameters, params) of _last_walk
        self._neck_feet: np.ndarray | None = None
        self._stopped = False
        self._collision_pairs: tuple[tuple[str, str], ...] = ()  # the CollisionDetector's hold, last tick
        self._revert_to_s: float | None = None
        self._history: deque[tuple[float, dict, np.ndarray]] = deque()
        self._active_since_s: float | None = None
        self._reset_blend: tuple[Transition, np.ndarray] | None = None
        self._last_out: Reference | None = None
        self._last_in: Reference | None = None
        self._feet_world: PlanarFrame | None = None
        self._ref_kin = RobotKinematics()  # the upstream reference's own soles (F without a gait)
        self._ref_frame: PlanarFrame | None = None
        self._ref_frame_key: tuple | None = None
        self._waist_checked = None  # the waist target last found reachable by the AutoBalancer's legs
        self._anchored_walking = False  # the hand targets are held relative to BODY (walking), else to F
        self._anchor = _ZERO3  # BODY in F while walking (what the hand targets are relative to), else 0
        self._walking = False
        self._time_s = 0.0
        self._version = 0
        self._status = SharedStatus()
        self._limits = PointLimits()  # speed limits and acceleration steps per IK point, from the params
        self._rates: dict[str, Twist] = {}  # the twist each IK point integrated last tick (none: at rest)
        self._view_kin = RobotKinematics()  # view(): the output reference's FK (joints only, 4 frames)
        self._view_frames = {point: self._view_kin.model.getFrameId(frame) for point, frame in _FRAMES.items()}
        self._view_cache: tuple | None = None  # ((ref, gait, time, walking, stopped), the view of that tick)

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

    def drop_motion(self) -> None:
        """Forget the operator's setpoints (the hard e-stop: nothing streamed before it runs after it)."""
        self._rates.clear()  # and nothing coasts on after it: the points start again from rest
        if self._motion:
            self._motion.clear()
            self._version += 1

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
        self._rates.clear()
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
        self._collision_pairs = ctx.last_ports.collision_pairs
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
                gait = self._gait = ctx.last_ports.gait  # the view stays current: the feet frame, walking
                self._walking = gait is not None and gait.walking
                out = ref if self._reset_blend is None else self._blend_back(ref, ctx.dt_s)
                self._last_out = out
                return out
        # the hard e-stop's hold (and its release blend) freezes the integration too: the AutoBalancer holds its
        # output meanwhile, and a waist target integrated under it came in as one jump when the blend ended (a
        # squat started 1 s after a release: BODY 34 mm down in a tick, CP error 108 mm, the motion stopped)
        return self._operate(ctx, ref, total, stopped or ctx.last_ports.hold)

    def _motion_twists(self, t: float) -> dict[str, Twist]:
        return live_twists(self._motion, t, self.params.deadman_timeout_s, self.params.deadman_ramp_s)

    def _publish_walk(self, ctx: TickContext, twist: Twist | None) -> None:
        if twist is None or twist.is_zero:
            if self._walk_active:  # one zero command: the walk the operator drove stops
                self._walk_active = False
                ctx.ports.walk_command = self._last_walk = WalkCommand(0.0, 0.0, 0.0)
            return
        p = self.params
        vx, vy, _ = twist.linear_m_s.tolist()
        vtheta = twist.angular_rad_s.tolist()[2]
        steps = self._motion_walk or self._behavior_walk
        key = (vx, vy, vtheta, steps, p)
        if key == self._walk_key and self._walk_active:  # the same command as last tick (a held stick)
            ctx.ports.walk_command = self._last_walk
            return
        k = min(speed_scale(math.hypot(vx, vy), p.walk_speed_m_s), speed_scale(abs(vtheta), p.walk_turn_rad_s))
        cmd = WalkCommand(vx * k, vy * k, vtheta * k,
                          max_stride_m=steps.max_stride_m if steps else None,
                          foot_distance_m=steps.foot_distance_m if steps else None)
        self._walk_active = True
        self._walk_key = key
        ctx.ports.walk_command = self._last_walk = cmd

    # ---- the operated tick -------------------------------------------------------------------------
    def _operate(self, ctx: TickContext, ref: Reference, total: dict[str, Twist], stopped: bool) -> Reference:
        p, dt = self.params, ctx.dt_s
        gait = self._gait = ctx.last_ports.gait
        self._walking = gait is not None and gait.walking
        F, p_body, R_body = self._body_in_feet(ref, gait)
        self._feet_world = F
        if self._walking != self._anchored_walking:
            self._re_anchor(p_body if self._walking else -p_body)
        anchor = self._anchor = p_body if self._walking else _ZERO3
        if self._active_since_s is None:
            self._active_since_s = ctx.time_s
        seeded = False
        rates = self._rates
        stepped_from: dict[str, HandPose] = {}  # a hand's target before this tick's step
        if stopped:
            rates.clear()  # held: a release starts from rest
        else:
            for point in IK_POINTS:
                twist = total.get(point)
                previous = rates.get(point)
                if twist is None or twist.is_zero:
                    if previous is None:
                        continue
                    twist = ZERO_TWIST  # slowing down to rest
                if point not in self._targets:
                    if not seeded:  # FK in F of the posture as balanced, the upper body as last operated
                        operated = self._last_out if self._targets and self._last_out is not None else None
                        q_seed = ref.q_rad if operated is None else np.where(_IS_UPPER, operated.q_rad, ref.q_rad)
                        self.kin.update(p_body, R_body, q_seed)
                        seeded = True
                    self._targets[point] = self._seed(point, anchor, float(F.p[2]) - self._ground_z(gait, F))
                step = integrate_point(self._targets[point], twist, previous, self._limits.speed(p, point),
                                       self._limits.accel_steps(p, point, dt), dt)
                if step.rate.is_zero:
                    rates.pop(point, None)
                else:
                    rates[point] = step.rate
                if point in _HANDS:
                    stepped_from[point] = self._targets[point]
                self._targets[point] = step.target
                self._limited[point] = VELOCITY if step.velocity_limited else None
            if self._reset_blend is not None:  # a new motion during a reset: from where the blend is
                self._reset_blend = None
        q_out, base_out, rpy_out = ref.q_rad, ref.base_pos_world, ref.base_rpy_rad
        if "waist" in self._targets:
            base_out, rpy_out = self._waist(ref, gait, F, stopped)
        p_rel, R_rows = sub3(p_body.tolist(), anchor.tolist()), R_body.tolist()  # BODY in F, from the anchor
        ik_targets = self._ik_targets(p_rel, R_rows)
        if ik_targets.active:
            res = self.ik.solve(ref.q_rad, _ZERO3, _ZERO3, ik_targets)
            q_out = np.where(_IS_UPPER, res.q_rad, ref.q_rad)  # the legs stay the reference's
            for point, r in res.points.items():
                achieved = self._achieved[point] = self._achieved_pose(point, r.T_world, p_rel, R_rows)
                if stopped:
                    self._limited[point] = MOTION_STOP
                elif r.limited is not None:
                    self._limited[point] = r.limited
                    start = stepped_from.get(point)
                    if start is not None and r.limited in (REACH, JOINT_LIMIT):
                        # the hand did part of its step at most: the target advances by the share it made along
                        # the asked direction (one scale for the whole step), never sideways with the IK's
                        # best effort, which drifted the hand off the asked line along the workspace's edge
                        self._targets[point] = start.advanced_along(self._targets[point], achieved, HAND_STEP_LENGTH_M)
                    else:
                        self._targets[point] = clamp_to_achieved(self._targets[point], achieved, r.limited)
                elif self._limited.get(point) != VELOCITY:
                    self._limited[point] = None
        else:
            self.ik.reset()  # the next hand or head starts the IK afresh from the reference
        self._version += 1
        if p.history_s > 0.0 and not stopped:
            h = self._history
            h.append((ctx.time_s, dict(self._targets), self.ik.q.copy()))
            while len(h) > 1 and h[0][0] < ctx.time_s - p.history_s:
                h.popleft()
        if base_out is ref.base_pos_world:  # no waist target: only the joints change
            out = ref.with_owned(q_rad=q_out) if q_out is not ref.q_rad else ref
        else:
            out = ref.with_owned(q_rad=q_out, base_pos_world=base_out, base_rpy_rad=rpy_out)
        self._last_out = out
        return out

    def _re_anchor(self, shift: np.ndarray) -> None:
        """Walking started (shift = BODY in F) or stopped (shift = -BODY in F): the hand targets and the
        neck re-expressed relative to the new anchor, the same place in the world at this tick. Standing
        they are held in F; walking relative to BODY (in F's axes), so the hands go along with the body
        instead of sweeping against its sway from sole to sole and its bobbing with the swing foot."""
        self._anchored_walking = self._walking
        for store in (self._targets, self._achieved):
            for point in ("rhand", "lhand"):
                if point in store:
                    store[point] = HandPose.of(store[point].p_feet_m - shift, store[point].R_feet_hand)
        if self._neck_feet is not None:
            self._neck_feet = self._neck_feet - shift
        self._history.clear()  # its targets are in the old anchor: a release restarts from the present

    def _body_in_feet(self, ref: Reference, gait) -> tuple[PlanarFrame, np.ndarray, np.ndarray]:
        """F in the world and BODY in F as the AutoBalancer put it last tick (its gait port: BODY x-y where
        the COG balances, legs on the soles); without a gait, F and BODY of the reference itself."""
        if gait is not None and gait.base_pos_world is not None:
            F = PlanarFrame(*feet_frame(gait.p_rsole_world, gait.R_rsole_world, gait.p_lsole_world, gait.R_lsole_world))
            p_body, R_body = F.to_local_rpy(gait.base_pos_world, gait.base_rpy_rad)
            return F, p_body, R_body
        F = self._reference_frame(ref)
        p_body, R_body = F.to_local_rpy(ref.base_pos_world, ref.base_rpy_rad)
        return F, p_body, R_body

    def _reference_frame(self, ref: Reference) -> PlanarFrame:
        """F of the upstream reference (its own soles); cached while its base and legs do not move."""
        key = (*ref.base_pos_world.tolist(), *ref.base_rpy_rad.tolist(), *ref.q_rad[_LEGS].tolist())
        if key != self._ref_frame_key:
            kin = self._ref_kin
            kin.update_rpy(ref.base_pos_world, ref.base_rpy_rad, ref.q_rad)
            (pr, Rr), (pl, Rl) = kin.frame_pose("rleg_end"), kin.frame_pose("lleg_end")
            self._ref_frame = PlanarFrame(*feet_frame(pr, Rr, pl, Rl))
            self._ref_frame_key = key
        return self._ref_frame

    def _waist(self, ref: Reference, gait, F: PlanarFrame, stopped: bool) -> tuple[np.ndarray, np.ndarray]:
        """BODY height and orientation of the waist target, as the reference's base pose: the AutoBalancer
        keeps them and balances on the legs. A height or tilt its legs cannot reach is clamped to the last
        reachable one (reason "reach")."""
        target = self._targets["waist"]
        R_F = rpy_to_matrix(target.rpy_rad)
        if gait is not None and not stopped and target is not self._waist_checked:
            R_w = F.R @ R_F
            res = self._balanced.solve(ref.q_rad, float(F.p[2] + target.height_m), R_w, gait.cog_world[:2],
                                       (gait.p_rsole_world, gait.R_rsole_world),
                                       (gait.p_lsole_world, gait.R_lsole_world))
            margin = WALK_LEG_LIMIT_MARGIN_RAD if getattr(gait, "walking", False) else WAIST_LEG_LIMIT_MARGIN_RAD
            legs_ok = legs_within_limits(res.q_rad, self._leg_lower_rad, self._leg_upper_rad, margin)
            if not (res.reachable and legs_ok) and "waist" in self._achieved:
                target = self._targets["waist"] = self._achieved["waist"]
                self._limited["waist"] = REACH
                R_F = rpy_to_matrix(target.rpy_rad)
            self._waist_checked = target
        if stopped:
            self._limited["waist"] = MOTION_STOP
        self._achieved["waist"] = target
        if gait is not None:  # the AutoBalancer turns BODY yaw by the feet's: the rpy are F's
            rpy = np.array(target.rpy_rad, dtype=float)
        else:
            rpy = matrix_to_rpy(F.R @ R_F)
        base = np.array(ref.base_pos_world, dtype=float)
        base[2] = self._ground_z(gait, F) + target.height_m
        return base, rpy

    @staticmethod
    def _ground_z(gait, F: PlanarFrame) -> float:
        """The height the waist's is counted from: F's, or while one sole swings the other's (F would bob)."""
        if gait is None or all(gait.contact):
            return float(F.p[2])
        return float(gait.p_rsole_world[2] if gait.contact[0] else gait.p_lsole_world[2])

    def _seed(self, point: str, anchor: np.ndarray, ground_in_feet_m: float = 0.0):
        """A point's first target: where the posture has it now, in F (self.kin is on it, in F), the hands
        and the neck relative to `anchor` (F's origin standing, BODY walking)."""
        p, R = self.kin.frame_pose(_FRAMES[point])
        if point != "waist":
            p = p - anchor
        if point in ("rhand", "lhand"):
            return HandPose.of(p, R)
        if point == "head":
            self._neck_feet = self.kin.frame_pose(_NECK)[0] - anchor
            return GazeAngles.of_direction(R[:, 0])
        return WaistPose(float(p[2]) + ground_in_feet_m, tuple(matrix_to_rpy(R).tolist()))

    def _ik_targets(self, p_body: list, R_body: list) -> OperationTargets:
        """The hand and gaze targets in the BODY frame (where the upper-body IK works); BODY's pose in F
        (relative to the anchor) as floats: position (3,) and rotation rows."""
        t = self._targets
        kw = {}
        for point in ("rhand", "lhand"):
            if point in t:
                pose = t[point]
                kw[point] = HandTarget.from_rows(rows_tmulv(R_body, sub3(pose.p_feet_m.tolist(), p_body)),
                                                 rows_tmul(R_body, pose.R_feet_hand.tolist()))
        if "head" in t:
            nx, ny, nz = self._neck_feet.tolist() if self._neck_feet is not None else (0.0, 0.0, 0.0)
            dx, dy, dz = t["head"].direction_feet().tolist()
            look = (nx + _LOOK_AT_DISTANCE_M * dx, ny + _LOOK_AT_DISTANCE_M * dy, nz + _LOOK_AT_DISTANCE_M * dz)
            kw["head"] = GazeTarget.trusted_look_at(np.array(rows_tmulv(R_body, sub3(look, p_body))))
        return OperationTargets(**kw)

    @staticmethod
    def _achieved_pose(point: str, T_body_point: np.ndarray, p_body: list, R_body: list):
        """A point's achieved pose in F from the IK's (in BODY), BODY's pose in F as in _ik_targets."""
        (a0, a1, a2, x), (a3, a4, a5, y), (a6, a7, a8, z), _ = T_body_point.tolist()
        if point == "head":  # the gaze: the x axis
            return GazeAngles.of_direction(rows_mulv(R_body, (a0, a3, a6)))
        px, py, pz = rows_mulv(R_body, (x, y, z))
        return HandPose.owned(np.array((p_body[0] + px, p_body[1] + py, p_body[2] + pz)),
                              np.array(rows_mul(R_body, ((a0, a1, a2), (a3, a4, a5), (a6, a7, a8)))))

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
        placed in the world by the gait's feet frame), the gaze and waist height in F. Computed once per
        tick: the callers of one tick (the behaviours) share it (read-only arrays; do not modify)."""
        ref = self._last_out or self._last_in
        if ref is None:
            raise InvalidCommand("the operation layer has not ticked yet; no view before the first tick")
        key = (ref, self._gait, self._time_s, self._walking, self._stopped, self._collision_pairs)
        cached = self._view_cache
        if cached is not None and cached[0][0] is ref and cached[0][1] is self._gait and cached[0][2:] == key[2:]:
            return cached[1]
        F_world, p_body, R_body = self._body_in_feet(ref, self._gait)
        kin = self._view_kin
        kin.update_joints(p_body, R_body, ref.q_rad)  # in F, BODY where the AutoBalancer has it
        points = {}
        for point, fid in self._view_frames.items():
            (a0, a1, a2, x), (a3, a4, a5, y), (a6, a7, a8, z), _ = kin.frame_homogeneous(fid).tolist()
            R_feet = ((a0, a1, a2), (a3, a4, a5), (a6, a7, a8))
            p_w, R_w = F_world.to_world_rows((x, y, z), R_feet)
            points[point] = PointPose(p_world_m=frozen_array(p_w), R_world_point=frozen_array(R_w),
                                      p_feet_m=frozen_array((x, y, z)), R_feet_point=frozen_array(R_feet))
        gaze = GazeAngles.of_direction(points["head"].R_feet_point[:, 0])
        view = OperationView(time_s=self._time_s, feet_p_world_m=frozen_array(F_world.p), feet_yaw_rad=F_world.yaw,
                             points=points, gaze_rad=(gaze.pitch_rad, gaze.yaw_rad),
                             waist_height_m=float(points["waist"].p_feet_m[2]), walking=self._walking,
                             motion_stopped=self._stopped, collision_pairs=self._collision_pairs,
                             lsole_from_rsole=self._lsole_from_rsole())
        self._view_cache = (key, view)
        return view

    def _lsole_from_rsole(self) -> tuple[float, float, float]:
        g = self._gait
        if g is None:
            return OperationView.__dataclass_fields__["lsole_from_rsole"].default
        return sole_from_sole(g.p_rsole_world, g.R_rsole_world, g.p_lsole_world, g.R_lsole_world)

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
                target = status_layout(self._targets.get(point), self._anchor)
                achieved = status_layout(self._achieved.get(point), self._anchor)
                limited = self._limited.get(point) if point in self._targets else None
            pts[point] = PointStatus(target=target, achieved=achieved, limited=limited,
                                     motion=_ZERO_SIX if motion is ZERO_TWIST else _six(motion),
                                     behavior=_ZERO_SIX if behavior is ZERO_TWIST else _six(behavior))
        return OperationStatus(enabled=self.enabled, active=bool(self._targets), motion_stopped=self._stopped,
                               points=pts)

