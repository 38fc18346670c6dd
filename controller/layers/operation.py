"""OperationLayer ([OP] II-V, Eq. 5): the operator's and the behaviours' twists summed per operational point,
limited, integrated into targets in the feet frame F and realised by the whole-body IK on placo; the walking
point published for the AutoBalancer. Sits after the SequencePlayer and before the EmergencyStopper. Its pieces
are in controller/operation/: the sum (command_sum) and the dead-man (deadman), the targets' integration and
limits (point_targets), the walking point, the waist, the release history, the reset blend, the view, the status."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from controller.core.errors import InvalidCommand
from controller.core.layer import Layer, Params, SharedStatus
from controller.core.types import Reference, TickContext, WalkCommand, read_only
from controller.kinematics.model import RobotKinematics
from controller.kinematics.operation_ik import OperationIK
from controller.kinematics.rotations import matrix_to_rpy
from controller.operation.body_frame import NECK_FRAME, POINT_FRAMES, BodyInFeet, achieved_pose, ik_targets
from controller.operation.command_sum import CommandSum
from controller.operation.foot_point import FEET, FootPoints, check_foot_allowed
from controller.operation.frame import sub3
from controller.operation.limits import MOTION_STOP
from controller.operation.point_targets import HANDS, IK_POINTS, PointTargets
from controller.operation.points import OperationView, Twist, check_twist
from controller.operation.ranges import check_setpoint
from controller.operation.release import ReleaseHistory
from controller.operation.reset_blend import ResetBlend, reset_duration_s
from controller.operation.status import OperationStatus, PointStatus, operation_status
from controller.operation.targets import GazeAngles, HandPose, WaistPose
from controller.operation.view import LastTick, ViewOfTick
from controller.operation.waist import WaistPoint, ground_z
from controller.operation.walk_point import WalkPoint
from robot.names import JOINT_GROUPS, JOINT_NAMES

__all__ = ["OperationLayer", "OperationParams", "OperationStatus", "PointStatus"]

_LEGS = set(JOINT_GROUPS["rleg"] + JOINT_GROUPS["lleg"])
_IS_UPPER = np.array([i not in _LEGS for i in range(len(JOINT_NAMES))])  # torso, head, arms
_ZERO3 = read_only(np.zeros(3))
_OPERATED = IK_POINTS + FEET


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
    # a foot point's sole (rfoot, lfoot): the AutoBalancer bounds it at 0.12 m/s besides (controller/walking/foot_lift)
    foot_speed_m_s: float = field(default=0.1, metadata={"unit": "m/s", "min": 0.001, "max": 0.12})
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
        self.last_reset_s = 0.0  # [s] the last reset_targets()'s blend
        self.ik.reset()  # a shared IK (one per system, across resets) starts from this chain's reference, not the
        # posture it last solved before a reset (soak seed 10230: a hand streamed across a reset jumped, a fall)
        self.kin = RobotKinematics()  # the reference's own kinematics in F (seeding a point)
        self._commands = CommandSum()  # the operator's (dead-man) and the behaviours' twists, Eq. 5
        self._walk = WalkPoint()
        self._points = PointTargets()  # targets, achieved poses, limits, rates, the hands' anchor
        self._waist = WaistPoint()
        self._frames = BodyInFeet()
        self._history = ReleaseHistory()
        self._reset = ResetBlend()
        self._last = LastTick()
        self._view = ViewOfTick()
        self._version = 0  # bumped whenever the status may have changed
        self._status = SharedStatus()

    # ---- commands (at a tick boundary) ---------------------------------------------------------------
    def set_params(self, params: OperationParams) -> None:
        self.params = params

    def set_motion(self, point: str, twist: Twist, time_s: float, walk: WalkCommand | None = None) -> None:
        """The operator's latest setpoint for `point` (F frame, see controller.operation.points), arrived at
        control time `time_s` [s]; for "walk", `walk` may carry the step parameters. The last guard: nothing out of
        the point's ranges reaches the loop, however it was sent (InvalidCommand naming the field and the range)."""
        check_setpoint(point, twist, *((walk.max_stride_m, walk.foot_distance_m) if walk is not None else ()))
        if not math.isfinite(time_s):
            raise InvalidCommand(f"time_s must be a finite control time [s], got {time_s!r}")
        if walk is not None and point != "walk":
            raise InvalidCommand(f"walk step parameters given for point {point!r}; only the 'walk' point takes them")
        check_foot_allowed(point, twist, self._last.walking, self._points.targets)
        self._commands.streamed.set(point, twist, time_s, walk)

    def drop_motion(self) -> None:
        """Forget the operator's setpoints (the hard e-stop: nothing streamed before it runs after it)."""
        self._points.rates.clear()  # and nothing coasts on after it: the points start again from rest
        if self._commands.streamed.clear():
            self._version += 1

    def set_behavior(self, twists: Mapping[str, Twist], walk: WalkCommand | None = None) -> None:
        """The behaviours' sum per point for the next tick only (not refreshed: zero)."""
        for point, twist in twists.items():
            check_twist(point, twist)
            check_foot_allowed(point, twist, self._last.walking, self._points.targets)
        self._commands.set_behavior(twists, walk)

    def reset_targets(self) -> float:
        """Nothing offset any more: the targets go back onto the upstream reference (the output blends there
        over reset_time_s, longer for a large offset: reset_duration_s); the operator's setpoints are dropped.
        Returns the blend's duration [s]."""
        self._commands.streamed.clear()
        self._commands.drop_behavior()
        duration = self.params.reset_time_s
        last = self._last
        if self._points.targets and last.ref_out is not None:
            if last.ref_in is not None:
                duration = reset_duration_s(last.ref_out, last.ref_in, duration)
            self._reset.start(last.ref_out, duration)
        self._deactivate()
        self.last_reset_s = duration
        return duration

    def _deactivate(self) -> None:
        self._points.clear()
        self._history.forget()
        self.ik.reset()
        self._version += 1

    # ---- tick ------------------------------------------------------------------------------------
    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        if not self.enabled:
            return ref
        last, ports = self._last, ctx.last_ports
        t = last.time_s = ctx.time_s
        last.ref_in = ref
        last.collision_pairs = ports.collision_pairs
        stopped = ports.motion_stopped
        if stopped:
            if ports.motion_reverted_to_s is not None:
                self._history.revert_to_s = ports.motion_reverted_to_s
        elif last.stopped:
            self._on_release()
        if stopped != last.stopped:
            last.stopped = stopped
            self._version += 1
        p = self.params
        total, changed = self._commands.take(t, p.deadman_timeout_s, p.deadman_ramp_s)
        if changed:
            self._version += 1
        walk_twist = total.get("walk")
        if walk_twist is not None or self._walk.active:  # (else nothing to publish: no call on idle ticks)
            walk = self._walk.command(walk_twist, self._commands.walk_steps(), p.walk_speed_m_s, p.walk_turn_rad_s)
            if walk is not None:
                ctx.ports.walk_command = walk
        if not self._points.targets and not stopped:
            for point in _OPERATED:
                twist = total.get(point)
                if twist is not None and not twist.is_zero:
                    break
            else:  # idle
                gait = last.gait = ports.gait  # the view stays current: the feet frame, walking
                last.walking = gait is not None and gait.walking
                if not self._reset.pending:
                    out = last.ref_out = ref
                    return out
                # the reset's blend holds still under the hard e-stop's hold, as the integration does below
                out = last.ref_out = self._reset.step(ref, 0.0 if ports.hold else ctx.dt_s)
                return out
        # the hard e-stop's hold (and its release blend) freezes the integration too: the AutoBalancer holds its
        # output meanwhile, and a waist target integrated under it came in as one jump when the blend ended (a
        # squat started 1 s after a release: BODY 34 mm down in a tick, CP error 108 mm, the motion stopped)
        return self._operate(ctx, ref, total, stopped or ports.hold)

    # ---- the operated tick -------------------------------------------------------------------------
    def _operate(self, ctx: TickContext, ref: Reference, total: dict[str, Twist], stopped: bool) -> Reference:
        last, points = self._last, self._points
        gait = last.gait = ctx.last_ports.gait
        walking = last.walking = gait is not None and gait.walking
        F, p_body, R_body = self._frames.of_rows(ref, gait)  # BODY in F: floats (arrays only where needed)
        if walking != points.anchored_walking:
            # standing the hands are held in F, walking relative to BODY (in F's axes), so that they go along
            # with the body instead of sweeping against its sway from sole to sole and its bobbing
            shift = np.array(p_body)
            points.re_anchor(walking, shift if walking else -shift)
            self._history.drop_entries()  # its targets are in the old anchor: a release restarts from the present
        anchor = points.anchor = np.array(p_body) if walking else _ZERO3
        self._history.started(ctx.time_s)
        if stopped:
            points.rates.clear()  # held: a release starts from rest
            stepped_from = {}
        else:
            seeded = []

            def seed(point: str):
                if not seeded:  # FK in F of the posture as balanced, the upper body as last operated
                    operated = last.ref_out if points.targets and last.ref_out is not None else None
                    q_seed = ref.q_rad if operated is None else np.where(_IS_UPPER, operated.q_rad, ref.q_rad)
                    self.kin.update(np.array(p_body), np.array(R_body), q_seed)
                    seeded.append(True)
                return self._seed(point, anchor, float(F.p[2]) - ground_z(gait, F))
            stepped_from = points.integrate(total, self.params, ctx.dt_s, seed)
            FootPoints.integrate(total, points, self.params.foot_speed_m_s, ctx.dt_s, gait)
        self._command_feet(ctx, stopped, F.yaw)
        q_out, base_out, rpy_out = ref.q_rad, ref.base_pos_world, ref.base_rpy_rad
        if "waist" in points.targets:
            base_out, rpy_out = self._waist.realise(points, ref, gait, F, stopped)
        p_rel = sub3(p_body, p_body if walking else (0.0, 0.0, 0.0))  # BODY in F, from the anchor
        R_rows = R_body
        targets = ik_targets(points.targets, points.neck_feet_m, p_rel, R_rows)
        if targets.active:
            res = self.ik.solve(ref.q_rad, _ZERO3, _ZERO3, targets, lean=True)  # (poses and reasons only)
            q_out = np.where(_IS_UPPER, res.q_rad, ref.q_rad)  # the legs stay the reference's
            for point, r in res.points.items():
                points.settle(point, achieved_pose(point, r.T_world, p_rel, R_rows), r.limited, stopped, stepped_from)
        else:
            self.ik.reset()  # the next hand or head starts the IK afresh from the reference
        self._version += 1
        if self.params.history_s > 0.0 and not stopped:
            self._history.keep(ctx.time_s, points.targets, self.ik.q, self.params.history_s)
        if base_out is ref.base_pos_world:  # no waist target: only the joints change
            out = ref.with_owned(q_rad=q_out) if q_out is not ref.q_rad else ref
        else:
            out = ref.with_owned(q_rad=q_out, base_pos_world=base_out, base_rpy_rad=rpy_out)
        if self._reset.pending:  # a new motion during a reset: the blend goes on toward it (soak seed 10091: it
            out = self._reset.step(out, 0.0 if ctx.last_ports.hold else ctx.dt_s)  # was dropped, and BODY rose
            # 4 cm in a tick from a squat); still under the hard e-stop's hold
        last.ref_out = out
        return out

    def _command_feet(self, ctx: TickContext, stopped: bool, yaw_rad: float) -> None:
        """The foot point's command for the AutoBalancer: while the motion is stopped, the target the revert went
        back to (None before the foot was operated: it is put down), else the integrated one."""
        targets = self._points.targets
        if stopped and self._history.revert_to_s is not None:
            entry = self._history.entry_at(self._history.revert_to_s)
            targets = {} if entry is None else entry[1]
        ctx.ports.foot_command = FootPoints.command(targets)
        if stopped:
            for foot in FEET:
                if foot in self._points.targets:
                    self._points.limited[foot] = MOTION_STOP
        FootPoints.settle(self._points, ctx.last_ports.gait, yaw_rad)

    def _seed(self, point: str, anchor: np.ndarray, ground_in_feet_m: float = 0.0):
        """A point's first target: where the posture has it now, in F (self.kin is on it, in F), the hands
        and the neck relative to `anchor` (F's origin standing, BODY walking)."""
        p, R = self.kin.frame_pose(POINT_FRAMES[point])
        if point != "waist":
            p = p - anchor
        if point in HANDS:
            return HandPose.of(p, R)
        if point == "head":
            self._points.neck_feet_m = self.kin.frame_pose(NECK_FRAME)[0] - anchor
            return GazeAngles.of_direction(R[:, 0])
        return WaistPose(float(p[2]) + ground_in_feet_m, tuple(matrix_to_rpy(R).tolist()))

    def _on_release(self) -> None:
        """The EmergencyStopper released the motion: restart from the targets its revert went back to."""
        entry = self._history.release()
        self._commands.streamed.clear()  # a setpoint streamed into the stop is not replayed
        if entry is None:
            self._deactivate()  # reverted to before anything was operated: the plain reference
            return
        self._points.targets = dict(entry[1])
        self.ik.warm_start(entry[2])
        self._version += 1

    # ---- reading ------------------------------------------------------------------------------------
    def view(self) -> OperationView:
        """The points as the layer's last output reference puts them (FK of the controller's reference,
        placed in the world by the gait's feet frame), the gaze and waist height in F. Computed once per
        tick: the callers of one tick (the behaviours) share it (read-only arrays; do not modify)."""
        return self._view.of(self._last, self._frames)

    def status(self) -> OperationStatus:
        return self._status.get((self._version, self.enabled), self._build_status)

    def _build_status(self) -> OperationStatus:
        return operation_status(self.enabled, self._last.stopped, self._commands, self._points, self._walk)
