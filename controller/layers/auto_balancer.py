"""AutoBalancer layer ([MLC] III-C): footsteps and reference ZMP from the gait planner, COG by preview
control (Eq. 5), COG offset against hand forces (Eq. 6), whole-body IK with feet, COG X-Y, base height
and orientation; when not walking it keeps the COG over the feet while the upper body moves, and steps when the
capture point leaves the support polygon (the capture-point emergency step)."""

from __future__ import annotations

import dataclasses
import math
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np

from controller.balance.capture_point import HRP2_RIGHT_SOLE
from controller.balance.hand_forces import HandForceOffset
from controller.balance.tilt_anchor import TiltAnchor
from controller.core.errors import InvalidState
from controller.core.layer import Layer
from controller.core.types import GaitState, Ports, Reference, TickContext, WalkCommand, read_only
from controller.interpolation.blend import Transition
from controller.interpolation.rate_limit import approach
from controller.kinematics.fullbody_ik import WALK_LEG_LIMIT_MARGIN_RAD, FullbodyIK, nearest_leg_limit
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import homogeneous, rpy_to_rows
from controller.walking.auto_balancer_params import (
    WALK_STANCE_MAX_WIDTH_M,
    AutoBalancerParams,
    AutoBalancerStatus,
    FootstepStatus,
    stance_width_m,
    walk_command_valid,
)
from controller.walking.close_stance import CLOSE_STANCE_LOWERING_M, closing_gait_params, closing_steps
from controller.walking.emergency_stepping import EmergencyStepping, PreparedReplan
from controller.walking.foot_lift import FootLift
from controller.walking.footsteps import StepParams
from controller.walking.gait_generator import GaitGenerator
from controller.walking.preview_control import PreviewController, PreviewControlParams
from controller.walking.stop_from_rest import levelling_time_s, rest_zmp_xy, tilted, tipped
from controller.walking.toe_heel import ToeHeelParams
from robot.names import JOINT_NAMES

#: the AutoBalancer stops only this close to where its input reference places BODY (x, y [m]; yaw [rad]):
#: stopped, it passes that reference on, and the Stabilizer then balances the robot toward that place (a stop
#: 0.3 m from it after a walk tipped the robot over). Standing where it started, BODY is 3 mm from it.
STOP_PLACE_TOLERANCE_M = 0.02
STOP_YAW_TOLERANCE_RAD = math.radians(2.0)
#: [s] the BODY lowering of an emergency step comes in over this time, and goes back over 4 times it once standing
BASE_LOWERING_TIME_S = 0.2
#: [m/s] a waist raised above the walking height comes down to it at this rate once a walk starts (within the first
#: step's initial double support), and goes back up at it once standing
WALK_HEIGHT_RATE_M_S = 0.2
#: [m] BODY may stand this much above the walking height while walking (no lowering for rounding)
WALK_HEIGHT_SLACK_M = 0.001

#: New preview gains (preview_q / preview_r) are computed off the control thread (a Riccati solve, ~15 ms) and
#: swapped in at the first standstill tick at least this long after the change: a fixed delay in ticks keeps a
#: run at `--speed max` deterministic, and is far longer than the solve.
PREVIEW_GAINS_DELAY_S = 0.2


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
        self._q_lower_rad, self._q_upper_rad = self.kin.q_lower.tolist(), self.kin.q_upper.tolist()
        self.total_mass = self.kin.total_mass
        self.kin.update_rpy(initial.base_pos_world, initial.base_rpy_rad, initial.q_rad)
        T_r, T_l = (homogeneous(*self.kin.frame_pose(f)) for f in ("rleg_end", "lleg_end"))
        # toe and heel edges of HRP-2's sole (the model's sole box), not HRP2-JSKNT's 0.137 / -0.10
        toe_heel = ToeHeelParams(toe_offset_x_m=HRP2_RIGHT_SOLE.front_m, heel_offset_x_m=-HRP2_RIGHT_SOLE.rear_m)
        p = self.params
        self.gait = GaitGenerator(p.gait_params(), dt_s, T_world_rfoot=T_r, T_world_lfoot=T_l, toe_heel=toe_heel,
                                  footstep_params=p.footstep_params(dt_s), stride_limits=p.stride_limits())
        com = self.kin.com_world()
        ground_z = 0.5 * (T_r[2, 3] + T_l[2, 3])
        self.com_height_m = float(com[2] - ground_z)
        self.preview = PreviewController(PreviewControlParams(
            dt_s=dt_s, com_height_m=self.com_height_m, q=self.params.preview_q, r=self.params.preview_r))
        self.preview.reset(self.gait.tick().zmp_world[:2])
        self._gains_pool: ThreadPoolExecutor | None = None
        self._pending_preview: Future[PreviewController] | None = None  # new gains being computed
        self._pending_ticks = 0  # ticks to wait before the pending gains may be swapped in
        self._hands = HandForceOffset(self.kin, self.total_mass)  # Eq. 6
        # blend between the plain plan (0) and the balanced posture (1)
        self.active = False
        self._weight = 0.0
        self._blend: Transition | None = None  # start / stop blend of the weight
        self.has_ik_failed = False
        self.last_gait: GaitState | None = None
        self._footsteps_cache: tuple[int, int, tuple] | None = None
        self._walking_stop_requested = False  # emergency walking stop asked for since the last walk command
        self._last_out: Reference | None = None  # the last working tick's output (repeated while held)
        self._last_in: Reference | None = None  # that tick's input reference
        self._holding = False  # the hard e-stop holds the chain
        self._tilt: TiltAnchor | None = None  # the plan seen from a robot tipped onto its swing foot while held
        self._port_walking = False  # the walk in progress is driven by the walking point (Ports.walk_command)
        self._walk_armed = True  # False after an e-stop or walking stop, until the walking point reads zero
        self._walk_point = "idle"
        self._last_cp_flag = False  # Ports.cp_flag as the last tick read it (the walking stop is on its rise)
        self.estep = EmergencyStepping(self.gait, dt_s, self.total_mass)  # the capture-point emergency steps
        self._walk_cut: str | None = None  # why the last walk ended early (status)
        self._was_walking = False
        self._base_lowering_m = 0.0  # [m] BODY below the planned height (emergency step)
        self._walk_base_z_m = float(initial.base_pos_world[2])  # [m] the height walks plan at (the preview's)
        self._walk_lowering_m = 0.0  # [m] BODY below a raised waist while walking (and while closing a stance)
        self._closing_stance = False  # the walk is close_stance's step
        self._prepared: PreparedReplan | None = None  # after_write's re-plan, for the next tick only
        self.lift = FootLift(dt_s)  # a foot moved by its operational point while standing
        if active:
            self.start()

    # ---- operations --------------------------------------------------------------------------
    def start(self) -> None:
        if self.active:
            raise InvalidState("AutoBalancer is already active")
        self.active = True
        self._blend = Transition(self._weight, 1.0, self.params.transition_time_s, "min_jerk")

    def stop(self) -> None:
        if not self.active:
            raise InvalidState("AutoBalancer is not active")
        if self.gait.walking:
            raise InvalidState("AutoBalancer cannot stop while walking: stop the walk (goStop) and let it end first")
        away = self.away_from_reference()
        if away is not None and (away[0] > STOP_PLACE_TOLERANCE_M or abs(away[1]) > STOP_YAW_TOLERANCE_RAD):
            raise InvalidState(
                f"AutoBalancer cannot stop {away[0]:.3f} m and {math.degrees(away[1]):.1f} deg away from where its "
                "input reference places BODY (the SequencePlayer's base: where the robot started or was reset): "
                "stopped, it would hand that reference on and the Stabilizer would pull the robot back there; walk "
                f"back to within {STOP_PLACE_TOLERANCE_M:g} m and {math.degrees(STOP_YAW_TOLERANCE_RAD):g} deg of "
                "it (goPos), or reset the simulation")
        self.active = False
        self._blend = Transition(self._weight, 0.0, self.params.transition_time_s, "min_jerk")

    def away_from_reference(self) -> tuple[float, float] | None:
        """How far BODY as the AutoBalancer places it is from where its input reference does: (horizontal distance
        [m], yaw [rad]); None before its first working tick."""
        if self._last_out is None or self._last_in is None:
            return None
        d = self._last_out.base_pos_world[:2] - self._last_in.base_pos_world[:2]
        yaw = float(self._last_out.base_rpy_rad[2] - self._last_in.base_rpy_rad[2])
        return float(math.hypot(d[0], d[1])), math.atan2(math.sin(yaw), math.cos(yaw))

    def set_params(self, params: AutoBalancerParams) -> None:
        """New parameters; the gait's apply to the footsteps planned from now on (hrpsys setGaitGeneratorParam)."""
        gains_changed = (params.preview_q, params.preview_r) != (self.params.preview_q, self.params.preview_r)
        self.params = params
        if gains_changed:
            self._compute_preview_gains(params)
        gait = self.gait
        gait.configure(params=params.gait_params(gait.params),
                       footstep_params=params.footstep_params(self.dt_s, gait.footstep_params),
                       stride_limits=params.stride_limits())

    def _compute_preview_gains(self, params: AutoBalancerParams) -> None:
        """Start the Riccati solve for new preview gains on a worker thread; `_swap_preview` puts them in."""
        if self._gains_pool is None:
            self._gains_pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="abc-preview-gains")
        self._pending_preview = self._gains_pool.submit(PreviewController, PreviewControlParams(
            dt_s=self.dt_s, com_height_m=self.com_height_m, q=params.preview_q, r=params.preview_r))
        self._pending_ticks = max(1, round(PREVIEW_GAINS_DELAY_S / self.dt_s))

    def _swap_preview(self) -> None:
        """Pending preview gains replace the current ones at a standstill (not walking): the new controller
        starts from the COG's planned position and velocity; a walk keeps the gains it started with."""
        if self._pending_ticks > 0:
            self._pending_ticks -= 1
            return
        if self.gait.walking:
            return
        new = self._pending_preview.result()  # done long ago in practice: the delay is ~15x the solve
        new.reset(self.preview.x[0].copy(), self.preview.x[1].copy())
        self.preview = new
        self._pending_preview = None
        if self._gains_pool is not None:  # no idle thread left behind (a reset builds a new AutoBalancer)
            self._gains_pool.shutdown(wait=False)
            self._gains_pool = None

    @property
    def walking_stop(self) -> bool:
        """The emergency walking stop is in force: asked for, and the robot still stepping (in place, or an
        emergency step)."""
        return self._walking_stop_requested and (self.gait.walking or self.estep.active)

    def _require_active(self, what: str) -> None:
        if not self.active or self._blend is not None:
            raise InvalidState(f"{what}: the AutoBalancer must be running (start it first)")

    def go_pos(self, x_m: float, y_m: float, theta_rad: float) -> int:
        """hrpsys goPos relative to the current feet mid-coords; returns the number of footsteps to go.

        While walking it replaces the rest of the plan (hrpsys): the goal is then relative to the feet's
        mid-coords where this walk began (`gait.walk_origin`), the new steps start at the next free footstep,
        and a velocity walk (the walking point's too) ends in it. Returns 0 when the walk is in its last
        step: the new goal is then walked to from where the robot stands at its end."""
        self._require_active("goPos")
        self._require_balanced("goPos")
        if self.walking_stop:
            raise InvalidState("goPos: the emergency walking stop is in force (stepping in place); "
                               "goPos again once the robot stands")
        was_walking = self.gait.walking
        steps = self.gait.go_pos(x_m, y_m, theta_rad)
        self._walking_stop_requested = False
        self._port_walking = False  # the footsteps win; the walking point may drive the next walk
        if not was_walking:
            return len(steps)
        return len(self.gait.remaining_footsteps()) if steps else 0

    def go_velocity(self, vx_m_s: float, vy_m_s: float, vtheta_rad_s: float) -> None:
        self._require_active("goVelocity")
        self._require_balanced("goVelocity")
        if self.walking_stop:  # campaign seed 1012: a refused goVelocity had cleared the stop, and the walk went on
            raise InvalidState("goVelocity: the emergency walking stop is in force (stepping in place); "
                               "goVelocity again once the robot stands")
        self.gait.go_velocity(vx_m_s, vy_m_s, vtheta_rad_s)
        self._walking_stop_requested = False

    def go_stop(self) -> None:
        self.gait.go_stop()

    @property
    def emergency_step(self) -> bool:
        """A capture-point emergency step is in progress."""
        return self.estep.active

    def close_stance(self) -> int:
        """A stance wider than a walk starts from (a catching step's landing) closed by one slow step with BODY
        lowered (controller/walking/close_stance.py); returns the footsteps planned."""
        self._require_active("closeStance")
        if self.gait.walking:
            raise InvalidState("closeStance: the robot is walking; closeStance once it stands")
        self._require_balanced("closeStance", stance=False)
        cog = self.last_gait.cog_world if self.last_gait is not None else self.preview.x[0]
        steps = closing_steps(self.gait.T_world_rfoot, self.gait.T_world_lfoot, (float(cog[0]), float(cog[1])),
                              self.gait.footstep_params)  # raises InvalidState outside the widths it closes
        self.gait.plan(steps, params=closing_gait_params(self.gait.params))
        self._closing_stance = True
        self._walking_stop_requested = False
        self._port_walking = False
        return len(steps)

    def _require_balanced(self, what: str, stance: bool = True) -> None:
        if self.lift.active:
            raise InvalidState(f"{what}: the {self.lift.foot} is lifted (its operational point); "
                               f"{what} once it is down")
        if self._closing_stance and self.gait.walking:
            raise InvalidState(f"{what}: the robot is closing its stance (closeStance); {what} once it stands")
        if self.estep.active:
            raise InvalidState(f"{what}: a capture-point emergency step is in progress; {what} again once the "
                               "robot stands (status: abc.emergency_step false)")
        if self._last_cp_flag and not self.gait.walking:  # a walk started off balance falls (campaign seed 1009)
            raise InvalidState(f"{what}: the capture-point flag is up (the robot is balancing a disturbance); "
                               f"{what} again once it drops (status: st.emergency false)")
        near = self._legs_near_limit(stance)
        if near is not None:
            raise InvalidState(f"{what}: {near}")

    def _legs_near_limit(self, stance: bool = True) -> str | None:
        """Why a walk cannot start from the legs' pose (the waist tilted until a leg joint has too little range
        left to walk; campaign seeds 1017, 1018; the feet too far apart, seed 1004), or None."""
        if self.gait.walking or self._last_out is None:
            return None
        width = stance_width_m(self.gait.T_world_rfoot, self.gait.T_world_lfoot)
        if stance and width > WALK_STANCE_MAX_WIDTH_M:
            return (f"the feet stand {width:.3f} m apart across (a catching step's landing), wider than a walk can "
                    f"start from ({WALK_STANCE_MAX_WIDTH_M:g} m): the COM over one foot stretches the other leg "
                    "straight; `stand` (closeStance) closes it first")
        i, margin = nearest_leg_limit(self._last_out.q_rad, self._q_lower_rad, self._q_upper_rad)
        if margin >= WALK_LEG_LIMIT_MARGIN_RAD:
            return None
        return (f"{JOINT_NAMES[i]} is {math.degrees(margin):.1f} deg from its limit (the waist's tilt) and walking "
                f"needs {math.degrees(WALK_LEG_LIMIT_MARGIN_RAD):g} deg; straighten the waist first")

    def emergency_stop_walking(self) -> None:
        """Remaining footsteps replaced so the robot stops in place (manipulation is left alone). The walking
        point is ignored from now until it reads zero (a held stick does not walk on after the stop). An emergency
        step in progress goes on (it ends standing by itself), the stop in force until it has (soak seed 10495:
        it was answered ok and not in force)."""
        if not self.estep.active:
            self.gait.emergency_stop()
        self._walking_stop_requested = True
        self._disarm_walk_point()

    def _disarm_walk_point(self) -> None:
        self._port_walking = False
        self._walk_armed = False

    def _walk_at(self, cmd: WalkCommand | None) -> None:
        """The walking point this tick (hrpsys goVelocity each tick): a non-zero command walks at it, the
        velocity and step parameters taken by the velocity steps planned at the next mid-step check (the
        gait goes on); zero or None after a walk it drove ends that walk as goStop does. Ignored (said in
        status().walk_point) under the emergency walking stop, before the AutoBalancer runs, while a
        footstep list is walked, while a stop from rest after the e-stop plays, and, after a stop, until it
        has read zero once. Never raises: an invalid command is ignored too."""
        if cmd is None or cmd.is_zero:
            self._walk_armed = True
            if self._port_walking:
                self._port_walking = False
                self.gait.go_stop()
            self._walk_point = "idle"
            return
        why = self._walk_point_refusal(cmd)
        if why is not None:
            self._walk_point = why
            return
        gait = self.gait
        gait.set_velocity_step(cmd.max_stride_m, cmd.foot_distance_m)
        gait.go_velocity(cmd.vx_m_s, cmd.vy_m_s, cmd.vtheta_rad_s)
        self._walking_stop_requested = False
        self._port_walking = True
        self._walk_point = "walking"

    def _walk_point_refusal(self, cmd: WalkCommand) -> str | None:
        if self.lift.active:
            return f"ignored: the {self.lift.foot} is lifted (its operational point); walk once it is down"
        if self.estep.active:
            return "ignored: a capture-point emergency step is in progress"
        if self._last_cp_flag and not self.gait.walking:
            return "ignored: the capture-point flag is up; the walking point must read zero once after it drops"
        near = self._legs_near_limit()
        if near is not None:
            return f"ignored: {near}"
        if not self._walk_armed:
            return "ignored: stopped; the walking point must read zero once before walking again"
        if self.walking_stop:
            return "ignored: the emergency walking stop is in force"
        if not self.active or self._blend is not None:
            return "ignored: the AutoBalancer is not running"
        gait = self.gait
        if gait.walking and gait.velocity_mode not in ("walking", "ending"):
            return ("ignored: the walk is ending after the e-stop" if gait.stopping_from_rest
                    else "ignored: walking a footstep list (goPos / setFootSteps)")
        if not walk_command_valid(cmd):
            return "ignored: out of range (see check_walk_command)"
        return None

    def set_footsteps(self, footsteps: list[tuple], step_params: list[StepParams | None] | None = None) -> int:
        """hrpsys setFootSteps: `(leg, pos [m], rpy [rad])`, relative to the first, which is snapped to
        the current pose of that leg."""
        self._require_active("setFootSteps")
        self._require_balanced("setFootSteps")
        if self.gait.walking:
            raise InvalidState("setFootSteps while walking is not supported; wait for the steps to finish")
        self._walking_stop_requested = False
        return len(self.gait.set_footsteps(footsteps, step_params))

    def remaining_footsteps(self) -> tuple[FootstepStatus, ...]:
        return tuple(FootstepStatus(leg=f.leg, pos=(f.x, f.y, f.z), rpy=(f.roll, f.pitch, f.yaw),
                                    step_time_s=f.step_time_s, step_height_m=f.step_height_m)
                     for f in self.gait.remaining_footsteps())

    # ---- pieces ----------------------------------------------------------------------------------
    def _hand_force_offset(self, ref: Reference, cog_pc_xy: np.ndarray, zmp_z: float) -> np.ndarray:
        return self._hands.cog_xy(ref, cog_pc_xy, zmp_z) if self.params.use_hand_force_offset else cog_pc_xy

    # ---- tick ------------------------------------------------------------------------------------
    def tick(self, ctx: TickContext, ref: Reference) -> Reference:
        prepared, self._prepared = self._prepared, None  # made for this tick, or dropped
        if not self.enabled:  # pass-through
            self.last_gait = None
            return ref
        if ctx.balance_hold and self._last_out is not None:
            out = self._hold()
            tilt = self._tipped(ctx, out.gait, 1.0)
            if tilt is not None:  # the references follow the robot that tipped while held (nothing moves)
                gait, base, base_rpy = tilted(out.gait, tilt)
                out = out.with_(gait=gait, base_pos_world=base, base_rpy_rad=base_rpy)
            if out.gait is not None:
                ctx.ports.cog_acc_world = out.gait.cog_acc_world
            ctx.ports.gait = out.gait
            return out
        if self._holding:
            self._resume(ctx)
        if ctx.last_ports.landing and self.gait.walking and not self.estep.active and not self._walking_stop_requested:
            if self._blend is None:  # the hard e-stop lets this step land, a late swing cut short; none after it
                self.estep.cut(ctx, self.params, self.preview)
            self.emergency_stop_walking()
        if self._blend is not None:
            self._weight = self._blend.step(ctx.dt_s)
            if self._blend.done:
                self._blend = None
        if self._weight <= 0.0 and not self.active:
            self.last_gait = None
            return ref
        if self.estep.active:
            if self.estep.tick(ctx, self.params, self.preview, self.last_gait, prepared):
                self._disarm_walk_point()  # a stick held through the step must be released before it walks again
        elif self.params.emergency_step.enabled and not self.gait.walking and self._blend is None \
                and not self.lift.active:  # (on one foot the lift keeps the COM over its sole)
            if self.estep.check_standing(ctx, self.last_gait, self.params, self.preview):
                self._walking_stop_requested = False
                self._disarm_walk_point()
        flag = ctx.last_ports.cp_flag
        if flag and not self._last_cp_flag and self.params.walking_stop_on_cp_flag and self.gait.walking \
                and not self.walking_stop and not self.estep.active:
            self._walk_cut = f"the capture-point flag at t = {ctx.time_s:.3f} s"
            if self._can_catch_while_walking(ctx):
                self._catch_while_walking(ctx)
            else:
                self.emergency_stop_walking()
        self._last_cp_flag = flag
        if flag and not self.gait.walking:
            self._walk_armed = False  # a stick held through the flag does not walk off when it drops
        cmd = ctx.ports.walk_command
        if cmd is not None or self._port_walking or not self._walk_armed:
            self._walk_at(cmd)
        elif self._walk_point != "idle":
            self._walk_point = "idle"
        if self._pending_preview is not None:
            self._swap_preview()
        lift, foot_cmd = self.lift, ctx.ports.foot_command
        if foot_cmd is not None or lift.active:
            lift.step(foot_cmd, self.gait.walking, "the capture-point flag, an emergency step or a blend" if (
                self.estep.active or self._last_cp_flag or not self.active or self._blend is not None) else None)
        future = self.gait.zmp_preview(self.preview.preview_length)
        g = self.gait.tick()
        g, lift_off = lift.sample(g) if lift.active else (g, None)
        cog_xy, cog_vel_xy, cog_acc_xy, _ = self.preview.update(lift.zmp_preview(future, g)[:, :2])
        if g.walking and not self._was_walking and not self.estep.active:
            self._walk_cut = None  # a new walk began
        self._was_walking = g.walking and not self.estep.active
        zmp = g.zmp_world
        cog_abc_xy = self._hand_force_offset(ref, cog_xy, zmp[2])
        # BODY yaw follows the feet (mean of the two sole yaws); roll and pitch from the plan
        (r00, _, _), (r10, _, _), _ = g.R_rfoot_world.tolist()
        (l00, _, _), (l10, _, _), _ = g.R_lfoot_world.tolist()
        yaw = math.atan2(r10 + l10, r00 + l00)
        roll, pitch, yaw_in = ref.base_rpy_rad.tolist()
        base_rpy = np.array((roll, pitch, yaw_in + yaw))
        R_body = np.array(rpy_to_rows(roll, pitch, yaw_in + yaw))
        rsole, lsole = (g.p_rfoot_world, g.R_rfoot_world), (g.p_lfoot_world, g.R_lfoot_world)
        base_z = float(ref.base_pos_world[2])
        if g.walking or self._walk_lowering_m:  # campaign seed 2013: a raised waist straightened the swing knee
            base_z -= self._lower_to_walking_height(base_z, g.walking, ctx.dt_s)
        if self._base_lowering_m or self.estep.active:
            base_z -= self._lower_base(ctx.dt_s)
        res = self.ik.solve(ref.q_rad, base_z, R_body, cog_abc_xy, rsole, lsole)
        self.has_ik_failed = not res.reachable
        self._hands.stale = True  # the hands moved with the solve: read again if a force needs them
        com_z = float(res.com_world[2])
        cog_abc = cog_abc_xy.tolist() if isinstance(cog_abc_xy, np.ndarray) else cog_abc_xy
        cog_pc = cog_xy.tolist() if isinstance(cog_xy, np.ndarray) else cog_xy
        w = self._weight
        q = res.q_rad if w >= 1.0 else (1.0 - w) * ref.q_rad + w * res.q_rad
        base = res.base_pos_world if w >= 1.0 else (1.0 - w) * ref.base_pos_world + w * res.base_pos_world
        gait = GaitState(
            walking=g.walking, support=g.support, contact=g.contact,
            p_rsole_world=g.p_rfoot_world, R_rsole_world=g.R_rfoot_world,
            p_lsole_world=g.p_lfoot_world, R_lsole_world=g.R_lfoot_world,
            zmp_world=zmp, cog_world=np.array((cog_abc[0], cog_abc[1], com_z)),
            cog_vel_world=np.array((cog_vel_xy[0], cog_vel_xy[1], 0.0)),
            cog_pc_world=np.array((cog_pc[0], cog_pc[1], com_z)),
            cog_acc_world=np.array((cog_acc_xy[0], cog_acc_xy[1], 0.0)),
            base_pos_world=base, base_rpy_rad=base_rpy,
            foot_lift=None if lift_off is None else (lift.foot, tuple(lift_off.tolist())))
        zmp_base = R_body.T @ (zmp - base)
        if self._tilt is not None:
            gait, base, base_rpy = tilted(gait, self._tilt)
            self._tilt.step(ctx.dt_s)
            if self._tilt.done:
                self._tilt = None
        self.last_gait = gait
        # all fresh arrays of this tick: frozen in place rather than copied
        self._last_out = ref.with_owned(q_rad=q, base_pos_world=base, base_rpy_rad=base_rpy, zmp_base=zmp_base,
                                         gait=gait)
        self._last_in = ref
        ctx.ports.cog_acc_world = gait.cog_acc_world
        ctx.ports.gait = gait
        ctx.ports.step = self.estep.step_port(ctx, self.params)
        if self.estep.active:
            self.estep.k += 1
        return self._last_out

    # ---- the capture-point emergency step ---------------------------------------------------------------
    def _can_catch_while_walking(self, ctx: TickContext) -> bool:
        return (self.params.walking_capture_step and self.params.emergency_step.enabled and self._blend is None
                and not self.gait.stopping_from_rest and ctx.last_ports.balance is not None
                and not ctx.last_ports.landing)

    def _catch_while_walking(self, ctx: TickContext) -> None:
        """The capture-point flag rose while walking: the walk ends where it is, a foot in the air lands where the
        capture point will be (EmergencyStepping.catch); the walking stop is in force until the robot stands."""
        caught = self.estep.catch(ctx, self.params, self.preview)
        self._disarm_walk_point()
        if caught:
            self._walking_stop_requested = True

    def after_write(self, ports: Ports) -> None:
        """The emergency step's re-plan of the next tick's sample from the capture point this tick measured
        (ports.balance), made once the command is out: the next tick adopts it (PreparedReplan) instead of
        computing it, if nothing changed its inputs meanwhile. It changes nothing: the status, a command at the
        tick boundary and a next tick that does not re-plan (held, touched down, stepping again) see none of it."""
        self._prepared = self.estep.prepare(ports)

    def _lower_to_walking_height(self, base_z_m: float, walking: bool, dt_s: float) -> float:
        """BODY's lowering [m] this tick: while walking, toward how far the operated waist is above the walking
        height; standing, back to zero (rate-limited both ways)."""
        self._closing_stance = self._closing_stance and walking
        target = max(0.0, base_z_m - self._walk_base_z_m - WALK_HEIGHT_SLACK_M) if walking else 0.0
        target += CLOSE_STANCE_LOWERING_M if self._closing_stance else 0.0
        self._walk_lowering_m = low = approach(self._walk_lowering_m, target, WALK_HEIGHT_RATE_M_S * dt_s)
        return low

    def _lower_base(self, dt_s: float) -> float:
        """BODY's lowering [m] this tick: toward emergency_step.base_lowering_m while an emergency step is taken,
        back to zero once the robot stands (rate-limited, both ways)."""
        target = self.params.emergency_step.base_lowering_m if self.estep.active else 0.0
        rate = self.params.emergency_step.base_lowering_m / BASE_LOWERING_TIME_S * (1.0 if target else 0.25)
        self._base_lowering_m = low = approach(self._base_lowering_m, target, max(rate, 1e-6) * dt_s)
        return low

    def _resume(self, ctx: TickContext) -> None:
        """Released from the hard e-stop: the robot stood still, so the COG plan restarts from rest where it
        is; a walk that was cut ends from there, on both feet if the robot tipped onto its swing foot. A robot
        that tipped rests tilted: the plan is then seen rotated by that tilt about the support sole, levelling
        as the swing foot lands (TiltAnchor), so the references agree with where the robot is."""
        self._holding = False
        self.preview.reset(self.preview.x[0].copy())
        gait = self._last_out.gait if self._last_out is not None else None
        if self.gait.walking and gait is not None and gait.support != "both":
            tilt = self._tipped(ctx, gait, 1.0)
            landing_s = self.gait.stop_from_rest(rest_zmp_xy(self.preview.x[0], gait if tilt is None else None),
                                                 swing_foot_loaded=tilt is not None,
                                                 min_landing_time_s=max(0.8, levelling_time_s(tilt)))
            if tilt is not None and landing_s > 0.0:
                self._tilt = self._tipped(ctx, gait, landing_s)

    def _tipped(self, ctx: TickContext, gait: GaitState | None, duration_s: float) -> TiltAnchor | None:
        """The held walk's robot resting on its swing foot as well (stop_from_rest.tipped); None when not walking."""
        return tipped(gait, ctx.estimate, duration_s) if self.gait.walking else None

    def _hold(self) -> Reference:
        """A tick under the hard e-stop: the plan does not advance, and the last output is repeated with the
        COG at rest. A walk is cut to a stop that starts from rest where the robot is frozen (the swing
        foot goes down, the ZMP comes to the feet's middle), played after the release."""
        if not self._holding:
            self._holding = True
            self._disarm_walk_point()
            self._walk_point = "ignored: the hard e-stop holds"
            self.estep.drop()  # the stop from rest replaces an emergency step too
            if self.gait.walking:
                self._walking_stop_requested = True
                self.gait.stop_from_rest(rest_zmp_xy(self.preview.x[0], self._last_out.gait))
            out = self._last_out
            if out.gait is not None:
                still = read_only(np.zeros(3))
                out = out.with_(gait=dataclasses.replace(out.gait, cog_vel_world=still, cog_acc_world=still))
            self._last_out = out
            self.last_gait = out.gait
        return self._last_out

    def status(self) -> AutoBalancerStatus:
        g = self.last_gait
        return AutoBalancerStatus(enabled=self.enabled, active=self.active, weight=round(self._weight, 4),
                                  walking=bool(g.walking) if g else False, support=g.support if g else "both",
                                  walking_stop=self.walking_stop, has_ik_failed=self.has_ik_failed,
                                  footsteps=self._status_footsteps() if self.gait.walking else (),
                                  walk_point=self._walk_point,
                                  preview_gains="current" if self._pending_preview is None else "pending",
                                  emergency_step=self.estep.active, emergency_steps=self.estep.records,
                                  walk_cut=self._walk_cut, walk_height_lowering_m=round(self._walk_lowering_m, 4),
                                  foot_lift=self.lift.refused or self.lift.phase, lifted_foot=self.lift.foot)

    def _status_footsteps(self) -> tuple[FootstepStatus, ...]:
        """remaining_footsteps() for status(), rebuilt only when the plan or the footstep index changes
        (the list is shared between snapshots: readers must not modify it)."""
        remaining = self.gait.remaining_footsteps()
        # the remaining steps are a tail of the plan: its version and the tail length identify the content
        plan = self.gait.plan_version
        cache = self._footsteps_cache
        if cache is None or cache[0] != plan or cache[1] != len(remaining):
            cache = self._footsteps_cache = (plan, len(remaining), self.remaining_footsteps())
        return cache[2]
