"""AutoBalancer layer ([MLC] III-C): footsteps and reference ZMP from the gait planner, COG by preview
control (Eq. 5), COG offset against hand forces (Eq. 6), whole-body IK with feet, COG X-Y, base height
and orientation; when not walking it keeps the COG over the feet while the upper body moves, and steps when the
capture point leaves the support polygon (the capture-point emergency step)."""

from __future__ import annotations

import dataclasses
import math
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from controller.balance.capture_point import HRP2_LEFT_SOLE, HRP2_RIGHT_SOLE
from controller.balance.hand_force_cog_offset import cog_offset_against_hand_forces
from controller.balance.tilt_anchor import TiltAnchor
from controller.core.constants import GRAVITY_M_S2
from controller.core.errors import InvalidCommand, InvalidState
from controller.core.layer import Layer, Params, Status, described
from controller.core.types import (
    BalanceEstimate,
    GaitState,
    Ports,
    Reference,
    StepInProgress,
    TickContext,
    WalkCommand,
    read_only,
)
from controller.interpolation.blend import Transition
from controller.kinematics.fullbody_ik import WALK_LEG_LIMIT_MARGIN_RAD, FullbodyIK, nearest_leg_limit
from controller.kinematics.model import RobotKinematics
from controller.kinematics.rotations import matrix_to_rpy, rpy_to_matrix, rpy_to_rows
from controller.operation.ranges import (
    WALK_FOOT_DISTANCE_RANGE_M,
    WALK_MAX_ANGULAR_RAD_S,
    WALK_MAX_LINEAR_M_S,
    WALK_MAX_STRIDE_RANGE_M,
)
from controller.walking.emergency_step import EmergencyStepParams, EmergencyStepPlan, SupportRegion, swing_leg_for
from controller.walking.footsteps import Footstep, FootstepParams, StepParams, StrideLimits
from controller.walking.gait_generator import GaitGenerator, GaitParams, GaitPatch
from controller.walking.preview_control import PreviewController, PreviewControlParams
from controller.walking.toe_heel import ToeHeelParams
from robot.names import FORCE_SENSOR_NAMES, JOINT_NAMES

HANDS = (FORCE_SENSOR_NAMES.index("rhsensor"), FORCE_SENSOR_NAMES.index("lhsensor"))
REST_ZMP_MARGIN_M = 0.02  # [m] a robot stopped on one foot keeps its ZMP this far inside the sole
FEET = (FORCE_SENSOR_NAMES.index("rfsensor"), FORCE_SENSOR_NAMES.index("lfsensor"))
#: [N] a swing foot reading more has touched down (the Stabilizer's contact threshold)
SWING_FOOT_LOADED_N = 25.0
#: the AutoBalancer stops only this close to where its input reference places BODY (x, y [m]; yaw [rad]):
#: stopped, it passes that reference on, and the Stabilizer then balances the robot toward that place (a stop
#: 0.3 m from it after a walk tipped the robot over). Standing where it started, BODY is 3 mm from it.
STOP_PLACE_TOLERANCE_M = 0.02
STOP_YAW_TOLERANCE_RAD = math.radians(2.0)
#: [rad/s] a robot that tipped onto its swing foot under the hard e-stop lands it, and so levels, along a
#: minimum-jerk path whose peak rate is this: well below the KalmanFilter's gyro trust band (0.1 rad/s), so its
#: accelerometer keeps the attitude right as the robot turns back (levelling 7 deg in 2 s, 0.11 rad/s at the
#: peak, the estimate lagged 0.5 deg and caught up in a jump: a capture-point error of 42-58 mm; in 5.7 s (0.04
#: rad/s) 30-38 mm, in 7.6 s 32-36 mm)
TIPPED_LEVELLING_RATE_RAD_S = 0.03
#: [rad] ... when it rests tilted more than this (a swing foot loaded with the robot level lands in the usual time)
TIPPED_MIN_TILT_RAD = math.radians(1.0)
#: [-] peak over mean rate of a minimum-jerk path (15/8)
MIN_JERK_PEAK_RATIO = 1.875
#: [-] share of the robot's weight the feet must carry for an emergency step (a robot held in the air does not step)
EMERGENCY_STEP_MIN_LOAD_RATIO = 0.5
#: [-] an emergency step's foot touches down early when it carries this share of the weight after this share of its
#: swing (the force sensor of a foot swung fast reads its inertia: up to 110 N measured 5 cm above the ground)
TOUCHDOWN_LOAD_RATIO = 0.25
TOUCHDOWN_SWING_SHARE = 0.6
#: [s] the swing of a capture step from a walk: the walk's remaining swing, within these (the foot needs time to go
#: where the capture point calls it; a long swing is shortened so the foot lands before the capture point runs away)
CATCH_SWING_S = (0.16, 0.25)
#: [s] after an emergency step's touchdown, a capture point still outside the two soles calls for another step
RESTEP_AFTER_S = 0.05
#: emergency steps one after the other at most (each from the last one's feet)
EMERGENCY_STEPS_IN_A_ROW = 3
#: emergency steps remembered in the status
EMERGENCY_STEPS_KEPT = 10
#: [s] the BODY lowering of an emergency step comes in over this time, and goes back over 4 times it once standing
BASE_LOWERING_TIME_S = 0.2
#: [m/s] a waist raised above the walking height comes down to it at this rate once a walk starts (within the first
#: step's initial double support), and goes back up at it once standing
WALK_HEIGHT_RATE_M_S = 0.2
#: [m] BODY may stand this much above the walking height while walking (no lowering for rounding)
WALK_HEIGHT_SLACK_M = 0.001
#: [m] the widest stance (the soles' centres across, in their mean heading) a walk starts from: measured from 0.32 m
#: with the swing knee 7 deg from straight, from 0.36 m it straightens and raises the flag (a wide catching step)
WALK_STANCE_MAX_WIDTH_M = 0.34


def stance_width_m(T_world_rfoot: np.ndarray, T_world_lfoot: np.ndarray) -> float:
    """How far apart the soles' centres are across [m]: in the frame of their mean heading."""
    yaw = math.atan2(T_world_rfoot[1, 0] + T_world_lfoot[1, 0], T_world_rfoot[0, 0] + T_world_lfoot[0, 0])
    dx, dy = (T_world_lfoot[:2, 3] - T_world_rfoot[:2, 3]).tolist()
    return abs(-math.sin(yaw) * dx + math.cos(yaw) * dy)


def check_walk_command(cmd: WalkCommand) -> None:
    """Raise InvalidCommand naming the field and the allowed range when the walking point's command is not
    one the AutoBalancer takes (what the operation layer and the verbs check before it reaches the loop)."""
    for name, value, limit, unit in (("vx_m_s", cmd.vx_m_s, WALK_MAX_LINEAR_M_S, "m/s"),
                                     ("vy_m_s", cmd.vy_m_s, WALK_MAX_LINEAR_M_S, "m/s"),
                                     ("vtheta_rad_s", cmd.vtheta_rad_s, WALK_MAX_ANGULAR_RAD_S, "rad/s")):
        if not (math.isfinite(value) and abs(value) <= limit):
            raise InvalidCommand(f"walk.{name}={value!r} [{unit}]; allowed: [{-limit:g}, {limit:g}]")
    for name, value, (lo, hi) in (("max_stride_m", cmd.max_stride_m, WALK_MAX_STRIDE_RANGE_M),
                                  ("foot_distance_m", cmd.foot_distance_m, WALK_FOOT_DISTANCE_RANGE_M)):
        if value is not None and not (math.isfinite(value) and lo <= value <= hi):
            raise InvalidCommand(f"walk.{name}={value!r} [m]; allowed: [{lo:g}, {hi:g}] or null (the gait's own)")


def _walk_command_valid(cmd: WalkCommand) -> bool:
    try:
        check_walk_command(cmd)
    except InvalidCommand:
        return False
    return True


@dataclass(frozen=True)
class AutoBalancerParams(Params):
    """The AutoBalancer's parameters, the gait generator's among them (hrpsys setGaitGeneratorParam): a change
    applies to the footsteps planned from then on (a velocity walk's at its next mid-step check)."""

    transition_time_s: float = field(default=2.0, metadata={"unit": "s", "min": 0.01, "max": 10.0})
    use_hand_force_offset: bool = field(default=True, metadata={"unit": "-"})
    # preview-control weights (ZMP error, jerk); a change applies at the next standstill (PREVIEW_GAINS_DELAY_S)
    preview_q: float = field(default=1.0, metadata={"unit": "-", "min": 1e-6, "max": 1e6,
                                                    "doc": "preview control's ZMP-error weight"})
    preview_r: float = field(default=1e-6, metadata={"unit": "-", "min": 1e-12, "max": 1.0,
                                                     "doc": "preview control's jerk weight"})
    # gait (hrpsys default_step_time, rounded to whole control ticks; default_step_height; toe/heel angles)
    step_time_s: float = field(default=1.0, metadata={"unit": "s", "min": 0.4, "max": 5.0})
    step_height_m: float = field(default=0.05, metadata={"unit": "m", "min": 0.0, "max": 0.2})
    toe_angle_rad: float = field(default=0.0, metadata={"unit": "rad", "min": 0.0, "max": 0.6})
    heel_angle_rad: float = field(default=0.0, metadata={"unit": "rad", "min": 0.0, "max": 0.6})
    # share of each step's time in double support at its start and at its end (hrpsys default_double_support_ratio_*)
    double_support_ratio_before: float = field(default=0.1, metadata={"unit": "-", "min": 0.0, "max": 0.45})
    double_support_ratio_after: float = field(default=0.1, metadata={"unit": "-", "min": 0.0, "max": 0.45})
    # largest feet mid-coords displacement per step (hrpsys stride_parameter); "inside": towards the support foot
    stride_fwd_x_m: float = field(default=0.15, metadata={"unit": "m", "min": 0.0, "max": 0.4})
    stride_bwd_x_m: float = field(default=0.05, metadata={"unit": "m", "min": 0.0, "max": 0.3})
    stride_outside_y_m: float = field(default=0.05, metadata={"unit": "m", "min": 0.0, "max": 0.3})
    stride_inside_y_m: float = field(default=0.025, metadata={"unit": "m", "min": 0.0, "max": 0.3})
    stride_outside_th_rad: float = field(default=math.radians(10.0), metadata={"unit": "rad", "min": 0.0, "max": 0.8})
    stride_inside_th_rad: float = field(default=math.radians(5.0), metadata={"unit": "rad", "min": 0.0, "max": 0.8})
    # distance between the feet's centres when walking (hrpsys leg_default_translate_pos, both legs)
    foot_distance_m: float = field(default=0.19, metadata={"unit": "m", "min": WALK_FOOT_DISTANCE_RANGE_M[0],
                                                           "max": WALK_FOOT_DISTANCE_RANGE_M[1]})
    # the Stabilizer's capture-point flag rising while walking (Ports.cp_flag, its estop_while_walking) calls the
    # emergency walking stop: the steps end in place while the EmergencyStopper holds the motion
    walking_stop_on_cp_flag: bool = field(default=True, metadata={"unit": "-"})
    # ... by a capture step (issue 26): the walk ends where it is, a foot in the air lands where the capture point
    # will be (the emergency step below, from the swing in progress), both feet down stand; false: hrpsys'
    # emergencyStop, steps in place after the committed ones
    walking_capture_step: bool = field(default=True, metadata={"unit": "-"})
    # the capture-point emergency step (issue 13.3): standing, when the measured capture point is farther than
    # emergency_step_cp_margin_m outside the support polygon (the ankles cannot bring it back), one step where it
    # will be (controller/walking/emergency_step.py); the EmergencyStopper holds the motion, the robot ends
    # standing with its feet apart. The other fields are EmergencyStepParams' (units and ranges the same)
    emergency_step: bool = field(default=True, metadata={"unit": "-"})
    emergency_step_cp_margin_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.05, "max": 0.1})
    emergency_step_zmp_margin_m: float = field(default=0.015, metadata={"unit": "m", "min": 0.0, "max": 0.05})
    emergency_step_initial_double_support_s: float = field(default=0.05, metadata={"unit": "s", "min": 0.005,
                                                                                   "max": 0.5})
    emergency_step_time_s: float = field(default=0.3, metadata={"unit": "s", "min": 0.2, "max": 1.5})
    emergency_step_double_support_ratio: float = field(default=0.2, metadata={"unit": "-", "min": 0.05, "max": 0.5})
    emergency_step_final_double_support_s: float = field(default=1.5, metadata={"unit": "s", "min": 0.2, "max": 5.0})
    emergency_step_height_m: float = field(default=0.04, metadata={"unit": "m", "min": 0.01, "max": 0.1})
    emergency_step_max_forward_m: float = field(default=0.55, metadata={"unit": "m", "min": 0.0, "max": 0.7})
    emergency_step_max_backward_m: float = field(default=0.4, metadata={"unit": "m", "min": 0.0, "max": 0.7})
    emergency_step_min_width_m: float = field(default=0.16, metadata={"unit": "m", "min": 0.14, "max": 0.4})
    emergency_step_max_width_m: float = field(default=0.45, metadata={"unit": "m", "min": 0.16, "max": 0.7})
    emergency_step_landing_offset_m: float = field(default=0.0, metadata={"unit": "m", "min": -0.05, "max": 0.1})
    emergency_step_replan_until_s: float = field(default=0.1, metadata={"unit": "s", "min": 0.0, "max": 0.5})
    emergency_step_zmp_shift_s: float = field(default=0.03, metadata={"unit": "s", "min": 0.005, "max": 0.3})
    # BODY is lowered by this while the emergency step is taken (the legs reach farther), and raised again once
    # the robot stands
    emergency_step_base_lowering_m: float = field(default=0.04, metadata={"unit": "m", "min": 0.0, "max": 0.1})

    def validate(self) -> None:
        super().validate()
        if self.emergency_step_min_width_m > self.emergency_step_max_width_m:
            raise InvalidCommand(f"AutoBalancerParams.emergency_step_min_width_m={self.emergency_step_min_width_m} "
                                 f"> emergency_step_max_width_m={self.emergency_step_max_width_m}; "
                                 "the lateral range must not be empty")

    def emergency_step_params(self) -> EmergencyStepParams:
        return EmergencyStepParams(
            cp_margin_m=self.emergency_step_cp_margin_m, zmp_margin_m=self.emergency_step_zmp_margin_m,
            initial_double_support_s=self.emergency_step_initial_double_support_s,
            step_time_s=self.emergency_step_time_s, double_support_ratio=self.emergency_step_double_support_ratio,
            final_double_support_s=self.emergency_step_final_double_support_s,
            step_height_m=self.emergency_step_height_m, max_forward_m=self.emergency_step_max_forward_m,
            max_backward_m=self.emergency_step_max_backward_m, min_width_m=self.emergency_step_min_width_m,
            max_width_m=self.emergency_step_max_width_m, landing_offset_m=self.emergency_step_landing_offset_m,
            replan_until_s=self.emergency_step_replan_until_s, zmp_shift_s=self.emergency_step_zmp_shift_s)

    def gait_params(self, base: GaitParams | None = None) -> GaitParams:
        return (base or GaitParams()).replaced(double_support_ratio_before=self.double_support_ratio_before,
                                               double_support_ratio_after=self.double_support_ratio_after)

    def footstep_params(self, dt_s: float, base: FootstepParams | None = None) -> FootstepParams:
        step_time = max(1, round(self.step_time_s / dt_s)) * dt_s  # a whole number of control ticks
        return (base or FootstepParams()).replaced(step_time_s=step_time, step_height_m=self.step_height_m,
                                                   toe_angle_rad=self.toe_angle_rad,
                                                   heel_angle_rad=self.heel_angle_rad,
                                                   leg_offset_y_m=0.5 * self.foot_distance_m)

    def stride_limits(self) -> StrideLimits:
        return StrideLimits(fwd_x_m=self.stride_fwd_x_m, outside_y_m=self.stride_outside_y_m,
                            outside_th_rad=self.stride_outside_th_rad, bwd_x_m=self.stride_bwd_x_m,
                            inside_y_m=self.stride_inside_y_m, inside_th_rad=self.stride_inside_th_rad)


@dataclass(frozen=True, slots=True)
class FootstepStatus:
    """A planned footstep not landed yet, world frame."""

    leg: str = field(metadata=described("'rleg' or 'lleg'"))
    pos: tuple[float, float, float] = field(metadata=described("sole position", "m"))
    rpy: tuple[float, float, float] = field(metadata=described("sole roll, pitch, yaw", "rad"))
    step_time_s: float = field(metadata=described("duration of the step", "s"))
    step_height_m: float = field(metadata=described("swing height", "m"))


@dataclass(frozen=True, slots=True)
class EmergencyStepRecord:
    """A capture-point emergency step the AutoBalancer took, world frame."""

    leg: str = field(metadata=described("the leg that stepped, 'rleg' or 'lleg'"))
    time_s: float = field(metadata=described("simulated time the step was triggered", "s"))
    cp_at_trigger: tuple[float, float] = field(metadata=described("measured capture point at the trigger", "m"))
    landing: tuple[float, float] = field(metadata=described(
        "where the sole lands (x, y): the target while stepping, where it touched down once landed", "m"))
    landed: bool = field(metadata=described("the foot is down"))
    landed_early: bool = field(metadata=described("it touched down before the planned time (where it was)"))


@dataclass(frozen=True, slots=True)
class AutoBalancerStatus(Status):
    active: bool = field(metadata=described("the AutoBalancer is running (started)"))
    weight: float = field(metadata=described("start/stop blend weight, 0..1", "-"))
    walking: bool = field(metadata=described("a walk is in progress"))
    support: str = field(metadata=described("support phase: 'both', 'rleg' or 'lleg'"))
    walking_stop: bool = field(metadata=described("the emergency walking stop is in force (stepping in place)"))
    has_ik_failed: bool = field(metadata=described("the whole-body IK could not reach its targets this tick"))
    footsteps: tuple[FootstepStatus, ...] = field(metadata=described("the footsteps not landed yet"))
    walk_point: str = field(default="idle", metadata=described(
        "the walking point (Ports.walk_command): 'idle', 'walking' (abc walks at it), or 'ignored: <why>'"))
    preview_gains: str = field(default="current", metadata=described(
        "'current', or 'pending': new preview_q / preview_r wait for the next standstill"))
    emergency_step: bool = field(default=False, metadata=described(
        "a capture-point emergency step is in progress: goPos, goVelocity, setFootSteps and the walking point are "
        "refused and the EmergencyStopper holds the motion"))
    emergency_steps: tuple[EmergencyStepRecord, ...] = field(default=(), metadata=described(
        "the emergency steps taken, oldest first (the last 10)"))
    walk_cut: str | None = field(default=None, metadata=described(
        "why the last walk ended before its plan, and when (the capture-point flag, or a capture-point error with "
        "both feet down); None when it ended as planned or a new walk began"))
    walk_height_lowering_m: float = field(default=0.0, metadata=described(
        "how far BODY is held below the operated waist height because a walk is on: walking plans at the "
        "half-sitting height (a raised waist stretches the swing leg straight when the COM shifts over the "
        "stance foot)", "m"))


@dataclass(frozen=True, slots=True)
class PreparedReplan:
    """The emergency step's re-plan of sample k, made after the last tick's command was written (after_write) from
    the ports that tick published: the next tick adopts it if it re-plans the same plan at k from those ports."""

    ports: Ports  # what it read (the next tick's last_ports)
    plan: EmergencyStepPlan  # the live plan, unchanged; `replanned` is its copy, replanned at k
    k: int
    replanned: EmergencyStepPlan
    moved: bool  # replan's result
    gait_op: str | None  # what the gait gets with it: "move" (the landing and the ZMP), "zmp", or None
    zmp: np.ndarray | None  # replanned.zmp(k) for that op
    patch: GaitPatch | None  # the gait's change for that op, None if it must be done in the tick


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
        T_r, T_l = (_homogeneous(*self.kin.frame_pose(f)) for f in ("rleg_end", "lleg_end"))
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
        self._hand_pos = np.zeros((2, 3))
        self._hand_pos_stale = False  # True once a solve has moved the hands
        self._hand_frame_ids = [self.kin.model.getFrameId(n) for n in ("rarm_end", "larm_end")]
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
        #: the plan seen from a robot that tipped onto its swing foot while the e-stop held it (None: level)
        self._tilt: TiltAnchor | None = None
        self._port_walking = False  # the walk in progress is driven by the walking point (Ports.walk_command)
        self._walk_armed = True  # False after an e-stop or walking stop, until the walking point reads zero
        self._walk_point = "idle"
        self._last_cp_flag = False  # Ports.cp_flag as the last tick read it (the walking stop is on its rise)
        self._estep: EmergencyStepPlan | None = None  # the emergency step being taken
        self._estep_k = 0  # samples of its plan handed out
        self._estep_lifted = False  # the swinging foot has been unloaded in this swing
        self._estep_landing_pending = False  # the plan's landing moved before the swing; the gait's not yet
        self._estep_records: tuple[EmergencyStepRecord, ...] = ()
        self._estep_in_a_row = 0  # emergency steps taken one after the other (the first included)
        self._estep_from_walk = False  # the emergency step in progress caught a walk (it may step again)
        self._walk_cut: str | None = None  # why the last walk ended early (status)
        self._was_walking = False
        self._support: tuple[object, SupportRegion] | None = None  # (the idle soles it is for, the region)
        self._base_lowering_m = 0.0  # [m] BODY below the planned height (emergency step)
        self._walk_base_z_m = float(initial.base_pos_world[2])  # [m] the height walks plan at (the preview's)
        self._walk_lowering_m = 0.0  # [m] BODY below a raised waist while walking
        self._step_port: StepInProgress | None = None  # the last Ports.step published (reused while it holds)
        self._prepared: PreparedReplan | None = None  # after_write's re-plan, for the next tick only
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
        """The emergency walking stop is in force: asked for, and the robot still stepping in place."""
        return self._walking_stop_requested and self.gait.walking

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
        return self._estep is not None

    def _require_balanced(self, what: str) -> None:
        if self._estep is not None:
            raise InvalidState(f"{what}: a capture-point emergency step is in progress; {what} again once the "
                               "robot stands (status: abc.emergency_step false)")
        if self._last_cp_flag and not self.gait.walking:  # a walk started off balance falls (campaign seed 1009)
            raise InvalidState(f"{what}: the capture-point flag is up (the robot is balancing a disturbance); "
                               f"{what} again once it drops (status: st.emergency false)")
        near = self._legs_near_limit()
        if near is not None:
            raise InvalidState(f"{what}: {near}")

    def _legs_near_limit(self) -> str | None:
        """Why a walk cannot start from the legs' pose (the waist tilted until a leg joint has too little range
        left to walk; campaign seeds 1017, 1018; the feet too far apart, seed 1004), or None."""
        if self.gait.walking or self._last_out is None:
            return None
        width = stance_width_m(self.gait.T_world_rfoot, self.gait.T_world_lfoot)
        if width > WALK_STANCE_MAX_WIDTH_M:
            return (f"the feet stand {width:.3f} m apart across (a catching step's landing), wider than a walk can "
                    f"start from ({WALK_STANCE_MAX_WIDTH_M:g} m): the COM over one foot stretches the other leg "
                    "straight")
        i, margin = nearest_leg_limit(self._last_out.q_rad, self._q_lower_rad, self._q_upper_rad)
        if margin >= WALK_LEG_LIMIT_MARGIN_RAD:
            return None
        return (f"{JOINT_NAMES[i]} is {math.degrees(margin):.1f} deg from its limit (the waist's tilt) and walking "
                f"needs {math.degrees(WALK_LEG_LIMIT_MARGIN_RAD):g} deg; straighten the waist first")

    def emergency_stop_walking(self) -> None:
        """Remaining footsteps replaced so the robot stops in place (manipulation is left alone). The walking
        point is ignored from now until it reads zero (a held stick does not walk on after the stop). An emergency
        step in progress goes on (it ends standing by itself)."""
        if self._estep is not None:
            return
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
        if self._estep is not None:
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
        if not _walk_command_valid(cmd):
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
        if not self.params.use_hand_force_offset:
            return cog_pc_xy
        rows = ref.wrenches.tolist()
        if not any(v for i in HANDS for v in rows[i][:3]):
            return cog_pc_xy
        f = ref.wrenches[list(HANDS), :3]
        return cog_offset_against_hand_forces(cog_pc_xy, self.total_mass, self._hand_positions(), f, zmp_z,
                                              GRAVITY_M_S2)

    def _hand_positions(self) -> np.ndarray:
        """World hand positions (2, 3) [m] in the last whole-body IK solution (zeros before the first).

        Read when needed, before this tick's solve: until then the kinematic data is the last solve's."""
        if self._hand_pos_stale:
            model, data = self.kin.model, self.kin.data
            for i, fid in enumerate(self._hand_frame_ids):
                self._hand_pos[i] = pin.updateFramePlacement(model, data, fid).translation
            self._hand_pos_stale = False
        return self._hand_pos

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
                gait, base, base_rpy = self._tilted(out.gait, tilt)
                out = out.with_(gait=gait, base_pos_world=base, base_rpy_rad=base_rpy)
            if out.gait is not None:
                ctx.ports.cog_acc_world = out.gait.cog_acc_world
            ctx.ports.gait = out.gait
            return out
        if self._holding:
            self._resume(ctx)
        if ctx.last_ports.landing and self.gait.walking and self._estep is None and not self._walking_stop_requested:
            self.emergency_stop_walking()  # the hard e-stop lets this step land: no step after it
        if self._blend is not None:
            self._weight = self._blend.step(ctx.dt_s)
            if self._blend.done:
                self._blend = None
        if self._weight <= 0.0 and not self.active:
            self.last_gait = None
            return ref
        if self._estep is not None:
            self._emergency_step_tick(ctx, prepared)
        elif self.params.emergency_step and not self.gait.walking and self._blend is None:
            self._check_emergency_step(ctx)
        flag = ctx.last_ports.cp_flag
        if flag and not self._last_cp_flag and self.params.walking_stop_on_cp_flag and self.gait.walking \
                and not self.walking_stop and self._estep is None:
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
        future = self.gait.zmp_preview(self.preview.preview_length)
        cog_xy, cog_vel_xy, cog_acc_xy, _ = self.preview.update(future[:, :2])
        g = self.gait.tick()
        if g.walking and not self._was_walking and self._estep is None:
            self._walk_cut = None  # a new walk began
        self._was_walking = g.walking and self._estep is None
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
        if self._base_lowering_m or self._estep is not None:
            base_z -= self._lower_base(ctx.dt_s)
        res = self.ik.solve(ref.q_rad, base_z, R_body, cog_abc_xy, rsole, lsole)
        self.has_ik_failed = not res.reachable
        self._hand_pos_stale = True  # the hands moved with the solve: _hand_positions() reads them if needed
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
        )
        zmp_base = R_body.T @ (zmp - base)
        if self._tilt is not None:
            gait, base, base_rpy = self._tilted(gait, self._tilt)
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
        ctx.ports.step = self._step_in_progress(ctx)
        if self._estep is not None:
            self._estep_k += 1
        return self._last_out

    def _step_in_progress(self, ctx: TickContext) -> StepInProgress | None:
        """Ports.step this tick: the emergency step until it ends, or a walk's swing while its foot is in the air."""
        if self._estep is not None:
            samples, catching = self._estep.touchdown_k - self._estep_k, True
        else:
            samples, catching = self.gait.swing_samples_left(), False
            if samples == 0:
                self._step_port = None
                return None
        touchdown_s = ctx.time_s + samples * ctx.dt_s
        last = self._step_port
        if last is None or last.catching != catching or abs(last.touchdown_time_s - touchdown_s) > 0.5 * ctx.dt_s:
            last = self._step_port = StepInProgress(touchdown_s, catching)
        return last

    # ---- the capture-point emergency step ---------------------------------------------------------------
    def _check_emergency_step(self, ctx: TickContext) -> None:
        """Standing: step when the capture point the Stabilizer measured last tick is farther than the margin
        outside the support polygon of the two soles (and the feet carry the robot)."""
        bal = ctx.last_ports.balance
        g = self.last_gait
        if bal is None or g is None or g.walking or (ctx.hold and not ctx.last_ports.landing):
            return
        support = self._support
        if support is None or support[0] is not g.p_rsole_world:  # the idle soles' arrays: rebuilt when they move
            support = self._support = (g.p_rsole_world, SupportRegion.of_soles(
                (g.p_rsole_world, g.R_rsole_world), (g.p_lsole_world, g.R_lsole_world)))
        cx, cy = bal.cp_world_xy.tolist()
        if support[1].outside_m(cx, cy) <= self.params.emergency_step_cp_margin_m:
            return
        rows = ctx.estimate.wrenches_ext.tolist()
        fz_r, fz_l = rows[FEET[0]][2], rows[FEET[1]][2]
        if fz_r + fz_l < EMERGENCY_STEP_MIN_LOAD_RATIO * self.total_mass * GRAVITY_M_S2:
            return
        self._start_emergency_step(ctx, bal, fz_r, fz_l)

    def _can_catch_while_walking(self, ctx: TickContext) -> bool:
        return (self.params.walking_capture_step and self.params.emergency_step and self._blend is None
                and not self.gait.stopping_from_rest and ctx.last_ports.balance is not None
                and not ctx.last_ports.landing)

    def _catch_while_walking(self, ctx: TickContext) -> None:
        """The capture-point flag rose while walking: the walk ends where it is. A foot in the air lands where the
        capture point will be, as the emergency step does (the swing's time kept, within CATCH_SWING_S); with both
        feet down the robot stands there, and the standing emergency step follows if the ankles cannot hold it."""
        bal = ctx.last_ports.balance
        swing_left = self.gait.swing_samples_left()
        support = self.gait.abort()
        self._disarm_walk_point()
        if support == "both" or swing_left == 0:
            return  # the COG plan goes on to rest over the feet; the Stabilizer's feedback takes the push
        self.preview.reset(bal.cog_world[:2], bal.cog_vel_world[:2])
        swing_leg = "lleg" if support == "rleg" else "rleg"
        T_swing = self.gait.T_world_lfoot if swing_leg == "lleg" else self.gait.T_world_rfoot
        T_stance = self.gait.T_world_rfoot if swing_leg == "lleg" else self.gait.T_world_lfoot
        p = self.params.emergency_step_params()
        lo, hi = CATCH_SWING_S
        swing_s = min(max(swing_left * self.dt_s, lo), hi)
        height = float(T_swing[2, 3] - T_stance[2, 3])  # the foot is this high already: the arc adds the rest
        p = p.replaced(initial_double_support_s=self.dt_s,
                       step_time_s=max(swing_s / (1.0 - p.double_support_ratio), 0.2),
                       step_height_m=min(max(p.step_height_m - height, 0.01), p.step_height_m))
        rows = ctx.estimate.wrenches_ext.tolist()
        self._start_emergency_step(ctx, bal, rows[FEET[0]][2], rows[FEET[1]][2], swing_leg=swing_leg, params=p)
        self._walking_stop_requested = True  # the walking stop is in force until the robot stands
        self._estep_from_walk = True

    def _start_emergency_step(self, ctx: TickContext, bal: BalanceEstimate, fz_r: float, fz_l: float,
                              swing_leg: str | None = None, params: EmergencyStepParams | None = None) -> None:
        """Plan the step from the feet where the (idle) gait has them and start it this tick; `swing_leg`: the foot
        in the air of a walk that ended (else the leg the capture point calls for)."""
        gait = self.gait
        rfoot, lfoot = Footstep.from_T("rleg", gait.T_world_rfoot), Footstep.from_T("lleg", gait.T_world_lfoot)
        leg = swing_leg
        if leg is None:
            yaw = math.atan2(math.sin(rfoot.yaw) + math.sin(lfoot.yaw), math.cos(rfoot.yaw) + math.cos(lfoot.yaw))
            dx = float(bal.cp_world_xy[0]) - 0.5 * (rfoot.x + lfoot.x)
            dy = float(bal.cp_world_xy[1]) - 0.5 * (rfoot.y + lfoot.y)
            c, s_ = math.cos(yaw), math.sin(yaw)
            leg = swing_leg_for((c * dx + s_ * dy, -s_ * dx + c * dy), fz_r, fz_l)
        self._begin_emergency_step(ctx, bal, self._plan_emergency_step(bal, rfoot, lfoot, leg, params))

    def _plan_emergency_step(self, bal: BalanceEstimate, rfoot: Footstep, lfoot: Footstep, leg: str,
                             params: EmergencyStepParams | None = None) -> EmergencyStepPlan:
        stance, swing = (rfoot, lfoot) if leg == "lleg" else (lfoot, rfoot)
        return EmergencyStepPlan(params or self.params.emergency_step_params(), self.dt_s, stance, swing,
                                 bal.cp_world_xy, bal.zmp_world, bal.omega_1_s)

    def _begin_emergency_step(self, ctx: TickContext, bal: BalanceEstimate, plan: EmergencyStepPlan) -> None:
        """Walk `plan` from this tick (the gait idle, its feet where the plan starts)."""
        gait, leg = self.gait, plan.swing.leg
        gait.plan(plan.footsteps(), params=plan.gait_params(gait.params))
        gait.set_zmp(plan.zmp(0))
        self.preview.reset(bal.cog_world[:2], bal.cog_vel_world[:2])
        again = self._estep is not None
        self._estep_in_a_row = self._estep_in_a_row + 1 if again else 1
        self._estep_from_walk = self._estep_from_walk and again
        self._estep, self._estep_k = plan, 0
        self._estep_landing_pending = False
        self._walking_stop_requested = False
        self._disarm_walk_point()  # a stick held through the step must be released before it walks again
        self._estep_records = (*self._estep_records, EmergencyStepRecord(
            leg=leg, time_s=ctx.time_s, cp_at_trigger=tuple(bal.cp_world_xy.tolist()),
            landing=tuple(plan.landing_xy.tolist()), landed=False, landed_early=False))[-EMERGENCY_STEPS_KEPT:]
        ctx.ports.emergency_step = True

    def after_write(self, ports: Ports) -> None:
        """The emergency step's re-plan of the next tick's sample from the capture point this tick measured
        (ports.balance), made once the command is out: the next tick adopts it (PreparedReplan) instead of
        computing it, if nothing changed its inputs meanwhile. It changes nothing: the status, a command at the
        tick boundary and a next tick that does not re-plan (held, touched down, stepping again) see none of it."""
        self._prepared = None
        plan, bal = self._estep, ports.balance
        if plan is None or bal is None or not self.gait.walking:
            return
        k = self._estep_k
        if k >= plan.n_touchdown or plan.landed_k is not None:
            return  # replan does nothing any more: nothing worth preparing
        new, moved = plan.replanned(k, bal.cp_world_xy)
        op = self._estep_gait_op(plan, k, moved, new.landing_xy is not plan.landing_xy)
        zmp = patch = None
        if op is not None:
            zmp = new.zmp(k)
            patch = self.gait.prepare_set_zmp(zmp) if op == "zmp" else \
                self.gait.prepare_move_swing({1: tuple(new.landing_xy.tolist())}, zmp)
        self._prepared = PreparedReplan(ports, plan, k, new, moved, op, zmp, patch)

    def _estep_gait_op(self, plan: EmergencyStepPlan, k: int, moved: bool, foot_moved: bool) -> str | None:
        """What the gait gets after a re-plan of sample k (no touchdown): "move" (the landing with the ZMP), "zmp"
        (the ZMP alone) or None; the landing reaches the gait once, the tick before the swing (what samples the
        foot's path before it is not used; a move then resamples the whole step, the last one is what counts)."""
        if foot_moved and k < plan.n_lift - 1:
            return "zmp" if moved else None
        if foot_moved or (self._estep_landing_pending and k >= plan.n_lift - 1):
            return "move"
        return "zmp" if moved else None

    def _emergency_step_tick(self, ctx: TickContext, prepared: PreparedReplan | None = None) -> None:
        """One tick of the emergency step before the gait samples it: the landing follows the measured capture
        point (until shortly before touchdown), a foot that touches down early lands where it is, the COG plan
        restarts from the measured COG until the foot is down; the plan's end ends it (standing, the feet apart).
        The re-plan is `prepared`'s when it was made from this tick's inputs (after_write)."""
        plan, k = self._estep, self._estep_k
        if not self.gait.walking:
            self._estep = None
            self._update_record(plan, landed=True)
            return
        ctx.ports.emergency_step = True
        bal = ctx.last_ports.balance
        if self._step_again(ctx, plan, k):
            return
        ready = None  # the prepared re-plan, adopted
        if plan.swinging(k) and self._touched_down(ctx, plan, k):
            plan.land(k, self._measured_sole_xy(ctx, plan))
            moved, landed = True, True
            op = self._estep_gait_op(plan, k, moved, True)
        elif bal is not None:
            landing = plan.landing_xy
            if prepared is not None and prepared.ports is ctx.last_ports and prepared.plan is plan \
                    and prepared.k == k and prepared.replanned.revision == plan.revision + 1:
                plan.adopt(prepared.replanned)
                moved, ready = prepared.moved, prepared
            else:
                moved = plan.replan(k, bal.cp_world_xy)
            op, landed = self._estep_gait_op(plan, k, moved, plan.landing_xy is not landing), False
            if plan.landing_xy is not landing and k < plan.n_lift - 1:
                self._estep_landing_pending = True
        else:
            moved, landed, op = False, False, None
        if ready is not None and ready.gait_op != op:
            ready = None  # the same decision from the same state: never, but then the gait's part is done here
        if op == "move":  # the footstep and the plan's ZMP in one (the ZMP the moved feet give would be overwritten)
            self._estep_landing_pending = False
            if ready is None or ready.patch is None or not self.gait.apply(ready.patch):
                zmp = plan.zmp(k) if ready is None else ready.zmp
                self.gait.move_footsteps({1: tuple(plan.landing_xy.tolist())}, landed=landed, zmp_world=zmp)
        elif op == "zmp":
            if ready is None or not self.gait.apply(ready.patch):
                self.gait.set_zmp(plan.zmp(k) if ready is None else ready.zmp)
        if moved or k == plan.touchdown_k:
            self._update_record(plan, landed=k >= plan.touchdown_k)
        if bal is not None and k < plan.touchdown_k:  # the COG plan follows the measured COG until the foot is down
            self.preview.reset(bal.cog_world[:2], bal.cog_vel_world[:2])

    def _step_again(self, ctx: TickContext, plan: EmergencyStepPlan, k: int) -> bool:
        """A step from a walk (the catch): once the foot is down and the weight shared (RESTEP_AFTER_S), a capture
        point still outside the new support polygon calls for another step, from where the feet are (at most
        EMERGENCY_STEPS_IN_A_ROW). The standing emergency step stays one step (its [MLC] experiments' verdicts)."""
        bal = ctx.last_ports.balance
        if bal is None or not self._estep_from_walk or k < plan.touchdown_k + round(RESTEP_AFTER_S / self.dt_s) \
                or ctx.last_ports.landing or self._estep_in_a_row >= EMERGENCY_STEPS_IN_A_ROW:
            return False
        support = self._support
        if support is None or support[0] is not plan:
            support = self._support = (plan, SupportRegion(plan.support_polygon_after()))
        cx, cy = bal.cp_world_xy.tolist()
        if support[1].outside_m(cx, cy) <= self.params.emergency_step_cp_margin_m:
            return False
        rows = ctx.estimate.wrenches_ext.tolist()
        fz_r, fz_l = rows[FEET[0]][2], rows[FEET[1]][2]
        if fz_r + fz_l < EMERGENCY_STEP_MIN_LOAD_RATIO * self.total_mass * GRAVITY_M_S2:
            return False
        # the leg whose landing leaves the capture point predicted at its touchdown least outside the feet
        g = self.last_gait
        rfoot = Footstep.from_T("rleg", _homogeneous(g.p_rsole_world, g.R_rsole_world))
        lfoot = Footstep.from_T("lleg", _homogeneous(g.p_lsole_world, g.R_lsole_world))
        again = min((self._plan_emergency_step(bal, rfoot, lfoot, leg) for leg in (plan.stance.leg, plan.swing.leg)),
                    key=lambda c: SupportRegion(c.support_polygon_after()).outside_m(*c.cp_touchdown_xy.tolist()))
        self._update_record(plan, landed=True)
        walking_stop = self._walking_stop_requested
        self.gait.abort()
        self._begin_emergency_step(ctx, bal, again)
        self._walking_stop_requested = walking_stop
        return True

    def _touched_down(self, ctx: TickContext, plan: EmergencyStepPlan, k: int) -> bool:
        """The swing foot, in the air before, carries TOUCHDOWN_LOAD_RATIO of the weight late in its swing: it has
        touched the ground early. (A foot that never left the ground is not landing: it is dragged.)"""
        fz = float(ctx.estimate.wrenches_ext[FEET[0 if plan.swing.leg == "rleg" else 1]][2])
        if k == plan.n_lift:
            self._estep_lifted = False
        if fz < SWING_FOOT_LOADED_N:
            self._estep_lifted = True
            return False
        late = k - plan.n_lift >= TOUCHDOWN_SWING_SHARE * (plan.n_touchdown - plan.n_lift)
        return self._estep_lifted and late and fz > TOUCHDOWN_LOAD_RATIO * self.total_mass * GRAVITY_M_S2

    @staticmethod
    def _measured_sole_xy(ctx: TickContext, plan: EmergencyStepPlan) -> tuple[float, float]:
        """Where the swing sole is [m]: the stance sole where the plan has it plus the measured kinematics from it to
        the swing sole (encoders and the KalmanFilter attitude)."""
        pos = ctx.estimate.sensor_pos_from_base.tolist()
        i_sw, i_st = (FEET[0], FEET[1]) if plan.swing.leg == "rleg" else (FEET[1], FEET[0])
        return (plan.stance.x + pos[i_sw][0] - pos[i_st][0], plan.stance.y + pos[i_sw][1] - pos[i_st][1])

    def _lower_to_walking_height(self, base_z_m: float, walking: bool, dt_s: float) -> float:
        """BODY's lowering [m] this tick: while walking, toward how far the operated waist is above the walking
        height; standing, back to zero (rate-limited both ways)."""
        target = max(0.0, base_z_m - self._walk_base_z_m - WALK_HEIGHT_SLACK_M) if walking else 0.0
        step = WALK_HEIGHT_RATE_M_S * dt_s
        low = self._walk_lowering_m
        self._walk_lowering_m = low = min(low + step, target) if target > low else max(low - step, target)
        return low

    def _lower_base(self, dt_s: float) -> float:
        """BODY's lowering [m] this tick: toward emergency_step_base_lowering_m while an emergency step is taken,
        back to zero once the robot stands (rate-limited, both ways)."""
        target = self.params.emergency_step_base_lowering_m if self._estep is not None else 0.0
        rate = self.params.emergency_step_base_lowering_m / BASE_LOWERING_TIME_S * (1.0 if target else 0.25)
        step = max(rate, 1e-6) * dt_s
        low = self._base_lowering_m
        low = min(low + step, target) if target > low else max(low - step, target)
        self._base_lowering_m = low
        return low

    def _update_record(self, plan: EmergencyStepPlan, landed: bool) -> None:
        """The status record of the step in progress (the last one): its landing and whether it is down."""
        if self._estep_records:
            *rest, last = self._estep_records
            self._estep_records = (*rest, dataclasses.replace(
                last, landing=tuple(plan.landing_xy.tolist()), landed=landed, landed_early=plan.landed_k is not None))

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
            levelling_s = 0.0 if tilt is None or tilt.angle0_rad <= TIPPED_MIN_TILT_RAD else \
                MIN_JERK_PEAK_RATIO * tilt.angle0_rad / TIPPED_LEVELLING_RATE_RAD_S
            landing_s = self.gait.stop_from_rest(self._rest_zmp_xy(gait if tilt is None else None),
                                                 swing_foot_loaded=tilt is not None,
                                                 min_landing_time_s=max(0.8, levelling_s))
            if tilt is not None and landing_s > 0.0:
                self._tilt = self._tipped(ctx, gait, landing_s)

    def _tipped(self, ctx: TickContext, gait: GaitState | None, duration_s: float) -> TiltAnchor | None:
        """The held walk's robot resting on its swing foot as well (it tipped onto it): the plan as it sees it,
        levelling over `duration_s`; None when the plan is not on one foot or the swing foot carries nothing."""
        if gait is None or gait.support == "both" or not self.gait.walking:
            return None
        swing = FEET[0] if gait.support == "lleg" else FEET[1]
        if not float(ctx.estimate.wrenches_ext[swing][2]) > SWING_FOOT_LOADED_N:
            return None
        p_support = gait.p_rsole_world if gait.support == "rleg" else gait.p_lsole_world
        return TiltAnchor(rpy_to_matrix(gait.base_rpy_rad), rpy_to_matrix(ctx.estimate.base_rpy_rad), p_support,
                          duration_s)

    @staticmethod
    def _tilted(gait: GaitState, t: TiltAnchor) -> tuple[GaitState, np.ndarray, np.ndarray]:
        """The gait, BODY position and rpy as the robot tipped by `t` sees them."""
        R_body = t.rotation(rpy_to_matrix(gait.base_rpy_rad))
        out = dataclasses.replace(
            gait, p_rsole_world=t.point(gait.p_rsole_world), R_rsole_world=t.rotation(gait.R_rsole_world),
            p_lsole_world=t.point(gait.p_lsole_world), R_lsole_world=t.rotation(gait.R_lsole_world),
            zmp_world=t.point(gait.zmp_world), cog_world=t.point(gait.cog_world),
            cog_vel_world=t.velocity(gait.cog_world, gait.cog_vel_world), cog_pc_world=t.point(gait.cog_pc_world),
            base_pos_world=t.point(gait.base_pos_world), base_rpy_rad=matrix_to_rpy(R_body))
        return out, out.base_pos_world, out.base_rpy_rad

    def _hold(self) -> Reference:
        """A tick under the hard e-stop: the plan does not advance, and the last output is repeated with the
        COG at rest. A walk is cut to a stop that starts from rest where the robot is frozen (the swing
        foot goes down, the ZMP comes to the feet's middle), played after the release."""
        if not self._holding:
            self._holding = True
            self._disarm_walk_point()
            self._walk_point = "ignored: the hard e-stop holds"
            self._estep = None  # the stop from rest replaces an emergency step too
            if self.gait.walking:
                self._walking_stop_requested = True
                self.gait.stop_from_rest(self._rest_zmp_xy(self._last_out.gait))
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
                                  emergency_step=self._estep is not None, emergency_steps=self._estep_records,
                                  walk_cut=self._walk_cut, walk_height_lowering_m=round(self._walk_lowering_m, 4))

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


    def _rest_zmp_xy(self, gait: GaitState | None) -> tuple[float, float]:
        """Where the ZMP of the robot frozen now is once at rest: under the planned COG, kept REST_ZMP_MARGIN_M
        inside the support sole when on one foot."""
        x, y = self.preview.x[0].tolist()
        if gait is None or gait.support == "both":
            return x, y
        right = gait.support == "rleg"
        p, R = (gait.p_rsole_world, gait.R_rsole_world) if right else (gait.p_lsole_world, gait.R_lsole_world)
        sole = HRP2_RIGHT_SOLE if right else HRP2_LEFT_SOLE
        c, s_ = float(R[0, 0]), float(R[1, 0])
        n = math.hypot(c, s_)
        c, s_ = c / n, s_ / n
        dx, dy = x - float(p[0]), y - float(p[1])
        u, v = c * dx + s_ * dy, -s_ * dx + c * dy  # in the sole frame
        m = REST_ZMP_MARGIN_M
        u = min(max(u, -sole.rear_m + m), sole.front_m - m)
        v = min(max(v, -sole.right_m + m), sole.left_m - m)
        return float(p[0]) + c * u - s_ * v, float(p[1]) + s_ * u + c * v


def _homogeneous(p: np.ndarray, R: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T
